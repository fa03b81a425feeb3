//! Atomic file writes: write to a temporary sibling file, flush + fsync it, then
//! rename it over the target. A reader (or a crash at any point) therefore sees
//! either the old complete file or the new complete file, never a half-written one.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// Temporary sibling path `.{filename}.tmp-{pid}` in the same directory as `path`
/// (same directory => same filesystem => `rename` is atomic).
fn temp_path(path: &Path) -> io::Result<PathBuf> {
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("write_atomic: path {} has no file name", path.display()),
        )
    })?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".tmp-{}", std::process::id()));
    Ok(path.with_file_name(tmp_name))
}

/// Best-effort fsync of the directory containing `path`, so the rename itself is
/// durable. Ignored where directories cannot be opened/synced (e.g. Windows).
fn sync_parent_dir(path: &Path) {
    #[cfg(unix)]
    {
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
    }
    #[cfg(not(unix))]
    let _ = path;
}

/// Whether `a` and `b` name the same existing file (through symbolic links, and on Unix
/// through hard links too).
fn same_file(a: &Path, b: &Path) -> bool {
    match (fs::canonicalize(a), fs::canonicalize(b)) {
        (Ok(x), Ok(y)) if x == y => return true,
        (Ok(_), Ok(_)) => {}
        _ => return false,
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (fs::metadata(a), fs::metadata(b)) {
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
    }
    false
}

/// Refuses, before anything is written, a command whose output directory `out` would
/// receive one of `outputs` (file names) over one of its `inputs` (`(path, what)`: `what`
/// names the argument, e.g. `the head (HEAD.obj)`): a user's file is never overwritten.
pub fn refuse_overwriting_inputs(
    out: &Path,
    outputs: &[&str],
    inputs: &[(&Path, &str)],
) -> crate::error::Result<()> {
    for name in outputs {
        let target = out.join(name);
        for (input, what) in inputs {
            if same_file(input, &target) {
                return Err(crate::error::Error::input(
                    input.display().to_string(),
                    crate::error::Location::Field("--out".into()),
                    format!(
                        "{what} is {}, which this command writes: it would overwrite its own \
                         input; give another --out",
                        target.display()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Temporary files and staging directories this process has open: removed by
/// [`remove_pending`] when the process must end at once (a second interrupt), so that even
/// that exit leaves no temporary file behind.
static PENDING: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

fn pending() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    PENDING.lock().unwrap_or_else(|e| e.into_inner())
}

fn register(p: &Path) {
    pending().push(p.to_path_buf());
}

fn unregister(p: &Path) {
    let mut v = pending();
    if let Some(i) = v.iter().rposition(|q| q == p) {
        v.swap_remove(i);
    }
}

/// Removes every temporary file and staging directory still open (for an exit that does
/// not unwind: the second of two interrupts). Returns how many were removed.
pub fn remove_pending() -> usize {
    let v: Vec<PathBuf> = pending().drain(..).collect();
    let mut n = 0;
    for p in v {
        let gone = if p.is_dir() {
            fs::remove_dir_all(&p)
        } else {
            fs::remove_file(&p)
        };
        n += usize::from(gone.is_ok());
    }
    n
}

/// A command's outputs written first into a hidden directory beside them
/// (`DIR/.NAME.staging-PID`) and moved into `DIR` together once all are written and
/// checked ([`Staging::commit`]). Dropped without a commit (an error, an interrupt), the
/// staging directory is removed and `DIR` is as it was.
pub struct Staging {
    dir: PathBuf,
    out: PathBuf,
    done: bool,
    /// `out` did not exist before: removed too when dropped without a commit.
    created_out: bool,
}

impl Staging {
    /// Creates `out` if needed and the staging directory in it; `name` is the command's.
    pub fn new(out: &Path, name: &str) -> io::Result<Staging> {
        let created_out = !out.exists();
        fs::create_dir_all(out)?;
        let dir = out.join(format!(".{name}.staging-{}", std::process::id()));
        if dir.exists() {
            fs::remove_dir_all(&dir)?;
        }
        register(&dir);
        if let Err(e) = fs::create_dir(&dir) {
            unregister(&dir);
            return Err(e);
        }
        Ok(Staging {
            dir,
            out: out.to_path_buf(),
            done: false,
            created_out,
        })
    }

    /// Where to write the outputs.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Moves every file written into the staging directory into the output directory (each
    /// by an atomic rename, replacing an older output of the same name) and removes the
    /// staging directory. Returns the names moved, sorted.
    pub fn commit(mut self) -> io::Result<Vec<String>> {
        let mut names: Vec<String> = fs::read_dir(&self.dir)?
            .map(|e| e.map(|e| e.file_name().to_string_lossy().into_owned()))
            .collect::<io::Result<_>>()?;
        names.sort();
        for n in &names {
            fs::rename(self.dir.join(n), self.out.join(n))?;
        }
        fs::remove_dir(&self.dir)?;
        unregister(&self.dir);
        sync_parent_dir(&self.out.join("x"));
        self.done = true;
        Ok(names)
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.done {
            let _ = fs::remove_dir_all(&self.dir);
            unregister(&self.dir);
            if self.created_out {
                // only if still empty: remove_dir refuses a directory with anything in it
                let _ = fs::remove_dir(&self.out);
            }
        }
    }
}

/// Atomically replace `path` with `bytes`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Atomically replace `path` with whatever `f` writes. `f` writes into a
/// buffered temporary file; if `f` (or flushing/syncing) fails, the temporary
/// file is removed and the target is left untouched.
pub fn write_atomic_with<F>(path: &Path, f: F) -> io::Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let tmp = temp_path(path)?;
    register(&tmp);
    let result = (|| {
        let file = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .open(&tmp)?;
        let mut w = BufWriter::with_capacity(1 << 16, file);
        f(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        drop(file);
        fs::rename(&tmp, path)
    })();
    let result = match result {
        Ok(()) => {
            sync_parent_dir(path);
            Ok(())
        }
        Err(e) => {
            let _ = fs::remove_file(&tmp);
            Err(e)
        }
    };
    unregister(&tmp);
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch_dir(tag: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("sticky_lips_atomic_{}_{}", tag, std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    fn leftovers(dir: &Path) -> Vec<String> {
        fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains(".tmp-"))
            .collect()
    }

    #[test]
    fn temp_name_is_hidden_sibling() {
        let t = temp_path(Path::new("/a/b/out.vtu")).unwrap();
        assert_eq!(
            t,
            PathBuf::from(format!("/a/b/.out.vtu.tmp-{}", std::process::id()))
        );
        assert!(temp_path(Path::new("/")).is_err());
    }

    #[test]
    fn writes_and_overwrites() {
        let d = scratch_dir("overwrite");
        let p = d.join("x.txt");
        write_atomic(&p, b"first version, long").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"first version, long");
        write_atomic(&p, b"second").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"second");
        assert!(leftovers(&d).is_empty());
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn streaming_writer() {
        let d = scratch_dir("stream");
        let p = d.join("big.bin");
        let expected: Vec<u8> = (0..300_000u32).map(|i| (i % 251) as u8).collect();
        write_atomic_with(&p, |w| {
            for chunk in expected.chunks(1000) {
                w.write_all(chunk)?;
            }
            Ok(())
        })
        .unwrap();
        assert_eq!(fs::read(&p).unwrap(), expected);
        assert!(leftovers(&d).is_empty());
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn failure_keeps_old_file_and_cleans_temp() {
        let d = scratch_dir("fail");
        let p = d.join("keep.txt");
        write_atomic(&p, b"old").unwrap();
        let err = write_atomic_with(&p, |w| {
            w.write_all(b"partial new content")?;
            Err(io::Error::other("simulated crash"))
        })
        .unwrap_err();
        assert_eq!(err.to_string(), "simulated crash");
        assert_eq!(fs::read(&p).unwrap(), b"old");
        assert!(leftovers(&d).is_empty());
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn staging_commits_together_or_leaves_nothing() {
        let d = scratch_dir("staging");
        fs::write(d.join("a.txt"), b"old").unwrap();
        {
            let s = Staging::new(&d, "t").unwrap();
            write_atomic(&s.path().join("a.txt"), b"new").unwrap();
            write_atomic(&s.path().join("b.txt"), b"b").unwrap();
            // dropped without a commit: nothing moved, the staging directory gone
        }
        assert_eq!(fs::read(d.join("a.txt")).unwrap(), b"old");
        assert!(!d.join("b.txt").exists());
        assert_eq!(fs::read_dir(&d).unwrap().count(), 1);
        let s = Staging::new(&d, "t").unwrap();
        write_atomic(&s.path().join("a.txt"), b"new").unwrap();
        write_atomic(&s.path().join("b.txt"), b"b").unwrap();
        assert_eq!(s.commit().unwrap(), vec!["a.txt", "b.txt"]);
        assert_eq!(fs::read(d.join("a.txt")).unwrap(), b"new");
        assert_eq!(fs::read_dir(&d).unwrap().count(), 2);
        // an output directory it made is removed again when nothing was committed
        let new_out = d.join("new_out");
        {
            let s = Staging::new(&new_out, "t").unwrap();
            write_atomic(&s.path().join("a.txt"), b"x").unwrap();
        }
        assert!(!new_out.exists());
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn missing_directory_is_an_error() {
        let d = scratch_dir("missing");
        let p = d.join("no_such_dir").join("f.txt");
        assert!(write_atomic(&p, b"x").is_err());
        fs::remove_dir_all(&d).unwrap();
    }
}
