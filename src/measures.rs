//! Measures of a mouth run, computed from every output frame (issue: reproduce the paper):
//! the lip gap along the mouth width, the open fraction of the width, where the opening
//! starts, the number of broken saliva elements, and the left/right asymmetry.
//!
//! The lips are sampled at "saliva columns": for each position `x` along the mouth width, a
//! node on the inner surface of the upper lip and the node facing it on the lower lip, across
//! the saliva layer. The gap at a column is their current distance minus their reference
//! distance (the saliva layer's thickness), so a closed mouth has gap 0.

/// Gap above which a column of the lips counts as open (m): 1 mm, about twice the saliva
/// layer's thickness and well below a visible opening (the paper's mouth opens by ~10 mm).
pub const OPEN_THRESHOLD: f64 = 1.0e-3;

/// The columns along the mouth width, sorted by `x` (m).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LipColumns {
    pub x: Vec<f64>,
    pub upper: Vec<u32>,
    pub lower: Vec<u32>,
    /// The x of the mouth's centre line (m), for left/right measures.
    pub center: f64,
}

/// Lip gap at every column (m): current upper-lower distance minus the reference distance.
pub fn lip_gap(reference: &[[f64; 3]], u: &[[f64; 3]], cols: &LipColumns) -> Vec<f64> {
    let dist =
        |a: [f64; 3], b: [f64; 3]| crate::linalg::norm(&[a[0] - b[0], a[1] - b[1], a[2] - b[2]]);
    cols.upper
        .iter()
        .zip(&cols.lower)
        .map(|(&p, &q)| {
            let (p, q) = (p as usize, q as usize);
            let x = |n: usize| {
                [
                    reference[n][0] + u[n][0],
                    reference[n][1] + u[n][1],
                    reference[n][2] + u[n][2],
                ]
            };
            dist(x(p), x(q)) - dist(reference[p], reference[q])
        })
        .collect()
}

/// Fraction of the mouth width (measured between the first and last column, each column
/// weighted by the width it represents) where the gap exceeds `threshold` (m).
pub fn open_fraction(cols: &LipColumns, gap: &[f64], threshold: f64) -> f64 {
    let n = cols.x.len();
    if n < 2 {
        return if gap.first().is_some_and(|g| *g > threshold) {
            1.0
        } else {
            0.0
        };
    }
    let width = cols.x[n - 1] - cols.x[0];
    let mut open = 0.0;
    for i in 0..n {
        let lo = if i == 0 {
            cols.x[0]
        } else {
            0.5 * (cols.x[i - 1] + cols.x[i])
        };
        let hi = if i + 1 == n {
            cols.x[n - 1]
        } else {
            0.5 * (cols.x[i] + cols.x[i + 1])
        };
        if gap[i] > threshold {
            open += hi - lo;
        }
    }
    open / width
}

/// Left/right asymmetry of the opening: `(mean gap at x > center - mean gap at x < center) /
/// mean gap`. In the mouth model `+x` is the subject's left, so a positive value means the
/// mouth is open wider on the subject's left. 0 for a symmetric opening and for a closed mouth.
pub fn asymmetry(cols: &LipColumns, gap: &[f64]) -> f64 {
    let (mut l, mut nl, mut r, mut nr) = (0.0, 0, 0.0, 0);
    for (x, g) in cols.x.iter().zip(gap) {
        if *x < cols.center {
            l += g;
            nl += 1;
        } else if *x > cols.center {
            r += g;
            nr += 1;
        }
    }
    let (ml, mr) = (l / nl.max(1) as f64, r / nr.max(1) as f64);
    let mean = 0.5 * (ml + mr);
    if mean.abs() < 1e-12 {
        0.0
    } else {
        (mr - ml) / mean
    }
}

/// The measures of one frame.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrameMeasures {
    pub time: f64,
    pub gap: Vec<f64>,
    pub open_fraction: f64,
    pub broken: usize,
    pub asymmetry: f64,
}

/// The measures of a whole run (`measures.json`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunMeasures {
    pub columns: LipColumns,
    /// Gap above which a column counts as open (m).
    pub open_threshold: f64,
    pub frames: Vec<FrameMeasures>,
    /// Time and x of the first column to open, if any.
    pub first_opening: Option<(f64, f64)>,
}

impl RunMeasures {
    pub fn new(columns: LipColumns, open_threshold: f64) -> Self {
        RunMeasures {
            columns,
            open_threshold,
            frames: Vec::new(),
            first_opening: None,
        }
    }

    /// Adds the measures of a frame.
    pub fn push(&mut self, time: f64, reference: &[[f64; 3]], u: &[[f64; 3]], broken: usize) {
        let gap = lip_gap(reference, u, &self.columns);
        if self.first_opening.is_none() {
            // the widest-open column among those above the threshold
            let best = gap
                .iter()
                .enumerate()
                .filter(|(_, g)| **g > self.open_threshold)
                .max_by(|a, b| a.1.total_cmp(b.1));
            if let Some((i, _)) = best {
                self.first_opening = Some((time, self.columns.x[i]));
            }
        }
        let of = open_fraction(&self.columns, &gap, self.open_threshold);
        let asym = asymmetry(&self.columns, &gap);
        self.frames.push(FrameMeasures {
            time,
            gap,
            open_fraction: of,
            broken,
            asymmetry: asym,
        });
    }

    /// The gap profiles as CSV: a header `time,x=...` then one row per frame (m).
    pub fn gap_csv(&self) -> String {
        let mut s = String::from("time_s");
        for x in &self.columns.x {
            s.push_str(&format!(",x={x:.6}"));
        }
        s.push('\n');
        for f in &self.frames {
            s.push_str(&format!("{}", f.time));
            for g in &f.gap {
                s.push_str(&format!(",{g:e}"));
            }
            s.push('\n');
        }
        s
    }

    /// Time series as CSV: time, open fraction, broken saliva elements, asymmetry, max gap.
    pub fn series_csv(&self) -> String {
        let mut s = String::from("time_s,open_fraction,broken_saliva,asymmetry,max_gap_m\n");
        for f in &self.frames {
            let mg = f.gap.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            s.push_str(&format!(
                "{},{},{},{},{:e}\n",
                f.time, f.open_fraction, f.broken, f.asymmetry, mg
            ));
        }
        s
    }
}

/// Gap growth at which a lip column counts as open for the zip front (m): 0.2 mm, a third
/// of the saliva row's height at the mouth's centre, far below a visible opening.
pub const ZIP_THRESHOLD: f64 = 2.0e-4;
/// Columns farther from the centre than this fraction of the half-width are the corners,
/// not counted by the zip front (the lips are joined there).
pub const CORNER_FRACTION: f64 = 0.9;

/// How the lips part along the mouth: the time each lip column opens (its gap first exceeds
/// the threshold, linear between output frames), with positions as `|x - centre| / w`
/// (`w` half the mouth width between the first and last column).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ZipFront {
    /// Gap growth that counts as open (m).
    pub threshold: f64,
    /// `|x - centre| / w` of every column.
    pub position: Vec<f64>,
    /// Opening time of every column (s); `None`: it never opens.
    pub opening_time: Vec<Option<f64>>,
    /// Columns counted (`position <= CORNER_FRACTION`).
    pub counted: Vec<bool>,
    /// Time and position of the first counted column to open.
    pub first: Option<(f64, f64)>,
    /// When 10 % and 90 % of the counted columns are open.
    pub t10: Option<f64>,
    pub t90: Option<f64>,
    /// Spearman rank correlation of opening time with position, over the counted columns
    /// that open (at least three): 1 when the lips open strictly from the centre outwards.
    pub spearman: Option<f64>,
    /// Counted columns open at the last frame.
    pub final_open: Vec<bool>,
    /// Fraction of the counted columns open at the last frame.
    pub final_open_fraction: f64,
}

impl ZipFront {
    /// The zip front of a run with one opening from the rest at its first frame: the gap
    /// itself is the growth.
    pub fn new(m: &RunMeasures, threshold: f64) -> ZipFront {
        ZipFront::of_frames(&m.columns, &m.frames, None, threshold)
    }

    /// The zip front of one opening among several (a jaw that opens, closes and opens
    /// again): only the frames from `t0` to `t1` (s) count, and a column opens when its gap
    /// has grown by more than `threshold` (m) over its gap at `t0`, so lips that start the
    /// window not quite back at rest are measured from where they are. The baseline is the
    /// last frame at or before `t0` (the first frame if none); the window runs from it to the
    /// last frame at or before `t1`. Times stay the run's (s): subtract `t0` for times
    /// relative to the opening's start. `final_open` and `final_open_fraction` are at the
    /// window's last frame. `between(m, threshold, first frame's time, last frame's time)` is
    /// [`ZipFront::new`] when the first frame's gap is zero.
    pub fn between(m: &RunMeasures, threshold: f64, t0: f64, t1: f64) -> ZipFront {
        // frame times are sums of dt: a key time given in the scenario matches within this
        let eps = 1e-9 * (1.0 + t0.abs().max(t1.abs()));
        let start = m
            .frames
            .iter()
            .rposition(|f| f.time <= t0 + eps)
            .unwrap_or(0);
        let end = m
            .frames
            .iter()
            .rposition(|f| f.time <= t1 + eps)
            .map_or(start, |e| e.max(start) + 1)
            .min(m.frames.len());
        let frames = &m.frames[start..end];
        let baseline = frames.first().map(|f| f.gap.as_slice());
        ZipFront::of_frames(&m.columns, frames, baseline, threshold)
    }

    /// The zip front over `frames`, the growth of each column's gap measured from
    /// `baseline` (none: from zero).
    fn of_frames(
        cols: &LipColumns,
        frames: &[FrameMeasures],
        baseline: Option<&[f64]>,
        threshold: f64,
    ) -> ZipFront {
        let growth = |f: &FrameMeasures, c: usize| f.gap[c] - baseline.map_or(0.0, |b| b[c]);
        let n = cols.x.len();
        let (lo, hi) = (
            cols.x.iter().copied().fold(f64::INFINITY, f64::min),
            cols.x.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        );
        let w = (0.5 * (hi - lo)).max(f64::MIN_POSITIVE);
        let position: Vec<f64> = cols.x.iter().map(|x| (x - cols.center).abs() / w).collect();
        let counted: Vec<bool> = position
            .iter()
            .map(|p| *p <= CORNER_FRACTION + 1e-12)
            .collect();
        let opening_time: Vec<Option<f64>> = (0..n)
            .map(|c| {
                let mut prev: Option<(f64, f64)> = None;
                for f in frames {
                    let g = growth(f, c);
                    if g > threshold {
                        return Some(match prev {
                            Some((t0, g0)) if g > g0 => {
                                t0 + (threshold - g0) / (g - g0) * (f.time - t0)
                            }
                            _ => f.time,
                        });
                    }
                    prev = Some((f.time, g));
                }
                None
            })
            .collect();
        let mut open_times: Vec<f64> = (0..n)
            .filter(|&c| counted[c])
            .filter_map(|c| opening_time[c])
            .collect();
        open_times.sort_by(f64::total_cmp);
        let nc = counted.iter().filter(|c| **c).count();
        let quantile = |q: f64| -> Option<f64> {
            let k = ((q * nc as f64).ceil() as usize).max(1) - 1;
            open_times.get(k).copied()
        };
        let first = (0..n)
            .filter(|&c| counted[c])
            .filter_map(|c| opening_time[c].map(|t| (t, position[c])))
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let pairs: Vec<(f64, f64)> = (0..n)
            .filter(|&c| counted[c])
            .filter_map(|c| opening_time[c].map(|t| (position[c], t)))
            .collect();
        let spearman = (pairs.len() >= 3).then(|| {
            let (a, b): (Vec<f64>, Vec<f64>) = pairs.iter().copied().unzip();
            spearman(&a, &b)
        });
        let last = frames.last();
        let final_open: Vec<bool> = (0..n)
            .map(|c| last.is_some_and(|f| growth(f, c) > threshold))
            .collect();
        let final_open_fraction =
            (0..n).filter(|&c| counted[c] && final_open[c]).count() as f64 / nc.max(1) as f64;
        ZipFront {
            threshold,
            position,
            opening_time,
            counted,
            first,
            t10: quantile(0.1),
            t90: quantile(0.9),
            spearman,
            final_open,
            final_open_fraction,
        }
    }

    /// `t90 - t10` (s), when both exist.
    pub fn spread(&self) -> Option<f64> {
        Some(self.t90? - self.t10?)
    }
}

/// Ranks (1-based, ties averaged).
fn ranks(v: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut r = vec![0.0; v.len()];
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
            j += 1;
        }
        let avg = 0.5 * (i + j) as f64 + 1.0;
        for &k in &idx[i..=j] {
            r[k] = avg;
        }
        i = j + 1;
    }
    r
}

/// Spearman's rank correlation of `a` and `b` (Pearson's on their ranks, ties averaged);
/// 0 when either is constant.
pub fn spearman(a: &[f64], b: &[f64]) -> f64 {
    let (ra, rb) = (ranks(a), ranks(b));
    let n = ra.len() as f64;
    let (ma, mb) = (ra.iter().sum::<f64>() / n, rb.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in ra.iter().zip(&rb) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    if saa == 0.0 || sbb == 0.0 {
        0.0
    } else {
        sab / (saa * sbb).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cols() -> LipColumns {
        LipColumns {
            x: vec![-0.02, -0.01, 0.0, 0.01, 0.02],
            upper: vec![0, 1, 2, 3, 4],
            lower: vec![5, 6, 7, 8, 9],
            center: 0.0,
        }
    }

    fn reference() -> Vec<[f64; 3]> {
        let c = cols();
        let mut r: Vec<[f64; 3]> = c.x.iter().map(|&x| [x, 0.0005, 0.0]).collect();
        r.extend(c.x.iter().map(|&x| [x, -0.0005, 0.0]));
        r
    }

    #[test]
    fn closed_mouth_has_zero_gap_and_no_opening() {
        let r = reference();
        let u = vec![[0.0; 3]; r.len()];
        let g = lip_gap(&r, &u, &cols());
        assert!(g.iter().all(|v| v.abs() < 1e-15));
        assert_eq!(open_fraction(&cols(), &g, 1e-3), 0.0);
        assert_eq!(asymmetry(&cols(), &g), 0.0);
    }

    #[test]
    fn central_opening_and_fraction() {
        let r = reference();
        let mut u = vec![[0.0; 3]; r.len()];
        u[7][1] = -0.004; // lower lip at the centre drops 4 mm
        let g = lip_gap(&r, &u, &cols());
        assert!((g[2] - 0.004).abs() < 1e-15);
        // the centre column represents [-0.005, 0.005] of a 0.04 m width
        assert!((open_fraction(&cols(), &g, 1e-3) - 0.25).abs() < 1e-12);
        let mut m = RunMeasures::new(cols(), 1e-3);
        m.push(0.1, &r, &u, 3);
        assert_eq!(m.first_opening, Some((0.1, 0.0)));
        assert!(m.gap_csv().lines().count() == 2 && m.series_csv().contains("0.1,0.25,3,"));
    }

    #[test]
    fn one_sided_opening_is_asymmetric() {
        let r = reference();
        let mut u = vec![[0.0; 3]; r.len()];
        u[8][1] = -0.002;
        u[9][1] = -0.004;
        let g = lip_gap(&r, &u, &cols());
        assert!(asymmetry(&cols(), &g) > 1.0);
    }

    #[test]
    fn spearman_of_monotone_and_reversed_and_tied_data() {
        assert!((spearman(&[1.0, 2.0, 3.0, 4.0], &[10.0, 20.0, 25.0, 100.0]) - 1.0).abs() < 1e-15);
        assert!((spearman(&[1.0, 2.0, 3.0], &[3.0, 2.0, 1.0]) + 1.0).abs() < 1e-15);
        // ties averaged: ranks of b are 1.5, 1.5, 3 -> 0.866...
        let r = spearman(&[1.0, 2.0, 3.0], &[5.0, 5.0, 7.0]);
        assert!((r - 0.75f64.sqrt()).abs() < 1e-12, "{r}");
        assert_eq!(spearman(&[1.0, 2.0], &[4.0, 4.0]), 0.0);
    }

    #[test]
    fn zip_front_from_a_centre_first_opening() {
        // nine columns across [-0.02, 0.02]; column c opens at t = 0.1 + 0.01 |c - 4|, the
        // gap growing linearly by 1 mm per 0.01 s after that; the corners (|x| = w) are not counted
        let x: Vec<f64> = (0..9).map(|c| 0.005 * (c as f64 - 4.0)).collect();
        let cols = LipColumns {
            x: x.clone(),
            upper: (0..9).collect(),
            lower: (9..18).collect(),
            center: 0.0,
        };
        let mut m = RunMeasures::new(cols, 1e-3);
        for f in 0..30 {
            let t = 0.01 * f as f64;
            let gap: Vec<f64> = (0..9)
                .map(|c| {
                    let t0 = 0.1 + 0.01 * (c as f64 - 4.0).abs();
                    (0.1 * (t - t0)).max(0.0)
                })
                .collect();
            m.frames.push(FrameMeasures {
                time: t,
                gap,
                open_fraction: 0.0,
                broken: 0,
                asymmetry: 0.0,
            });
        }
        let z = ZipFront::new(&m, 2e-4);
        assert_eq!(z.counted.iter().filter(|c| **c).count(), 7);
        // the centre crosses 0.2 mm 2 ms after it starts moving
        assert!((z.opening_time[4].unwrap() - 0.102).abs() < 1e-12);
        assert_eq!(z.first.map(|f| f.1), Some(0.0));
        assert!((z.spearman.unwrap() - 1.0).abs() < 1e-12);
        // 7 counted columns: 10 % -> the 1st to open, 90 % -> the 7th
        assert!((z.t10.unwrap() - 0.102).abs() < 1e-12);
        assert!((z.t90.unwrap() - 0.132).abs() < 1e-12);
        assert!((z.spread().unwrap() - 0.03).abs() < 1e-12);
        assert_eq!(z.final_open_fraction, 1.0);
    }
    #[test]
    fn zip_front_between_measures_each_of_two_openings() {
        // nine columns across [-0.02, 0.02]. First opening: column c starts at
        // 0.1 + 0.01 |c - 4| s and opens at 0.1 m/s; at 0.3 s every gap drops to a residual
        // 0.5 mm (above the threshold: the lips are not back at rest) and holds. Second
        // opening: column c starts at 0.45 + 0.01 |c - 4| s, the gap growing by 0.2 m/s over
        // the residual.
        let x: Vec<f64> = (0..9).map(|c| 0.005 * (c as f64 - 4.0)).collect();
        let cols = LipColumns {
            x,
            upper: (0..9).collect(),
            lower: (9..18).collect(),
            center: 0.0,
        };
        let mut m = RunMeasures::new(cols, 1e-3);
        let residual = 5e-4;
        for f in 0..=70 {
            let t = 0.01 * f as f64;
            let gap: Vec<f64> = (0..9)
                .map(|c| {
                    let d = (c as f64 - 4.0).abs();
                    if t < 0.3 - 1e-9 {
                        (0.1 * (t - (0.1 + 0.01 * d))).max(0.0)
                    } else {
                        residual + (0.2 * (t - (0.45 + 0.01 * d))).max(0.0)
                    }
                })
                .collect();
            m.frames.push(FrameMeasures {
                time: t,
                gap,
                open_fraction: 0.0,
                broken: 0,
                asymmetry: 0.0,
            });
        }
        // over the whole run the second opening is invisible: every column is open already
        let whole = ZipFront::new(&m, 2e-4);
        assert!((whole.t90.unwrap() - 0.132).abs() < 1e-12);
        // the first window is the first opening as `new` measures it
        let first = ZipFront::between(&m, 2e-4, 0.0, 0.29);
        assert_eq!(first.first.map(|f| f.1), Some(0.0));
        assert!((first.first.unwrap().0 - 0.102).abs() < 1e-12);
        assert!((first.spread().unwrap() - 0.03).abs() < 1e-12);
        // the second window: growth over the gap at 0.4 s
        let second = ZipFront::between(&m, 2e-4, 0.4, 0.7);
        assert_eq!(second.first.map(|f| f.1), Some(0.0));
        assert!((second.first.unwrap().0 - 0.451).abs() < 1e-12);
        assert!((second.t10.unwrap() - 0.451).abs() < 1e-12);
        assert!((second.t90.unwrap() - 0.481).abs() < 1e-12);
        assert!((second.spearman.unwrap() - 1.0).abs() < 1e-12);
        assert_eq!(second.final_open_fraction, 1.0);
        // a window that ends before the second opening: nothing opens, nothing is open
        let closed = ZipFront::between(&m, 2e-4, 0.3, 0.44);
        assert!(closed.first.is_none() && closed.opening_time.iter().all(|t| t.is_none()));
        assert_eq!(closed.final_open_fraction, 0.0);
        // from the first frame (gap 0) to the last, `between` is `new`
        assert_eq!(ZipFront::between(&m, 2e-4, 0.0, 0.7), whole);
    }
}
