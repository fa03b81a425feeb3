//! The paper's claims as numbers, measured from run outputs (the `paper` command and
//! `verification/paper_claims.rs` both use this).
//!
//! A lip column is open once its gap has grown by [`crate::measures::ZIP_THRESHOLD`]
//! (0.2 mm); positions are `|x - centre| / w` with `w` half the mouth width; the corner-most
//! columns (beyond [`crate::measures::CORNER_FRACTION`] = 0.9 w) are not counted
//! ([`crate::measures::ZipFront`]).
//!
//! | id | figure | claim (the paper's words in brackets) | holds when |
//! |---|---|---|---|
//! | C1 | 4, left | without stickiness the whole lip parts at once ("the entire lip moves away ... in one go") | 10 % to 90 % of the columns open within 0.04 s (one row of Fig. 4) |
//! | C2 | 4, right | with stickiness the lips part at the centre first ("begin to part in the centre") | the first column to open lies at `<= 0.2 w` |
//! | C3 | 4, right | the gap widens over time ("opening up over time", rows 0.04 s apart) | 10 % to 90 % of the columns open takes at least 0.08 s (two rows) |
//! | C4 | 4, right | the opening runs from the centre to the corners (zippering) | Spearman rank correlation of opening time with position `>= 0.6` |
//! | C5 | 7, right | at a slight opening the lips stay joined towards the corners | at the end: 20-80 % of the columns open, every column within 0.2 w open, none between 0.7 w and 0.9 w |
//! | C6 | 7, left | without stickiness a slight opening opens the lips to the corners | at the end at least 90 % of the columns open |
//! | C7 | 8 | a wide opening reaches the same equilibrium with and without stickiness | final displacements differ by at most 2 % of the largest (max over nodes of `|u_sticky - u_dry|` against max `|u_dry|`) |

use crate::measures::ZipFront;

/// One claim as measured.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Claim {
    pub id: &'static str,
    pub figure: &'static str,
    /// What must hold, in words with the threshold.
    pub criterion: &'static str,
    /// The measured number(s), in words.
    pub measured: String,
    pub holds: bool,
}

fn fmt_opt(v: Option<f64>, unit: &str, scale: f64) -> String {
    match v {
        Some(v) => format!("{:.3}{unit}", v * scale),
        None => "none".into(),
    }
}

/// C1: the dry wide opening parts the lips at once.
pub fn c1(dry: &ZipFront) -> Claim {
    let s = dry.spread();
    Claim {
        id: "C1",
        figure: "4 (without stickiness)",
        criterion: "10 % to 90 % of the columns open within 0.04 s",
        measured: format!(
            "10 % at {}, 90 % at {}: {}",
            fmt_opt(dry.t10, " s", 1.0),
            fmt_opt(dry.t90, " s", 1.0),
            fmt_opt(s, " s", 1.0)
        ),
        holds: s.is_some_and(|s| s <= 0.04),
    }
}

/// C2: with stickiness the first column to open is at the centre.
pub fn c2(sticky: &ZipFront) -> Claim {
    Claim {
        id: "C2",
        figure: "4 (with stickiness)",
        criterion: "the first column to open lies within 0.2 w of the centre",
        measured: match sticky.first {
            Some((t, p)) => format!("first opening at t = {t:.3} s, |x| = {p:.3} w"),
            None => "no column opens".into(),
        },
        holds: sticky.first.is_some_and(|(_, p)| p <= 0.2 + 1e-12),
    }
}

/// C3: with stickiness the opening takes at least two rows of Fig. 4.
pub fn c3(sticky: &ZipFront) -> Claim {
    let s = sticky.spread();
    Claim {
        id: "C3",
        figure: "4 (with stickiness)",
        criterion: "10 % to 90 % of the columns open takes at least 0.08 s",
        measured: format!(
            "10 % at {}, 90 % at {}: {}",
            fmt_opt(sticky.t10, " s", 1.0),
            fmt_opt(sticky.t90, " s", 1.0),
            fmt_opt(s, " s", 1.0)
        ),
        holds: s.is_some_and(|s| s >= 0.08),
    }
}

/// C4: with stickiness the opening time rises towards the corners.
pub fn c4(sticky: &ZipFront) -> Claim {
    Claim {
        id: "C4",
        figure: "4 (with stickiness)",
        criterion: "Spearman rank correlation of opening time with |x| at least 0.6",
        measured: fmt_opt(sticky.spearman, "", 1.0),
        holds: sticky.spearman.is_some_and(|r| r >= 0.6),
    }
}

/// C5: with stickiness a slight opening stays joined towards the corners.
pub fn c5(sticky_slight: &ZipFront) -> Claim {
    let z = sticky_slight;
    let n = z.position.len();
    let centre_open = (0..n)
        .filter(|&c| z.position[c] <= 0.2 + 1e-12)
        .all(|c| z.final_open[c]);
    let corners_closed = (0..n)
        .filter(|&c| z.position[c] >= 0.7 - 1e-12 && z.counted[c])
        .all(|c| !z.final_open[c]);
    let f = z.final_open_fraction;
    Claim {
        id: "C5",
        figure: "7 (with stickiness)",
        criterion: "at equilibrium 20-80 % of the columns open, all within 0.2 w open, none within 0.7-0.9 w",
        measured: format!(
            "open fraction {f:.3}; centre (<= 0.2 w) {}; 0.7-0.9 w {}",
            if centre_open { "all open" } else { "not all open" },
            if corners_closed { "all joined" } else { "some open" }
        ),
        holds: (0.2..=0.8).contains(&f) && centre_open && corners_closed,
    }
}

/// C6: without stickiness a slight opening opens the lips to the corners.
pub fn c6(dry_slight: &ZipFront) -> Claim {
    let f = dry_slight.final_open_fraction;
    Claim {
        id: "C6",
        figure: "7 (without stickiness)",
        criterion: "at equilibrium at least 90 % of the columns open",
        measured: format!("open fraction {f:.3}"),
        holds: f >= 0.9,
    }
}

/// The largest node displacement difference and the largest displacement (m).
pub fn max_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> (f64, f64) {
    let n = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let mut d: f64 = 0.0;
    let mut m: f64 = 0.0;
    for (x, y) in a.iter().zip(b) {
        d = d.max(n([x[0] - y[0], x[1] - y[1], x[2] - y[2]]));
        m = m.max(n(*x));
    }
    (d, m)
}

/// C7: the wide opening's final shapes agree with and without stickiness.
pub fn c7(u_dry: &[[f64; 3]], u_sticky: &[[f64; 3]]) -> Claim {
    let (d, m) = max_difference(u_dry, u_sticky);
    let r = if m > 0.0 { d / m } else { f64::INFINITY };
    Claim {
        id: "C7",
        figure: "8",
        criterion: "final displacements differ by at most 2 % of the largest",
        measured: format!(
            "max |du| = {:.3e} m = {:.2e} of max |u| = {:.3e} m",
            d, r, m
        ),
        holds: r <= 0.02,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn zip(first: Option<(f64, f64)>, t10: Option<f64>, t90: Option<f64>) -> ZipFront {
        ZipFront {
            threshold: 2e-4,
            position: vec![0.0, 0.5, 0.8, 1.0],
            opening_time: vec![Some(0.1), Some(0.2), None, None],
            counted: vec![true, true, true, false],
            first,
            t10,
            t90,
            spearman: Some(0.7),
            final_open: vec![true, true, false, false],
            final_open_fraction: 2.0 / 3.0,
        }
    }

    #[test]
    fn thresholds_decide_each_claim() {
        assert!(c1(&zip(None, Some(0.1), Some(0.139))).holds);
        assert!(!c1(&zip(None, Some(0.1), Some(0.141))).holds);
        assert!(!c1(&zip(None, Some(0.1), None)).holds);
        assert!(c2(&zip(Some((0.1, 0.2)), None, None)).holds);
        assert!(c2(&zip(Some((0.1, 0.19)), None, None)).holds);
        assert!(!c2(&zip(Some((0.1, 0.25)), None, None)).holds);
        assert!(!c2(&zip(None, None, None)).holds);
        assert!(c3(&zip(None, Some(0.1), Some(0.181))).holds);
        assert!(!c3(&zip(None, Some(0.1), Some(0.179))).holds);
        assert!(c4(&zip(None, None, None)).holds);
        // 2 of 3 counted open, the centre open, the 0.8 w column joined
        assert!(c5(&zip(None, None, None)).holds);
        let mut z = zip(None, None, None);
        z.final_open[2] = true;
        z.final_open_fraction = 1.0;
        assert!(!c5(&z).holds);
        assert!(c6(&z).holds);
        assert!(c7(&[[0.0, -0.01, 0.0]], &[[0.0, -0.0101, 0.0]]).holds);
        assert!(!c7(&[[0.0, -0.01, 0.0]], &[[0.0, -0.0103, 0.0]]).holds);
    }
}
