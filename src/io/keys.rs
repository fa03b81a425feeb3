//! Keyframes from the files animation packages export: `(time, value)` pairs for a keyed
//! curve ([`crate::boundary::Keyframes`]).
//!
//! * **CSV** (or any text table): one key per line, time and value separated by a comma,
//!   semicolon, tab or spaces; blank lines and lines starting with `#` are skipped, and so is
//!   a first line none of whose columns is a number (a header such as `time,value` or
//!   `frame,jaw`); a first line with a number in it is data, and refused if malformed.
//! * **JSON**: `[[t, v], ...]`, `[{"time": t, "value": v}, ...]` (also `"frame"` for `"time"`)
//!   or `{"time": [...], "value": [...]}`.
//!
//! With `fps`, the first column counts frames of an animation at that rate (Blender's and
//! Maya's frame numbers), converted to seconds as `frame / fps`. Errors name the file and
//! the line (CSV) or the key (JSON).

use crate::error::{Error, Location, Result};

/// The frame rates `keys_fps` may take (frames per second): from one frame in 1000 s to a
/// million a second. Outside it a key's time would be absurd (at 1e-300 fps frame 1 lies
/// 1e300 s away, and the curve never moves).
pub const FPS_RANGE: (f64, f64) = (1e-3, 1e6);

/// Seconds per key time unit: 1, or `1 / fps` where the times are frame numbers; an error
/// naming `field` in `name` for a rate outside [`FPS_RANGE`].
pub fn time_scale(fps: Option<f64>, name: &str, field: &str) -> Result<f64> {
    let (lo, hi) = FPS_RANGE;
    match fps {
        None => Ok(1.0),
        Some(f) if f.is_finite() && (lo..=hi).contains(&f) => Ok(1.0 / f),
        Some(f) => Err(Error::input(
            name,
            Location::Field(field.into()),
            format!("must be a frame rate from {lo:e} to {hi:e} per second, got {f:e}"),
        )),
    }
}

/// Parses the text of a keys file (`name` for messages); times in seconds.
pub fn parse_keys(text: &str, name: &str, fps: Option<f64>) -> Result<Vec<(f64, f64)>> {
    let scale = time_scale(fps, name, "keys_fps")?;
    // a byte order mark (some spreadsheets and editors write one) is not part of the data
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let first = text.trim_start().chars().next();
    let keys = if matches!(first, Some('[') | Some('{')) {
        parse_json(text, name)?
    } else {
        parse_table(text, name)?
    };
    if keys.is_empty() {
        return Err(Error::input(name, Location::None, "holds no keys"));
    }
    let keys: Vec<(f64, f64)> = keys.into_iter().map(|(t, v)| (t * scale, v)).collect();
    if let Some((i, (t, _))) = keys.iter().enumerate().find(|(_, (t, _))| !t.is_finite()) {
        return Err(Error::input(
            name,
            Location::None,
            format!(
                "key {i}: its time is {t} s at keys_fps = {}: not a finite number of seconds",
                fps.unwrap_or(1.0)
            ),
        ));
    }
    Ok(keys)
}

/// The largest keys file read (64 MiB, about four million keys of CSV): the keys are held
/// in memory, 16 bytes each, and each curve evaluation searches them.
pub const MAX_KEYS_FILE_BYTES: u64 = 64 << 20;

/// Reads a keys file: a regular file (a FIFO or a device would block or never end) of at
/// most [`MAX_KEYS_FILE_BYTES`].
pub fn read_keys(path: &std::path::Path, fps: Option<f64>) -> Result<Vec<(f64, f64)>> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        return Err(Error::input(
            path.display().to_string(),
            Location::None,
            "is not a regular file (a keys file is a CSV or JSON file)",
        ));
    }
    if meta.len() > MAX_KEYS_FILE_BYTES {
        return Err(Error::input(
            path.display().to_string(),
            Location::None,
            format!(
                "is {} bytes; a keys file may have at most {MAX_KEYS_FILE_BYTES} (64 MiB, about \
                 four million keys): resample the curve",
                meta.len()
            ),
        ));
    }
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_keys(&text, &path.display().to_string(), fps)
}

fn parse_table(text: &str, name: &str) -> Result<Vec<(f64, f64)>> {
    let mut keys = Vec::new();
    let mut seen_data = false;
    for (i, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let cols: Vec<&str> = l
            .split([',', ';', '\t', ' '])
            .filter(|s| !s.is_empty())
            .collect();
        let nums: Option<Vec<f64>> = cols.iter().map(|c| c.parse::<f64>().ok()).collect();
        match nums {
            Some(n) if n.len() == 2 => {
                if !(n[0].is_finite() && n[1].is_finite()) {
                    return Err(Error::input(
                        name,
                        Location::Line(i + 1),
                        format!("`{l}`: time and value must be finite"),
                    ));
                }
                keys.push((n[0], n[1]));
                seen_data = true;
            }
            // a header: the first line, and none of its columns a number (`time,value`,
            // `frame,jaw`); a first line with numbers in it is a malformed data row
            _ if !seen_data
                && keys.is_empty()
                && cols.iter().all(|c| c.parse::<f64>().is_err()) =>
            {
                seen_data = true;
            }
            _ => {
                return Err(Error::input(
                    name,
                    Location::Line(i + 1),
                    format!("`{l}` is not a time and a value"),
                ))
            }
        }
    }
    Ok(keys)
}

fn parse_json(text: &str, name: &str) -> Result<Vec<(f64, f64)>> {
    let v: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| Error::input(name, Location::Line(e.line()), e.to_string()))?;
    let bad = |k: usize, what: &str| {
        Error::input(name, Location::Field(format!("key {k}")), what.to_string())
    };
    let num = |x: &serde_json::Value| x.as_f64().filter(|f| f.is_finite());
    match &v {
        serde_json::Value::Array(items) => items
            .iter()
            .enumerate()
            .map(|(k, it)| match it {
                serde_json::Value::Array(p) if p.len() == 2 => match (num(&p[0]), num(&p[1])) {
                    (Some(t), Some(v)) => Ok((t, v)),
                    _ => Err(bad(k, "time and value must be finite numbers")),
                },
                serde_json::Value::Object(o) => {
                    let t = o.get("time").or_else(|| o.get("frame")).and_then(num);
                    match (t, o.get("value").and_then(num)) {
                        (Some(t), Some(v)) => Ok((t, v)),
                        _ => Err(bad(k, "needs finite `time` (or `frame`) and `value`")),
                    }
                }
                _ => Err(bad(k, "is neither [time, value] nor {\"time\", \"value\"}")),
            })
            .collect(),
        serde_json::Value::Object(o) => {
            let col = |k: &str| o.get(k).and_then(|c| c.as_array());
            let (Some(ts), Some(vs)) = (col("time").or_else(|| col("frame")), col("value")) else {
                return Err(Error::input(
                    name,
                    Location::None,
                    "an object of keys needs the arrays `time` (or `frame`) and `value`",
                ));
            };
            if ts.len() != vs.len() {
                return Err(Error::input(
                    name,
                    Location::Field("value".into()),
                    format!("{} values for {} times", vs.len(), ts.len()),
                ));
            }
            ts.iter()
                .zip(vs)
                .enumerate()
                .map(|(k, (t, v))| match (num(t), num(v)) {
                    (Some(t), Some(v)) => Ok((t, v)),
                    _ => Err(bad(k, "time and value must be finite numbers")),
                })
                .collect()
        }
        _ => Err(Error::input(
            name,
            Location::None,
            "keys must be an array or an object",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A keys file over the size limit is refused from its size, before it is read (a sparse
    /// file: nothing is written).
    #[test]
    fn a_keys_file_too_large_is_refused_unread() {
        let p =
            std::env::temp_dir().join(format!("sticky_lips_big_keys_{}.csv", std::process::id()));
        let f = std::fs::File::create(&p).unwrap();
        f.set_len(MAX_KEYS_FILE_BYTES + 1).unwrap();
        let e = read_keys(&p, None).unwrap_err().to_string();
        std::fs::remove_file(&p).unwrap();
        assert!(
            e.contains("at most 67108864") && e.contains("resample"),
            "{e}"
        );
    }

    #[test]
    fn csv_with_a_header_comments_and_frames() {
        let text = "# jaw from Blender\nframe,jaw_open\n0, 0.0\n12;0.1\n24\t0.15\n";
        let k = parse_keys(text, "jaw.csv", Some(24.0)).unwrap();
        assert_eq!(k, vec![(0.0, 0.0), (0.5, 0.1), (1.0, 0.15)]);
    }

    #[test]
    fn the_json_forms_agree() {
        let want = vec![(0.0, 0.0), (0.5, 0.2)];
        for text in [
            "[[0, 0], [0.5, 0.2]]",
            r#"[{"time": 0, "value": 0}, {"time": 0.5, "value": 0.2}]"#,
            r#"{"time": [0, 0.5], "value": [0, 0.2]}"#,
        ] {
            assert_eq!(parse_keys(text, "k.json", None).unwrap(), want, "{text}");
        }
    }

    #[test]
    fn bad_keys_name_the_file_and_line_or_key() {
        let e = parse_keys("time,value\n0,0\n0.5,x\n", "jaw.csv", None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("jaw.csv:3:"), "{e}");
        let e = parse_keys("[[0, 0], [1]]", "k.json", None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("k.json") && e.contains("key 1"), "{e}");
        let e = parse_keys("0,nan\n", "k.csv", None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("finite"), "{e}");
        let e = parse_keys("# nothing\n", "k.csv", None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("no keys"), "{e}");
        let e = parse_keys("0,1\n", "k.csv", Some(0.0))
            .unwrap_err()
            .to_string();
        assert!(e.contains("keys_fps"), "{e}");
    }

    #[test]
    fn a_malformed_first_row_is_not_taken_for_a_header() {
        // a first line with a number in it is data: refused when malformed, naming line 1
        for text in ["0,0.1x\n1,0.2\n", "0,0.1,0.2\n1,0.2\n", "0;x\n1,0.2\n"] {
            let e = parse_keys(text, "jaw.csv", None).unwrap_err().to_string();
            assert!(e.contains("jaw.csv:1:"), "{text:?}: {e}");
        }
        // a header has no number in it
        assert_eq!(
            parse_keys("t,v\n1,0.2\n", "jaw.csv", None).unwrap(),
            vec![(1.0, 0.2)]
        );
    }

    #[test]
    fn a_byte_order_mark_is_not_data() {
        let want = vec![(0.0, 0.0), (0.5, 0.2)];
        for text in [
            "\u{feff}[[0, 0], [0.5, 0.2]]",
            "\u{feff}time,value\n0,0\n0.5,0.2\n",
        ] {
            assert_eq!(parse_keys(text, "k", None).unwrap(), want, "{text:?}");
        }
    }

    #[test]
    fn frame_rates_outside_the_range_are_refused() {
        for fps in [1e-300, 1e-4, 2e6, f64::INFINITY, -24.0] {
            let e = parse_keys("0,1\n", "k.csv", Some(fps))
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("keys_fps") && e.contains("frame rate from"),
                "{fps}: {e}"
            );
        }
        for fps in [1e-3, 24.0, 1e6] {
            assert!(parse_keys("0,1\n", "k.csv", Some(fps)).is_ok(), "{fps}");
        }
    }

    #[test]
    fn a_keys_file_that_is_not_a_regular_file_is_refused() {
        let dir = std::env::temp_dir();
        let e = read_keys(&dir, None).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
    }
}
