//! The command line's side of [`sticky_lips::control`]: one cancel token for the process
//! (cancelled by SIGINT/SIGTERM in `main`), and the progress a run shows (`run --progress`).

use clap::ValueEnum;
use std::io::Write;
use std::sync::{Mutex, OnceLock};
use sticky_lips::control::{CancelToken, OnProgress, ProgressUpdate};

/// The process's token: the signal handler cancels it, every long job holds a clone.
pub fn cancel_token() -> CancelToken {
    static TOKEN: OnceLock<CancelToken> = OnceLock::new();
    TOKEN.get_or_init(CancelToken::new).clone()
}

/// What `run` prints while it steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Progress {
    /// A bar on the terminal (steps per second, ETA).
    Bar,
    /// A line on stderr every 10 % of the steps (for logs and pipes).
    Plain,
    /// One JSON object per line on stdout, for programs that drive the CLI (`event`,
    /// `step`, `steps`, `time`, `end_time`, `frames`, `elapsed`, `seconds_left`); the run's
    /// closing line is then a JSON object too (`event: "finished"` or `"interrupted"`).
    Json,
    /// Nothing.
    None,
}

impl Progress {
    /// `bar` on a terminal, else `plain`.
    pub fn default_for_stderr() -> Progress {
        use std::io::IsTerminal;
        if std::io::stderr().is_terminal() {
            Progress::Bar
        } else {
            Progress::Plain
        }
    }

    /// The callback that shows this kind of progress (`None` for [`Progress::None`]).
    pub fn callback(self) -> Option<OnProgress> {
        match self {
            Progress::None => None,
            Progress::Bar => {
                let bar: Mutex<Option<indicatif::ProgressBar>> = Mutex::new(None);
                Some(OnProgress::new(move |u: &ProgressUpdate| {
                    let mut b = bar.lock().unwrap_or_else(|e| e.into_inner());
                    let b = b.get_or_insert_with(|| {
                        let b = indicatif::ProgressBar::new(u.steps as u64);
                        b.set_style(
                            indicatif::ProgressStyle::with_template(
                                "{bar:40} {pos}/{len} steps  {per_sec}  ETA {eta}",
                            )
                            .expect("progress template"),
                        );
                        b
                    });
                    b.set_position(u.step as u64);
                    if u.step >= u.steps {
                        b.finish_and_clear();
                    }
                }))
            }
            Progress::Plain => {
                // the next step at which a line is printed (set at the first update)
                let next: Mutex<Option<usize>> = Mutex::new(None);
                Some(OnProgress::new(move |u: &ProgressUpdate| {
                    let mut next = next.lock().unwrap_or_else(|e| e.into_inner());
                    let tenth = u.steps / 10;
                    let n = next.get_or_insert(u.step + tenth);
                    if u.step >= *n && u.step > 0 {
                        eprintln!("step {}/{} (t = {:.4e} s)", u.step, u.steps, u.time);
                        *n += tenth.max(1);
                    }
                }))
            }
            Progress::Json => Some(OnProgress::new(|u: &ProgressUpdate| {
                json_line(&progress_json(u));
            })),
        }
    }
}

/// One progress update as the JSON object `--progress json` prints.
pub fn progress_json(u: &ProgressUpdate) -> serde_json::Value {
    let mut v = serde_json::to_value(u).expect("progress serialises");
    v.as_object_mut()
        .expect("an object")
        .insert("event".into(), "progress".into());
    v
}

/// Prints `v` as one line on stdout and flushes it (a reader sees each line at once).
pub fn json_line(v: &serde_json::Value) {
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{v}");
    let _ = out.flush();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_has_every_field() {
        let u = ProgressUpdate {
            step: 512,
            steps: 1000,
            time: 0.5,
            end_time: 1.0,
            frames: 3,
            elapsed: 0.25,
            seconds_left: Some(0.25),
        };
        let v = progress_json(&u);
        assert_eq!(v["event"], "progress");
        assert_eq!(v["step"], 512);
        assert_eq!(v["steps"], 1000);
        assert_eq!(v["frames"], 3);
        assert_eq!(v["seconds_left"], 0.25);
        let first = progress_json(&ProgressUpdate {
            seconds_left: None,
            ..u
        });
        assert!(first["seconds_left"].is_null());
    }
}
