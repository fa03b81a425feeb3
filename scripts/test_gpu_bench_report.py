"""Tests of scripts/gpu_bench_report.py on criterion result trees written here.

    .venv/bin/python -m pytest -q scripts/test_gpu_bench_report.py
"""

import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
import gpu_bench_report as rep  # noqa: E402


def put(root: Path, group: str, function: str, value: str, elements: int, ns: float):
    """One criterion result as criterion 0.8 lays it out (only the fields the script reads)."""
    d = root / group / function / value / "new"
    d.mkdir(parents=True)
    (d / "benchmark.json").write_text(json.dumps({
        "group_id": group, "function_id": function, "value_str": value,
        "throughput": {"Elements": elements},
    }))
    (d / "estimates.json").write_text(json.dumps({
        "median": {"point_estimate": ns,
                   "confidence_interval": {"lower_bound": 0.9 * ns, "upper_bound": 1.1 * ns}},
    }))


def scene(d: Path, steps: int, stepping: float):
    d.mkdir(parents=True)
    (d / "summary.json").write_text(json.dumps({
        "steps": steps, "stepping_time": stepping, "wall_time": stepping + 0.5,
        "backend": "gpu: test", "precision": "f32",
    }))


def report(root: Path, *extra: str) -> str:
    import io
    from contextlib import redirect_stdout
    buf = io.StringIO()
    with redirect_stdout(buf):
        assert rep.main([str(root), "--cpu-threads", "2", *extra]) == 0
    return buf.getvalue()


def test_targets_met(tmp_path):
    put(tmp_path, "step", "gpu-f32", "hex=mouth", 3420, 8_000.0)  # 8 us a step
    put(tmp_path, "step", "cpu-f32", "hex=mouth", 3420, 200_000.0)  # 25x
    put(tmp_path, "step", "gpu-f32", "hex=512000", 512_000, 400_000.0)  # 1.28e9 /s
    put(tmp_path, "step", "cpu-f32", "hex=512000", 512_000, 10_000_000.0)  # 25x
    scene(tmp_path / "scene", 100_000, 0.9)
    out = report(tmp_path, "--scene", str(tmp_path / "scene"))
    assert "1. paper's scene in real time (<= 1 s for 100000 steps): met" in out
    assert "x 100000 = 0.8 s" in out
    assert "stepping_time 0.900 s" in out and "(<= 1 s stepping)" in out
    assert "element-updates/s at 512k hexahedra: met" in out
    assert "1.28 G element-updates/s" in out
    assert "every size and precision: met" in out
    assert "`hex=mouth` f32: GPU 25x the CPU" in out
    # steps per second only for full steps: 1 / 8 us
    assert "| `step/gpu-f32/hex=mouth` | 8 us [7.2 us, 8.8 us] | 428 M | 125 k |" in out


def test_each_target_can_fail(tmp_path):
    put(tmp_path, "step", "gpu-f32", "hex=mouth", 3420, 10_500.0)  # 1.05 s for the scene
    put(tmp_path, "step", "cpu-f32", "hex=mouth", 3420, 200_000.0)  # 19x: misses 20x
    put(tmp_path, "step", "gpu-f32", "hex=512000", 512_000, 600_000.0)  # 0.85e9 /s
    put(tmp_path, "step", "cpu-f32", "hex=512000", 512_000, 100_000_000.0)
    scene(tmp_path / "scene", 100_000, 1.2)
    out = report(tmp_path, "--scene", str(tmp_path / "scene"))
    assert "100000 steps): NOT met" in out
    assert "(> 1 s stepping)" in out
    assert "at 512k hexahedra: NOT met" in out
    assert "every size and precision: NOT met" in out  # one size short is enough


def test_missing_figures_are_not_measured(tmp_path):
    # only a host id and a tled.rs result (a different layout the script must ignore)
    put(tmp_path, "host", "gpu-f32", "hex=mouth", 3420, 3_000.0)
    put(tmp_path, "step", "f64_threads=2", "hex=8000", 8000, 300_000.0)
    scene(tmp_path / "cut", 4_000, 0.1)  # a run stopped by its time limit
    out = report(tmp_path, "--scene", str(tmp_path / "cut"), "--scene", str(tmp_path / "absent"))
    assert out.count("not measured") == 3
    assert "absent: no summary.json (the run did not finish)" in out
    assert "f64_threads" not in out
    assert "4000 steps, not the scene's 100000" in out


def test_bad_result_names_the_file(tmp_path):
    put(tmp_path, "step", "gpu-f32", "hex=1000", 1000, 1.0)
    bad = tmp_path / "step" / "gpu-f32" / "hex=1000" / "new" / "estimates.json"
    bad.write_text("{not json")
    with pytest.raises(SystemExit, match="hex=1000/new: unreadable criterion result"):
        rep.main([str(tmp_path)])


def test_no_results_is_an_error(tmp_path):
    assert rep.main([str(tmp_path / "absent")]) == 2
    assert rep.main([str(tmp_path)]) == 2
