"""Errors arrive as Python exceptions naming the file and the line or field."""

from __future__ import annotations

from pathlib import Path

import pytest

import sticky_lips

REPO = Path(__file__).resolve().parents[2]
SLABS = REPO / "examples" / "sticky_slabs.toml"


def test_a_bad_field_names_the_file_and_the_field(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(SLABS.read_text().replace("mu = 800.0", "mu = -800.0", 1))
    with pytest.raises(sticky_lips.InputError) as caught:
        sticky_lips.Scenario(bad)
    e = caught.value
    assert isinstance(e, ValueError)
    assert e.file == str(bad)
    assert e.field is not None and "mu" in e.field
    assert e.message in str(e) and str(bad) in str(e)


def test_a_syntax_error_names_the_line(tmp_path):
    bad = tmp_path / "broken.toml"
    lines = SLABS.read_text().splitlines()
    lines[20] = "size = [10.0, 10.0"  # an unclosed array on line 21
    bad.write_text("\n".join(lines))
    with pytest.raises(sticky_lips.InputError) as caught:
        sticky_lips.Scenario(bad)
    assert caught.value.file == str(bad)
    assert caught.value.line is not None and caught.value.line >= 21


def test_an_unknown_field_names_the_file(tmp_path):
    with pytest.raises(sticky_lips.InputError) as caught:
        sticky_lips.Scenario.from_toml(
            SLABS.read_text() + "\n[time2]\nx = 1\n", name=tmp_path / "extra.toml"
        )
    assert caught.value.file == str(tmp_path / "extra.toml")
    assert "time2" in caught.value.message


def test_an_override_is_checked_like_the_file():
    with pytest.raises(sticky_lips.InputError) as caught:
        sticky_lips.Scenario(SLABS, overrides={"time.dt": -1e-5})
    assert caught.value.file == str(SLABS)
    assert caught.value.field == "time.dt"
    with pytest.raises(TypeError, match="time.dt"):
        sticky_lips.Scenario(SLABS, overrides={"time.dt": None})
    with pytest.raises(TypeError, match="mapping"):
        sticky_lips.Scenario(SLABS).with_overrides([("time.dt", 1e-5)])


def test_a_missing_file_is_file_not_found(tmp_path):
    missing = tmp_path / "nowhere.toml"
    with pytest.raises(FileNotFoundError) as caught:
        sticky_lips.Scenario(missing)
    assert caught.value.filename == str(missing)
    with pytest.raises(FileNotFoundError):
        sticky_lips.open_run(tmp_path)
    with pytest.raises(FileNotFoundError):
        sticky_lips.face(tmp_path / "head.obj", tmp_path / "model")


def test_a_time_step_above_the_critical_one_is_refused(tmp_path):
    s = sticky_lips.Scenario(SLABS, overrides={"time.dt": 1e-3})
    with pytest.raises(sticky_lips.UnstableTimeStepError) as caught:
        s.run(tmp_path / "unstable", threads=1)
    e = caught.value
    assert isinstance(e, sticky_lips.SimulationError) and isinstance(e, RuntimeError)
    assert e.dt == 1e-3 and e.critical_time_step < 1e-3 and e.subcycles == 1
    assert e.critical_time_step == s.check().critical_time_step


def test_bad_arguments_are_value_errors(tmp_path):
    s = sticky_lips.Scenario(SLABS)
    with pytest.raises(ValueError, match="precision"):
        s.run(tmp_path / "p", precision="f16")
    with pytest.raises(ValueError, match="threads"):
        s.run(tmp_path / "t", threads=0)
    with pytest.raises(ValueError, match="dt"):
        s.with_dt(-1.0)
    with pytest.raises(sticky_lips.InputError) as caught:
        sticky_lips.face(tmp_path / "head.obj", tmp_path / "model", units="furlong")
    assert caught.value.field == "--units"


def test_a_malformed_run_directory_names_the_file(tmp_path):
    (tmp_path / "summary.json").write_text("{\n  \"steps\": \n")
    with pytest.raises(sticky_lips.InputError) as caught:
        sticky_lips.open_run(tmp_path)
    assert caught.value.file == str(tmp_path / "summary.json")
    assert caught.value.line == 3
