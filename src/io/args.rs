//! Values given on the command line: counts, vectors and `NAME=VALUE` pairs. Every function
//! refuses what is not a valid value with a message naming the option, and returns only
//! finite numbers (fuzzed by `fuzz/fuzz_targets/cli_values.rs`).

use crate::error::{Error, Location, Result};

/// A count of at least 1 (`what`: "thread", "step"), for `--threads` and `--checkpoint-every`.
pub fn count(text: &str, what: &str) -> std::result::Result<usize, String> {
    match text.parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        Ok(_) => Err(format!("the number of {what}s must be at least 1")),
        Err(e) => Err(format!("`{text}` is not a {what} count: {e}")),
    }
}

/// The most worker threads a run may have: four per CPU the process may use
/// (`std::thread::available_parallelism`). More would only cost time (the results are the
/// same for any count), and a mistyped count would otherwise spawn threads until the
/// machine gives out.
pub fn max_threads() -> usize {
    4 * std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// A thread count: at least 1 and at most [`max_threads`].
pub fn threads(text: &str) -> std::result::Result<usize, String> {
    let n = count(text, "thread")?;
    let max = max_threads();
    if n > max {
        return Err(format!(
            "{n} threads on a machine with {} CPUs: at most {max} (four per CPU)",
            max / 4
        ));
    }
    Ok(n)
}

/// A finite number between `lo` and `hi` (each bound included where `*_inclusive`), for an
/// option whose physical range is known (e.g. `--humidity`, a fraction of 1). `what` names
/// the quantity and its range in the message.
pub fn number_in(
    text: &str,
    (lo, lo_inclusive): (f64, bool),
    (hi, hi_inclusive): (f64, bool),
    what: &str,
) -> std::result::Result<f64, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a number ({what})"))?;
    let above = if lo_inclusive { v >= lo } else { v > lo };
    let below = if hi_inclusive { v <= hi } else { v < hi };
    if v.is_finite() && above && below {
        Ok(v)
    } else {
        Err(format!("`{text}` is out of range: {what}"))
    }
}

/// Three finite numbers `X,Y,Z` for the option `option` (e.g. `--up`).
pub fn vec3(text: &str, option: &str) -> Result<[f64; 3]> {
    let bad = |m: String| Error::input("command line", Location::Field(option.into()), m);
    let v: Vec<f64> = text
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| bad(format!("`{text}` is not X,Y,Z")))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([x, y, z]),
        _ => Err(bad(format!("`{text}` must be three finite numbers X,Y,Z"))),
    }
}

/// `NAME=VALUE` with a finite VALUE for the option `option`; the name is what lies before the
/// last `=` and may not be empty. `expected` says the form in messages (`PATH.vtu=WEIGHT`).
pub fn name_value<'a>(spec: &'a str, option: &str, expected: &str) -> Result<(&'a str, f64)> {
    let bad = |m: String| Error::input(option, Location::None, m);
    let (name, value) = spec
        .rsplit_once('=')
        .filter(|(n, _)| !n.is_empty())
        .ok_or_else(|| bad(format!("`{spec}`: expected {expected}")))?;
    match value.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok((name, v)),
        _ => Err(bad(format!(
            "`{value}` is not a finite number ({expected})"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thread_counts_are_bounded_by_the_cpus() {
        let max = max_threads();
        assert!(max >= 4 && max % 4 == 0);
        assert_eq!(threads("1"), Ok(1));
        assert_eq!(threads(&max.to_string()), Ok(max));
        let e = threads(&(max + 1).to_string()).unwrap_err();
        assert!(e.contains("four per CPU"), "{e}");
        assert!(threads("100000000").is_err());
        assert!(threads("0").is_err());
    }

    #[test]
    fn numbers_in_a_range() {
        let frac = |t: &str| number_in(t, (0.0, true), (1.0, true), "a fraction, 0 to 1");
        assert_eq!(frac("0"), Ok(0.0));
        assert_eq!(frac(" 1 "), Ok(1.0));
        assert_eq!(frac("0.5"), Ok(0.5));
        for bad in ["-0.01", "1.0001", "nan", "inf", "-inf", "x", ""] {
            let e = frac(bad).unwrap_err();
            assert!(e.contains("0 to 1"), "{bad}: {e}");
        }
        // an excluded upper bound: the bound itself refused, just below it taken
        let below_one = |t: &str| number_in(t, (0.0, true), (1.0, false), "below 1");
        assert!(below_one("1").is_err());
        assert!(below_one("1.5").is_err());
        assert_eq!(below_one("0.999"), Ok(0.999));
        assert_eq!(below_one("0"), Ok(0.0));
        // an excluded lower bound
        let kelvin = |t: &str| number_in(t, (-273.15, false), (1e3, true), "above -273.15 C");
        assert!(kelvin("-273.15").is_err());
        assert_eq!(kelvin("-273.1"), Ok(-273.1));
        assert!(kelvin("1000.5").is_err());
    }

    #[test]
    fn values_are_checked() {
        assert_eq!(count("4", "thread"), Ok(4));
        assert!(count("0", "thread").unwrap_err().contains("at least 1"));
        assert!(count("-1", "step")
            .unwrap_err()
            .contains("not a step count"));
        assert_eq!(vec3(" 0, 1 ,-2.5", "--up").unwrap(), [0.0, 1.0, -2.5]);
        for bad in ["1,2", "1,2,3,4", "1,nan,2", "inf,0,0", "a,b,c", ""] {
            let e = vec3(bad, "--up").unwrap_err().to_string();
            assert!(e.contains("--up"), "{bad}: {e}");
        }
        assert_eq!(
            name_value("a=b.vtu=0.5", "--shape", "PATH=W").unwrap(),
            ("a=b.vtu", 0.5)
        );
        for bad in ["x.vtu", "=1", "x=nan", "x=-inf", "x="] {
            let e = name_value(bad, "--shape", "PATH=W")
                .unwrap_err()
                .to_string();
            assert!(e.contains("--shape"), "{bad}: {e}");
        }
    }
}
