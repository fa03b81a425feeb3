"""Stopping a run: Ctrl-C (a real SIGINT) and a progress callback that raises both stop it
between two steps, leave its complete frames and a summary marked interrupted, and raise."""

from __future__ import annotations

import os
import signal
import threading
from pathlib import Path

import numpy as np
import pytest

import sticky_lips

REPO = Path(__file__).resolve().parents[2]
SLABS = REPO / "examples" / "sticky_slabs.toml"
# 2 million steps: minutes of stepping, stopped within the first seconds
LONG = {"time.total": 20.0}


def test_sigint_stops_a_run_cleanly(tmp_path):
    """SIGINT sent to the process from another thread while the run steps without the GIL
    and without a callback (so that only the package's own look at the signals can see it):
    KeyboardInterrupt (RunInterrupted), and the partial run is readable."""
    out = tmp_path / "stopped"
    s = sticky_lips.Scenario(SLABS, overrides=LONG)
    steps = s.check().steps
    timer = threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt) as caught:
            s.run(out, threads=1)
    finally:
        timer.cancel()
    e = caught.value
    assert isinstance(e, sticky_lips.RunInterrupted)
    assert e.out == str(out) and 0 < e.step < steps
    assert isinstance(e.__cause__, KeyboardInterrupt)
    run = sticky_lips.open_run(out)
    assert run.interrupted == {"step": e.step, "time": e.time}
    assert e.run is not None and e.run.out == out
    assert run.summary["steps"] == e.step
    # complete frames: every one listed is read back, and they are the frames of the same
    # run left alone (the slabs' first 0.05 s)
    assert len(run.times) == run.summary["frames"] >= 1
    short = sticky_lips.Scenario(SLABS, overrides={"time.total": 0.05}).run(threads=1)
    k = min(len(run.times), len(short.times))
    assert np.array_equal(run.frames[:k], short.frames[:k])
    assert np.array_equal(run.times[:k], short.times[:k])


def test_a_raising_callback_stops_the_run(tmp_path):
    """The callback's own exception arrives, after the run has stopped and written its
    frames; a KeyboardInterrupt raised in the callback is Ctrl-C's."""
    out = tmp_path / "raised"
    s = sticky_lips.Scenario(SLABS, overrides=LONG)

    class Enough(Exception):
        pass

    def progress(p: sticky_lips.Progress) -> None:
        if p.step >= 3000:
            raise Enough(p.step)

    with pytest.raises(Enough):
        s.run(out, threads=1, progress=progress)
    run = sticky_lips.open_run(out)
    assert run.interrupted is not None
    assert 3000 <= run.interrupted["step"] < s.check().steps
    assert len(run.times) >= 4  # frames at 0, 1000, 2000 and 3000 steps at least

    def ctrl_c(p: sticky_lips.Progress) -> None:
        if p.step >= 1000:
            raise KeyboardInterrupt

    with pytest.raises(sticky_lips.RunInterrupted) as caught:
        s.run(out, threads=1, progress=ctrl_c)
    assert caught.value.run.interrupted["step"] >= 1000


def test_an_interrupted_temporary_run_stays_readable():
    """With out=None the partial run lives as long as the exception's `run`."""
    s = sticky_lips.Scenario(SLABS, overrides=LONG)

    def ctrl_c(p: sticky_lips.Progress) -> None:
        if p.step >= 2000:
            raise KeyboardInterrupt

    with pytest.raises(sticky_lips.RunInterrupted) as caught:
        s.run(threads=1, progress=ctrl_c)
    run = caught.value.run
    assert run.out.is_dir() and run.frames.shape[0] >= 3
