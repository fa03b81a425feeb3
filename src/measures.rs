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
#[derive(Clone, Debug, serde::Serialize)]
pub struct FrameMeasures {
    pub time: f64,
    pub gap: Vec<f64>,
    pub open_fraction: f64,
    pub broken: usize,
    pub asymmetry: f64,
}

/// The measures of a whole run.
#[derive(Clone, Debug, serde::Serialize)]
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
}
