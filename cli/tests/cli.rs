//! The command line's behaviour on bad input, signals and restarts, through the `sticky-lips`
//! binary: every malformed input gets an error naming the file and the line or field, an
//! interrupted job leaves complete frames, no command overwrites its input. (The library's
//! readers are tested without the binary in `verification/inputs.rs`.)

use std::path::{Path, PathBuf};

/// The repository root (this package is `cli/` in it).
/// A small valid scenario (its first line is a comment), shared with `verification/inputs.rs`.
const GOOD_TOML: &str = include_str!("../../verification/small_block.toml");

/// Waits (at most 60 s) until the run writing into `out` has written its second frame.
fn wait_for_second_frame(out: &Path) {
    let t0 = std::time::Instant::now();
    while !out.join("frame_000001.vtu").exists() {
        assert!(t0.elapsed().as_secs() < 60, "no second frame within 60 s");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("cli/ is inside the repository")
        .to_path_buf()
}

/// The command line refuses `--threads 0`, a non-finite blend weight, a blend shape with a
/// non-finite displacement, an extrusion thickness that is a unit mistake and a temperature
/// at absolute zero, and takes a negative temperature above it.
#[test]
fn command_line_values_are_checked() {
    use std::process::Command;
    let bin = env!("CARGO_BIN_EXE_sticky-lips");
    let dir = std::env::temp_dir().join(format!("sticky-lips-cli-values-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let case = dir.join("case.toml");
    std::fs::write(&case, GOOD_TOML).unwrap();
    let fails = |args: &[&str], want: &str| {
        let o = Command::new(bin).args(args).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(
            o.status.code(),
            Some(if want.starts_with("error: invalid value") {
                2
            } else {
                1
            }),
            "{args:?}: {err}"
        );
        assert!(
            err.contains(want),
            "{args:?}: expected `{want}`, got: {err}"
        );
    };
    let c = case.to_str().unwrap();
    // a temperature below 0 C is a value, not an option; below absolute zero it is refused
    let o = Command::new(bin)
        .args(["evaporation", "--ambient", "-5", "--json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["inputs"]["p_eq_Pa"].as_f64().unwrap() > 0.0);
    fails(
        &["evaporation", "--temperature", "-273.15"],
        "error: invalid value '-273.15' for '--temperature",
    );
    fails(
        &[
            "run",
            c,
            "--threads",
            "0",
            "--out",
            dir.join("o").to_str().unwrap(),
        ],
        "error: invalid value '0' for '--threads",
    );
    // a shape to blend: the run's own final frame, then the same frame with a NaN in it
    let run = dir.join("run");
    let o = Command::new(bin)
        .args(["run", c, "--quiet", "--out", run.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let fin = run.join("final.vtu");
    let blend_out = dir.join("blend");
    fails(
        &[
            "blend",
            c,
            "--shape",
            &format!("{}=nan", fin.display()),
            "--out",
            blend_out.to_str().unwrap(),
        ],
        "`nan` is not a finite number (PATH.vtu=WEIGHT)",
    );
    assert!(!blend_out.join("frames.pvd").exists());
    // a surface 1 cm across extruded by 1e300 m
    let obj = dir.join("square.obj");
    std::fs::write(
        &obj,
        "v 0 0 0\nv 0.01 0 0\nv 0.01 0.01 0\nv 0 0.01 0\nf 1 2 3 4\n",
    )
    .unwrap();
    fails(
        &[
            "extrude",
            obj.to_str().unwrap(),
            "--thickness",
            "1e300",
            "--out",
            dir.join("ext").to_str().unwrap(),
        ],
        "more than 1000 times the surface's size",
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// SIGINT and SIGTERM stop a run between two steps: exit status 130, `summary.json` marked
/// interrupted, every frame on disk complete and listed in `frames.pvd`, no temporary file,
/// no `final.vtu`. A stale temporary file of an earlier killed run is removed.
#[test]
fn interrupted_runs_leave_complete_frames_and_say_where_they_stopped() {
    use std::process::Command;
    let bin = env!("CARGO_BIN_EXE_sticky-lips");
    let dir = std::env::temp_dir().join(format!("sticky-lips-interrupt-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // 1000 hexahedra for 10^6 steps: about a minute, far longer than the test waits
    let case = dir.join("long.toml");
    std::fs::write(
        &case,
        GOOD_TOML
            .replace("cells = [2, 2, 2]", "cells = [10, 10, 10]")
            .replace("total = 0.01", "total = 100.0\noutput_every = 2000"),
    )
    .unwrap();
    // the third: two signals a moment apart (GNU timeout signals the process, then its
    // group): one request, the same clean stop
    for (k, (signal, twice)) in [("INT", false), ("TERM", false), ("INT", true)]
        .into_iter()
        .enumerate()
    {
        let out = dir.join(format!("out_{k}_{signal}"));
        std::fs::create_dir_all(&out).unwrap();
        std::fs::write(out.join(".frame_000007.vtu.tmp-999999"), b"half a frame").unwrap();
        let child = Command::new(bin)
            .args([
                "run",
                case.to_str().unwrap(),
                "--quiet",
                "--out",
                out.to_str().unwrap(),
            ])
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        // wait for the second frame, then signal
        wait_for_second_frame(&out);
        for _ in 0..1 + usize::from(twice) {
            let kill = Command::new("kill")
                .args([format!("-{signal}"), child.id().to_string()])
                .status()
                .unwrap();
            assert!(kill.success());
        }
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(130), "SIG{signal}: {err}");
        assert!(err.contains("interrupted at step"), "{err}");
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        let step = summary["interrupted"]["step"].as_u64().unwrap();
        assert!(step > 0 && step < 1_000_000, "{summary}");
        assert_eq!(summary["steps"].as_u64(), Some(step));
        let mut names: Vec<String> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert!(names.iter().all(|n| !n.contains(".tmp-")), "{names:?}");
        assert!(!names.contains(&"final.vtu".to_string()));
        let pvd = std::fs::read_to_string(out.join("frames.pvd")).unwrap();
        let frames: Vec<&String> = names.iter().filter(|n| n.starts_with("frame_")).collect();
        assert_eq!(pvd.matches("<DataSet").count(), frames.len(), "{pvd}");
        assert_eq!(summary["frames"].as_u64(), Some(frames.len() as u64));
        for f in frames {
            assert!(pvd.contains(f.as_str()), "{f} not in frames.pvd");
            let (_, comps, points) =
                sticky_lips::io::vtu::read_point_data_f64(&out.join(f), "displacement").unwrap();
            assert_eq!((comps, points), (3, 1331), "{f}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `run --progress json`: every stdout line is one JSON object; the progress events rise from
/// step 0 to the last step with their frame counts, the last line is `finished` with the
/// summary's steps and frames; interrupted by SIGINT the last line is `interrupted` at the
/// step the summary names, exit status 130.
#[test]
fn progress_json_lines_rise_to_the_end_and_close_with_the_outcome() {
    use std::io::BufRead;
    use std::process::{Command, Stdio};
    let bin = env!("CARGO_BIN_EXE_sticky-lips");
    let dir = std::env::temp_dir().join(format!("sticky-lips-json-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let lines = |stdout: &[u8]| -> Vec<serde_json::Value> {
        stdout
            .lines()
            .map(|l| serde_json::from_str(&l.unwrap()).expect("each line is JSON"))
            .collect()
    };
    // a whole run: 100 steps of the small block
    let case = dir.join("case.toml");
    std::fs::write(&case, GOOD_TOML).unwrap();
    let out = dir.join("whole");
    let o = Command::new(bin)
        .args(["run", case.to_str().unwrap(), "--progress", "json", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v = lines(&o.stdout);
    let (last, progress) = v.split_last().unwrap();
    assert!(progress.iter().all(|p| p["event"] == "progress"), "{v:?}");
    let steps: Vec<u64> = progress
        .iter()
        .map(|p| p["step"].as_u64().unwrap())
        .collect();
    assert_eq!(steps.first(), Some(&0));
    assert!(steps.windows(2).all(|w| w[0] < w[1]), "{steps:?}");
    assert_eq!(steps.last().copied(), progress[0]["steps"].as_u64());
    assert!(progress[0]["seconds_left"].is_null());
    assert_eq!(progress.last().unwrap()["seconds_left"], 0.0);
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(last["event"], "finished");
    assert_eq!(last["steps"], summary["steps"]);
    assert_eq!(last["frames"], summary["frames"]);
    assert_eq!(progress.last().unwrap()["frames"], summary["frames"]);
    // interrupted: the 10^6-step block, SIGINT after its second frame
    let long = dir.join("long.toml");
    std::fs::write(
        &long,
        GOOD_TOML
            .replace("cells = [2, 2, 2]", "cells = [10, 10, 10]")
            .replace("total = 0.01", "total = 100.0\noutput_every = 2000"),
    )
    .unwrap();
    let out = dir.join("interrupted");
    let child = Command::new(bin)
        .args(["run", long.to_str().unwrap(), "--progress", "json", "--out"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for_second_frame(&out);
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130));
    let v = lines(&o.stdout);
    let last = v.last().unwrap();
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(last["event"], "interrupted", "{v:?}");
    assert_eq!(last["step"], summary["interrupted"]["step"]);
    assert!(v[..v.len() - 1].iter().all(|p| p["event"] == "progress"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `sweep` honours SIGTERM: no further run starts, the running one is stopped as an
/// interrupted run (its summary.json says so), and sweep.json lists what ran and what did
/// not; the sweep exits with 130.
#[test]
fn a_sweep_stops_on_a_signal() {
    use std::process::Command;
    let bin = env!("CARGO_BIN_EXE_sticky-lips");
    let dir = std::env::temp_dir().join(format!("sticky-lips-sweep-signal-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("long.toml"),
        GOOD_TOML
            .replace("cells = [2, 2, 2]", "cells = [10, 10, 10]")
            .replace("total = 0.01", "total = 100.0\noutput_every = 2000"),
    )
    .unwrap();
    let spec = dir.join("spec.toml");
    std::fs::write(
        &spec,
        "base = \"long.toml\"\nout = \"runs\"\njobs = 1\n[[shot]]\nname = \"a\"\n[[shot]]\nname = \"b\"\n",
    )
    .unwrap();
    let child = Command::new(bin)
        .arg("sweep")
        .arg(&spec)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let runs = dir.join("runs");
    let t0 = std::time::Instant::now();
    while !runs.join("a/frame_000001.vtu").exists() {
        assert!(
            t0.elapsed().as_secs() < 60,
            "run a wrote no second frame within 60 s"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let kill = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(
        err.contains("interrupted: sweep stopped") && err.contains("1 not started"),
        "{err}"
    );
    let sweep: serde_json::Value =
        serde_json::from_slice(&std::fs::read(runs.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(sweep["interrupted"], serde_json::json!(true));
    assert_eq!(sweep["not_started"], serde_json::json!(["b"]));
    assert_eq!(sweep["runs"][0]["status"], serde_json::json!(130));
    let a: serde_json::Value =
        serde_json::from_slice(&std::fs::read(runs.join("a/summary.json")).unwrap()).unwrap();
    assert!(a["interrupted"]["step"].as_u64().is_some(), "{a}");
    assert!(!runs.join("b/summary.json").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A run that diverges at its first steps (a prescribed displacement of -1000 m at once) says
/// that its inputs are out of range, not the stepping, with the step, time and element.
#[test]
fn a_divergence_at_the_first_step_points_at_the_inputs() {
    use std::process::Command;
    let bin = env!("CARGO_BIN_EXE_sticky-lips");
    let dir = std::env::temp_dir().join(format!("sticky-lips-diverge-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let case = dir.join("absurd.toml");
    std::fs::write(
        &case,
        GOOD_TOML.replace("value = 0.001", "value = -1000.0\nshape = \"step\""),
    )
    .unwrap();
    let o = Command::new(bin)
        .arg("run")
        .arg(&case)
        .args(["--quiet", "--out"])
        .arg(dir.join("out"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("run diverged at step 1")
            && err.contains("element")
            && err.contains(
                "at the first steps: what the run started from or was given is out of range"
            ),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `face` honours SIGTERM: stopped in the lip finder of a large head (a rough sheet of
/// 270 400 quads, 11 s to refuse here), it exits with 130 and the message, and `--out` holds
/// nothing of it (its outputs are staged and moved in together at the end).
#[test]
fn face_stops_on_a_signal_and_writes_nothing() {
    use std::fmt::Write as _;
    use std::process::Command;
    let bin = env!("CARGO_BIN_EXE_sticky-lips");
    let dir = std::env::temp_dir().join(format!("sticky-lips-face-signal-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let n = 520;
    let mut obj = String::new();
    for j in 0..=n {
        for i in 0..=n {
            let z = 0.002 * ((i * 7 + j * 3) % 5) as f64;
            let _ = writeln!(
                obj,
                "v {} {} {z}",
                0.3 * i as f64 / n as f64,
                0.3 * j as f64 / n as f64
            );
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i + 1;
            let _ = writeln!(obj, "f {a} {} {} {}", a + 1, a + n + 2, a + n + 1);
        }
    }
    let head = dir.join("sheet.obj");
    std::fs::write(&head, obj).unwrap();
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let child = Command::new(bin)
        .arg("face")
        .arg(&head)
        .arg("--out")
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let kill = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let t0 = std::time::Instant::now();
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted: face stopped"), "{err}");
    println!(
        "face stopped {:.2} s after SIGTERM",
        t0.elapsed().as_secs_f64()
    );
    assert_eq!(
        std::fs::read_dir(&out).unwrap().count(),
        0,
        "--out is not empty"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Checkpoint and restart: a run killed with SIGKILL part-way (after a checkpoint and with
/// frames written after it) and continued with `run --restart DIR` ends with every frame,
/// `frames.pvd`, `final.vtu` and the summary's series byte for byte those of an uninterrupted
/// run without checkpoints. A restart refuses a checkpoint of another problem, of another
/// precision, and a damaged one, with exit status 1, leaving the directory as it was.
#[test]
fn a_killed_run_restarted_from_its_checkpoint_gives_the_uninterrupted_frames() {
    use std::process::{Command, Stdio};
    let bin = env!("CARGO_BIN_EXE_sticky-lips");
    let dir = std::env::temp_dir().join(format!("sticky-lips-restart-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // the two glued slabs (saliva elements break during the pull), 10^5 steps
    let example = repo().join("examples/sticky_slabs.toml");
    let text = std::fs::read_to_string(&example)
        .unwrap()
        .replace("total = 0.4", "total = 1.0");
    let case = dir.join("slabs.toml");
    std::fs::write(&case, &text).unwrap();
    let run = |args: &[&str]| {
        let o = Command::new(bin).args(args).output().unwrap();
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let a = dir.join("a");
    let b = dir.join("b");
    let (s, c) = (case.to_str().unwrap(), "--quiet");
    assert_eq!(run(&["run", s, c, "--out", a.to_str().unwrap()]).0, Some(0));
    let child = Command::new(bin)
        .args(["run", s, c, "--checkpoint-every", "5000", "--out"])
        .arg(&b)
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // kill once a checkpoint is on disk and a frame after it
    let t0 = std::time::Instant::now();
    let ck = b.join("checkpoint.bin");
    while !(ck.exists() && b.join("frame_000007.vtu").exists()) {
        assert!(t0.elapsed().as_secs() < 60, "no checkpoint within 60 s");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let mut child = child;
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!b.join("final.vtu").exists(), "killed after the end");
    let (header, _) = sticky_lips::io::checkpoint::read(&ck).unwrap();
    let on_disk = std::fs::read_dir(&b)
        .unwrap()
        .filter(|e| {
            let n = e.as_ref().unwrap().file_name();
            let n = n.to_string_lossy();
            n.starts_with("frame_") && n.ends_with(".vtu")
        })
        .count();
    println!(
        "killed: checkpoint at step {} listing {} frames, {} frames on disk",
        header.step,
        header.history.frames.len(),
        on_disk
    );
    assert!(header.step > 0 && header.step < 100_000 && header.step % 5000 == 0);

    // refusals leave the directory as it was
    let listing = |d: &Path| {
        let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| {
                let p = e.unwrap().path();
                (
                    p.file_name().unwrap().to_string_lossy().into_owned(),
                    std::fs::read(&p).unwrap(),
                )
            })
            .collect();
        v.sort();
        v
    };
    let before = listing(&b);
    let other = dir.join("other.toml");
    std::fs::write(&other, text.replace("k_glue = 0.05 ", "k_glue = 0.06 ")).unwrap();
    let bs = b.to_str().unwrap();
    let (code, err) = run(&["run", other.to_str().unwrap(), c, "--restart", bs]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("checkpoint.bin") && err.contains("different problem"),
        "{err}"
    );
    let (code, err) = run(&["run", c, "--restart", bs, "--precision", "f32"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("checkpoint is of an f64 run"), "{err}");
    let (code, err) = run(&["run", c, "--restart", bs, "--out", a.to_str().unwrap()]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("--out"), "{err}");
    assert_eq!(
        listing(&b),
        before,
        "a refused restart changed the directory"
    );
    let damaged = dir.join("damaged");
    std::fs::create_dir_all(&damaged).unwrap();
    let mut bytes = std::fs::read(&ck).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 1;
    std::fs::write(damaged.join("checkpoint.bin"), bytes).unwrap();
    let (code, err) = run(&["run", s, c, "--restart", damaged.to_str().unwrap()]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("damaged"), "{err}");

    // a checkpoint moved into another run's directory (that run's frames there, a softer
    // tissue: other displacements from the first frames on): refused before anything
    // changes, naming the checkpoint and the frame that differs. (A run whose frames up to
    // the checkpoint are bit for bit the checkpoint's run's is continued: nothing mixes.)
    let foreign = dir.join("foreign");
    let short = dir.join("short.toml");
    std::fs::write(
        &short,
        text.replace("total = 1.0", "total = 0.4")
            .replace("mu = 800.0", "mu = 700.0"),
    )
    .unwrap();
    let fs_ = foreign.to_str().unwrap();
    assert_eq!(
        run(&["run", short.to_str().unwrap(), c, "--out", fs_]).0,
        Some(0)
    );
    std::fs::copy(&ck, foreign.join("checkpoint.bin")).unwrap();
    let before_foreign = listing(&foreign);
    let (code, err) = run(&["run", c, "--restart", fs_]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("checkpoint.bin") && err.contains("belongs to another run"),
        "{err}"
    );
    assert_eq!(
        listing(&foreign),
        before_foreign,
        "a refused restart changed the directory"
    );

    // the restart (input taken from the checkpoint) completes the run
    let (code, err) = run(&["run", c, "--restart", bs]);
    assert_eq!(code, Some(0), "{err}");
    assert!(!ck.exists(), "the checkpoint of a completed run is removed");
    let (la, lb) = (listing(&a), listing(&b));
    let names = |l: &[(String, Vec<u8>)]| l.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>();
    assert_eq!(names(&la), names(&lb));
    let mut frames = 0;
    for ((name, x), (_, y)) in la.iter().zip(&lb) {
        if name == "summary.json" {
            let parse = |b: &[u8]| -> serde_json::Value { serde_json::from_slice(b).unwrap() };
            let (mut x, mut y) = (parse(x), parse(y));
            assert_eq!(y["restarted_from"].as_u64(), Some(header.step as u64));
            for v in [&mut x, &mut y] {
                let o = v.as_object_mut().unwrap();
                for k in [
                    "wall_time",
                    "stepping_time",
                    "element_updates_per_second",
                    "restarted_from",
                ] {
                    o.remove(k);
                }
            }
            assert_eq!(x, y, "summary.json");
        } else {
            assert!(x == y, "{name} differs from the uninterrupted run's");
            frames += name.starts_with("frame_") as usize;
        }
    }
    assert_eq!(frames, 101);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every case of `verification/catalogue/cases.toml` (the malformed inputs of issue 15 and the
/// fuzz targets' finds) run through the command line: the exit status and message it lists,
/// no panic or abort, and no output directory left behind.
#[test]
fn catalogue_of_malformed_inputs() {
    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Case {
        what: String,
        source: String,
        args: Vec<String>,
        exit: i32,
        message: String,
    }
    #[derive(serde::Deserialize)]
    struct Catalogue {
        case: Vec<Case>,
    }
    let bin = env!("CARGO_BIN_EXE_sticky-lips");
    let cat = repo().join("verification/catalogue");
    let text = std::fs::read_to_string(cat.join("cases.toml")).unwrap();
    let catalogue: Catalogue = toml::from_str(&text).unwrap();
    let dir = std::env::temp_dir().join(format!("sticky-lips-catalogue-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (i, c) in catalogue.case.iter().enumerate() {
        let out = dir.join(format!("out_{i}"));
        let args: Vec<String> = c
            .args
            .iter()
            .map(|a| {
                a.replace("{cat}", cat.to_str().unwrap())
                    .replace("{out}", out.to_str().unwrap())
            })
            .collect();
        let o = std::process::Command::new(bin)
            .args(&args)
            .current_dir(&dir)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        let what = format!("case {i} ({}; {}): {}", c.what, c.source, args.join(" "));
        assert_eq!(o.status.code(), Some(c.exit), "{what}\n{err}");
        assert!(
            err.contains(&c.message),
            "{what}\nexpected `{}`\ngot {err}",
            c.message
        );
        assert!(!err.contains("panicked"), "{what}\n{err}");
        assert!(!out.exists(), "{what}: left {}", out.display());
    }
    println!(
        "catalogue: {} malformed inputs refused",
        catalogue.case.len()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `sticky-lips sweep`: a grid of two values and a named shot become three run directories,
/// each with its scenario, one line each in `jobs.txt`, and runs whose results differ as
/// their overrides say; `--plan` writes the plan only; a run whose overrides make a bad
/// scenario is refused before anything is written, naming the run and the field.
#[test]
fn a_sweep_expands_into_runs_and_a_job_list() {
    use std::process::Command;
    let bin = env!("CARGO_BIN_EXE_sticky-lips");
    let dir = std::env::temp_dir().join(format!("sticky-lips-sweep-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let base = repo().join("examples/cantilever.toml");
    let spec = dir.join("spec.toml");
    std::fs::write(
        &spec,
        format!(
            "base = {:?}\nout = \"runs\"\njobs = 2\n\n[grid]\n\"materials.0.mu\" = [800.0, 3200.0]\n\"time.total\" = [0.02]\n\n[[shot]]\nname = \"soft\"\nset = {{ \"materials.0.mu\" = 400.0, \"time.total\" = 0.02 }}\n",
            base.display().to_string()
        ),
    )
    .unwrap();
    let o = Command::new(bin)
        .args(["sweep", spec.to_str().unwrap(), "--plan"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let runs = dir.join("runs");
    let names = [
        "000_mu-800.0_total-0.02",
        "001_mu-3200.0_total-0.02",
        "soft",
    ];
    for n in names {
        assert!(runs.join(n).join("scenario.toml").exists(), "{n}");
        assert!(
            !runs.join(n).join("summary.json").exists(),
            "--plan ran {n}"
        );
    }
    let jobs = std::fs::read_to_string(runs.join("jobs.txt")).unwrap();
    assert_eq!(jobs.lines().count(), 3);
    assert!(jobs
        .lines()
        .all(|l| l.contains(" run ") && l.contains("--threads 1")));
    let o = Command::new(bin)
        .args(["sweep", spec.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(runs.join("sweep.json")).unwrap()).unwrap();
    let statuses: Vec<i64> = summary["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["status"].as_i64().unwrap())
        .collect();
    assert_eq!(statuses, vec![0, 0, 0]);
    let final_of = |n: &str| std::fs::read(runs.join(n).join("final.vtu")).unwrap();
    assert_ne!(final_of(names[0]), final_of(names[1]));
    assert_ne!(final_of(names[0]), final_of(names[2]));
    // each run is an ordinary run: its scenario, run again elsewhere, gives the same frames.
    // (The cantilever is smaller than one work chunk, so the 2 threads here cannot change
    // anything; that the thread count never changes the bits is tested on the full face,
    // with 1 to 7 threads, in `determinism.rs`.)
    let again = dir.join("again");
    let o = Command::new(bin)
        .args([
            "run",
            runs.join(names[1]).join("scenario.toml").to_str().unwrap(),
        ])
        .args([
            "--out",
            again.to_str().unwrap(),
            "--threads",
            "2",
            "--quiet",
        ])
        .output()
        .unwrap();
    assert!(o.status.success());
    assert_eq!(
        std::fs::read(again.join("final.vtu")).unwrap(),
        final_of(names[1])
    );
    // a bad value: refused before any directory is made
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        format!(
            "base = {:?}\nout = \"bad_runs\"\n[grid]\n\"materials.0.mu\" = [800.0, -1.0]\n",
            base.display().to_string()
        ),
    )
    .unwrap();
    let o = Command::new(bin)
        .args(["sweep", bad.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("run 001_mu--1.0") && err.contains("mu"),
        "{err}"
    );
    assert!(!dir.join("bad_runs").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// No command overwrites its own input: `face` with the head (or its rig) in `--out` under a
/// name it writes, `extrude` with the surface there, `mouth` with its parameters there. Each
/// is refused before anything is written, naming the input and `--out`, and the file keeps
/// its bytes.
#[test]
fn no_command_overwrites_its_input() {
    use std::process::Command;
    let bin = env!("CARGO_BIN_EXE_sticky-lips");
    let dir = std::env::temp_dir().join(format!("sticky-lips-overwrite-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    let cases: [(&[&str], &str, &str); 5] = [
        (
            &["face", "{d}/head.obj", "--out", "{d}"],
            "head.obj",
            "the head is",
        ),
        (
            &["face", "{d}/model.obj", "--out", "{d}"],
            "model.obj",
            "the head is",
        ),
        (
            &[
                "face",
                "{d}/in.obj",
                "--rig",
                "{d}/head.json",
                "--out",
                "{d}",
            ],
            "head.json",
            "the rig (--rig) is",
        ),
        (
            &[
                "extrude",
                "{d}/../x/mesh.vtu",
                "--thickness",
                "0.01",
                "--out",
                "{d}/../x",
            ],
            "../x/mesh.vtu",
            "the surface is",
        ),
        (
            &["mouth", "--params", "{d}/mouth.json", "--out", "{d}"],
            "mouth.json",
            "the parameters (--params) is",
        ),
    ];
    for (k, (args, file, want)) in cases.iter().enumerate() {
        let d = dir.join(format!("case{k}"));
        std::fs::create_dir_all(d.join("../x")).unwrap();
        std::fs::write(d.join("in.obj"), obj).unwrap();
        let target = d.join(file);
        let content = format!("{obj}# the user's file {k}\n");
        std::fs::write(&target, &content).unwrap();
        let args: Vec<String> = args
            .iter()
            .map(|a| a.replace("{d}", d.to_str().unwrap()))
            .collect();
        let o = Command::new(bin).args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains(want) && err.contains("--out") && err.contains("overwrite"),
            "{args:?}: {err}"
        );
        assert_eq!(
            std::fs::read_to_string(&target).unwrap(),
            content,
            "{args:?}: the input changed"
        );
        let written: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(
            written
                .iter()
                .all(|n| n == "in.obj" || n == "x" || target.ends_with(n)),
            "{args:?}: wrote {written:?}"
        );
    }
    // through a symbolic link and a hard link to the user's file: refused, the file unchanged
    #[cfg(unix)]
    for (k, symbolic) in [true, false].into_iter().enumerate() {
        let d = dir.join(format!("link{k}"));
        std::fs::create_dir_all(&d).unwrap();
        let user = dir.join(format!("users_head{k}.obj"));
        std::fs::write(&user, obj).unwrap();
        if symbolic {
            std::os::unix::fs::symlink(&user, d.join("head.obj")).unwrap();
        } else {
            std::fs::hard_link(&user, d.join("head.obj")).unwrap();
        }
        let o = Command::new(bin)
            .arg("face")
            .arg(d.join("head.obj"))
            .arg("--out")
            .arg(&d)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "link {k}: {err}");
        assert!(err.contains("overwrite"), "link {k}: {err}");
        assert_eq!(std::fs::read_to_string(&user).unwrap(), obj, "link {k}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `export` reads a run's frames and writes the animation files only from frames it can
/// trust: frames listed out of time order, and a frame with a non-finite displacement, are
/// refused naming the file and the entry or point, and the files already there are left as
/// they were.
#[test]
fn export_refuses_frames_out_of_order_and_non_finite() {
    use std::process::Command;
    let bin = env!("CARGO_BIN_EXE_sticky-lips");
    let dir = std::env::temp_dir().join(format!("sticky-lips-export-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // a short run of the quick face (300 steps, 4 frames)
    let path = repo().join("examples/plosive.toml");
    let text = sticky_lips::io::scenario::with_overrides(
        &std::fs::read_to_string(&path).unwrap(),
        "plosive.toml",
        &[
            ("time.total", toml::Value::Float(0.003)),
            ("time.output_every", toml::Value::Integer(100)),
        ],
    )
    .unwrap();
    let scenario = dir.join("scenario.toml");
    std::fs::write(&scenario, text).unwrap();
    let run = dir.join("run");
    let o = Command::new(bin)
        .args(["run", scenario.to_str().unwrap(), "--quiet", "--out"])
        .arg(&run)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let pc2 = std::fs::read(run.join("skin.pc2")).unwrap();
    let export = |what: &str, want: &[&str]| {
        let o = Command::new(bin).arg("export").arg(&run).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{what}: {err}");
        for w in want {
            assert!(err.contains(w), "{what}: expected `{w}` in {err}");
        }
        assert_eq!(
            std::fs::read(run.join("skin.pc2")).unwrap(),
            pc2,
            "{what}: skin.pc2 was rewritten"
        );
    };
    // two frames' times swapped in frames.pvd
    let pvd_path = run.join("frames.pvd");
    let pvd = std::fs::read_to_string(&pvd_path).unwrap();
    let swapped = pvd
        .replacen("timestep=\"0.001\"", "timestep=\"@\"", 1)
        .replacen("timestep=\"0.002\"", "timestep=\"0.001\"", 1)
        .replacen("timestep=\"@\"", "timestep=\"0.002\"", 1);
    assert_ne!(swapped, pvd, "frames.pvd: {pvd}");
    std::fs::write(&pvd_path, &swapped).unwrap();
    export("times out of order", &["frames.pvd", "does not come after"]);
    std::fs::write(&pvd_path, &pvd).unwrap();
    // a NaN in the last frame's displacement
    let frame = std::fs::read_dir(&run)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("frame_")
        })
        .max()
        .unwrap();
    let xml = std::fs::read_to_string(&frame).unwrap();
    let at = xml.find("Name=\"displacement\"").unwrap();
    let start = at + xml[at..].find('>').unwrap() + 1;
    let end = start + xml[start..].find("</DataArray>").unwrap();
    let mut raw = sticky_lips::io::vtu::base64_decode(&xml[start..end]).unwrap();
    raw[8 + 8 * 7..8 + 8 * 8].copy_from_slice(&f64::NAN.to_le_bytes());
    let forged = format!(
        "{}{}{}",
        &xml[..start],
        sticky_lips::io::vtu::base64_encode(&raw),
        &xml[end..]
    );
    std::fs::write(&frame, forged).unwrap();
    export(
        "a NaN displacement",
        &["point data `displacement`, point 2", "is not finite"],
    );
    // the skin map is never written over a file of the run
    let o = Command::new(bin)
        .arg("export")
        .arg(&run)
        .arg("--skin-map")
        .arg(run.join("summary.json"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("overwrite"), "{err}");
    assert!(std::fs::read_to_string(run.join("summary.json"))
        .unwrap()
        .contains("steps"));
    let _ = std::fs::remove_dir_all(&dir);
}
