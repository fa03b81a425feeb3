"""Runs through the package: the command line's bits, progress, the saliva state, check(),
the GIL released."""

from __future__ import annotations

import json
import re
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import sticky_lips

REPO = Path(__file__).resolve().parents[2]
SLABS = REPO / "examples" / "sticky_slabs.toml"


@pytest.fixture(scope="module")
def slabs_run(tmp_path_factory) -> sticky_lips.Run:
    """The sticky slabs (all 25 saliva elements break), run by the package on 2 threads."""
    out = tmp_path_factory.mktemp("py") / "sticky_slabs"
    return sticky_lips.Scenario(SLABS).run(out, threads=2)


def test_run_equals_the_command_lines_bit_for_bit(slabs_run, run_cli, tmp_path):
    """The same scenario through `sticky-lips run` (1 thread) and `Scenario.run` (2 threads):
    the same frame files byte for byte, and the same arrays read back."""
    cli_out = tmp_path / "cli"
    run_cli("run", str(SLABS), "--out", str(cli_out), "--quiet", "--threads", "1")
    ours = sorted(p.name for p in slabs_run.out.glob("*.vtu"))
    theirs = sorted(p.name for p in cli_out.glob("*.vtu"))
    assert ours == theirs and len(ours) == 42  # 41 frames and final.vtu
    for name in ours + ["frames.pvd"]:
        assert (slabs_run.out / name).read_bytes() == (cli_out / name).read_bytes(), name
    cli_run = sticky_lips.open_run(cli_out)
    assert slabs_run.frames.dtype == np.float64
    assert slabs_run.frames.shape == (41, cli_run.rest.shape[0], 3)
    assert np.array_equal(slabs_run.frames, cli_run.frames)
    assert np.array_equal(slabs_run.times, cli_run.times)
    assert np.array_equal(slabs_run.saliva.broken, cli_run.saliva.broken)
    # the summaries differ in wall times and threads only
    a, b = dict(slabs_run.summary), dict(cli_run.summary)
    for s in (a, b):
        for k in ("wall_time", "stepping_time", "element_updates_per_second", "threads"):
            s.pop(k)
    assert a == b


def test_frames_are_the_frame_files(slabs_run):
    """The arrays are the frame files' values: the displacement of the last frame against an
    independent reading of its base64 (the points are rest + displacement)."""
    import base64
    import xml.etree.ElementTree as ET

    def array(path: Path, name: str) -> np.ndarray:
        node = next(a for a in ET.parse(path).iter("DataArray") if a.get("Name") == name)
        raw = base64.b64decode("".join((node.text or "").split()))
        return np.frombuffer(raw[8:], dtype="<f8")

    last = slabs_run.frame_files[-1]
    assert last.name == "frame_000040.vtu"
    u = array(last, "displacement").reshape(-1, 3)
    assert np.array_equal(slabs_run.frames[-1], u)
    points = array(last, "Points").reshape(-1, 3)
    assert np.allclose(slabs_run.rest + u, points, rtol=0, atol=1e-15)
    # the first frame is at rest: its points are the rest positions exactly
    assert not slabs_run.frames[0].any()
    assert np.array_equal(array(slabs_run.frame_files[0], "Points").reshape(-1, 3), slabs_run.rest)
    assert slabs_run.cells.shape == (slabs_run.material.shape[0], 8)
    assert slabs_run.cells.max() == slabs_run.rest.shape[0] - 1


def test_saliva_state(slabs_run):
    """Every saliva element is whole at the start and broken at the end, and the broken
    count per frame is the summary's."""
    s = slabs_run.saliva
    assert s.elements.shape == (25,)
    assert s.broken.shape == s.moisture.shape == (41, 25)
    assert not s.broken[0].any() and s.broken[-1].all()
    assert list(s.broken.sum(axis=1)) == slabs_run.summary["broken_saliva"]
    # the breaking time is NaN until an element breaks, then fixed
    assert np.isnan(s.broken_at[0]).all() and np.isfinite(s.broken_at[-1]).all()
    assert (slabs_run.material[s.elements] == slabs_run.material[s.elements[0]]).all()
    assert slabs_run.measures is None  # two slabs have no lips
    assert slabs_run.interrupted is None


def test_progress_rises_to_the_end():
    """The callback sees the start, rising steps, and the end (every step, every frame)."""
    s = sticky_lips.Scenario(SLABS, overrides={"time.total": 0.05})
    seen: list[sticky_lips.Progress] = []
    run = s.run(threads=1, progress=seen.append)
    steps = s.check().steps
    assert steps == 5000
    assert seen[0].step == 0 and seen[0].seconds_left is None
    assert all(a.step < b.step for a, b in zip(seen, seen[1:]))
    # pieces of at most 512 steps, cut at the frames (every 1000 steps)
    assert all(b.step - a.step <= 512 for a, b in zip(seen, seen[1:]))
    last = seen[-1]
    assert (last.step, last.steps, last.fraction) == (steps, steps, 1.0)
    assert last.time == pytest.approx(0.05) and last.end_time == pytest.approx(0.05)
    assert last.frames == len(run.times) == 6


def test_check_matches_the_command_line(run_cli):
    """check() has the numbers `sticky-lips check` prints."""
    c = sticky_lips.Scenario(SLABS).check()
    text = run_cli("check", str(SLABS))
    m = re.search(r"nodes (\d+), hexahedra (\d+), materials (\d+)", text)
    assert (c.nodes, c.elements, c.materials) == tuple(int(g) for g in m.groups())
    m = re.search(
        r"critical time step 2/omega_max = (\S+) s \((\d+) Lanczos iterations\); "
        r"per-element estimate (\S+) s at element (\d+)",
        text,
    )
    # printed to 4 decimals in the mantissa
    assert float(m.group(1)) == float(f"{c.critical_time_step:.4e}")
    assert int(m.group(2)) == c.lanczos_iterations
    assert float(m.group(3)) == float(f"{c.element_estimate:.4e}")
    assert int(m.group(4)) == c.limiting_element
    m = re.search(r"critical time step of the tissue .* = (\S+) s", text)
    assert c.tissue_critical_time_step is not None
    assert float(m.group(1)) == float(f"{c.tissue_critical_time_step:.4e}")
    m = re.search(r"steps (\d+) of dt = (\S+) s", text)
    assert (c.steps, c.dt) == (int(m.group(1)), float(m.group(2)))
    assert c.saliva_elements == 25 and c.stable and "is stable" in text


def test_the_gil_is_released_while_stepping():
    """A Python thread doing pure-Python work finishes while a run (with no callback, so no
    Python code of ours runs meanwhile) is still stepping."""
    s = sticky_lips.Scenario(SLABS, overrides={"time.total": 0.6})
    done_at: list[float] = []

    def work() -> None:
        total = 0
        for k in range(2_000_000):
            total += k
        done_at.append(time.monotonic())

    t = threading.Thread(target=work)
    t0 = time.monotonic()
    t.start()
    run = s.run(threads=1)
    returned = time.monotonic()
    t.join()
    assert run.summary["steps"] == 60000
    # the work alone takes a fraction of the run; with the GIL held by the run it could only
    # finish after the run returned
    assert done_at[0] < returned, (done_at[0] - t0, returned - t0)


def test_scenario_from_toml_and_overrides():
    """A TOML string, a file, and overrides given either way make the same problem."""
    text = SLABS.read_text()
    a = sticky_lips.Scenario.from_toml(text, name=SLABS, overrides={"time.total": 0.1})
    b = sticky_lips.Scenario.from_file(SLABS).with_overrides({"time.total": 0.1})
    assert a.check() == b.check()
    assert a.check().steps == 10000
    # values of every TOML kind, NumPy's numbers among them
    c = b.with_overrides(
        {"numerics.damping": np.float64(40.0), "time.output_every": np.int64(500), "title": "x"}
    )
    assert (c.check().output_every, c.check().steps) == (500, 10000)
    assert "damping = 40.0" in c.text
    # with_dt keeps the frames' interval in seconds
    d = b.with_dt(5e-6)
    assert (d.check().dt, d.check().output_every) == (5e-6, 2000)
    assert sticky_lips.Scenario(SLABS).default_output is None


def test_an_out_of_none_is_a_temporary_directory():
    """out=None writes into a temporary directory that lives as long as the Run."""
    import gc

    run = sticky_lips.Scenario(SLABS, overrides={"time.total": 0.01}).run(threads=1)
    out = run.out
    assert (out / "summary.json").is_file() and run.frames.shape[0] == 2
    frames = run.frames
    del run
    gc.collect()
    assert not out.exists()
    assert frames.shape[0] == 2  # the arrays outlive the directory


def test_measures_of_a_model_with_lips(tmp_path, run_cli):
    """The quick face, shortened: the lip gap per column over time, as measures.json has it."""
    s = sticky_lips.Scenario.quick_face().with_overrides({"time.total": 0.02})
    run = s.run(tmp_path / "face", threads=2)
    m = run.measures
    raw = json.loads((run.out / "measures.json").read_text())
    assert m.gap.shape == (len(raw["frames"]), len(raw["columns"]["x"]))
    assert m.gap.shape[0] == len(run.times) and np.array_equal(m.times, run.times)
    assert m.gap[-1].tolist() == raw["frames"][-1]["gap"]
    # at rest the lips are closed
    assert not m.gap[0].any() and m.open_fraction[0] == 0.0
    assert list(m.broken) == run.summary["broken_saliva"]
