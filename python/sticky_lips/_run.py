"""A run directory read into NumPy arrays (:class:`Run`, :func:`open_run`), and what a run
reports while it goes (:class:`Progress`)."""

from __future__ import annotations

import json
import os
import tempfile
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np

from . import _native

PathLike = Union[str, "os.PathLike[str]"]


@dataclass(frozen=True)
class Progress:
    """Where a running run is, as handed to a progress callback."""

    #: Steps taken.
    step: int
    #: Steps of the whole run.
    steps: int
    #: Simulated time reached (s).
    time: float
    #: Simulated time at the end of the run (s).
    end_time: float
    #: Frames handed to the writer so far.
    frames: int
    #: Wall time of the stepping so far (s).
    elapsed: float
    #: Estimated wall time to the end (s); ``None`` before the first piece of stepping.
    seconds_left: Optional[float]

    @property
    def fraction(self) -> float:
        """``step / steps`` (1 for a run without steps)."""
        return 1.0 if self.steps == 0 else self.step / self.steps


@dataclass(frozen=True)
class Saliva:
    """The breaking saliva elements' state at every frame (``S`` elements, ``F`` frames), as
    the frame files hold it (paper section 3.4)."""

    #: The saliva elements' indices among the cells, shape ``(S,)``.
    elements: np.ndarray
    #: Whether each is broken, shape ``(F, S)`` (bool).
    broken: np.ndarray
    #: Moisture ``M`` (um), shape ``(F, S)``.
    moisture: np.ndarray
    #: Breaking point ``Z`` (eq. 7), shape ``(F, S)``.
    breaking_point: np.ndarray
    #: Stretch across the layer ``Q``, shape ``(F, S)``.
    stretch: np.ndarray
    #: Time at which each first broke (s), NaN while it has not, shape ``(F, S)``.
    broken_at: np.ndarray


@dataclass(frozen=True)
class Measures:
    """The lip measures of a run of a model with lips (``measures.json``), per frame:
    ``F`` frames, ``C`` columns along the mouth's width."""

    #: Time of each frame (s), shape ``(F,)``.
    times: np.ndarray
    #: x of each column along the mouth's width (m), shape ``(C,)``, sorted.
    x: np.ndarray
    #: The x of the mouth's centre line (m).
    center: float
    #: The node on the upper and on the lower lip of each column, shapes ``(C,)``.
    upper_nodes: np.ndarray
    lower_nodes: np.ndarray
    #: Lip gap at each column (m): the distance between its two nodes less the distance at
    #: rest (0 for closed lips), shape ``(F, C)``.
    gap: np.ndarray
    #: The fraction of the mouth's width that is open (gap above ``open_threshold``),
    #: shape ``(F,)``.
    open_fraction: np.ndarray
    #: Broken saliva elements, shape ``(F,)``.
    broken: np.ndarray
    #: Left/right asymmetry of the opening, shape ``(F,)``.
    asymmetry: np.ndarray
    #: Gap above which a column counts as open (m).
    open_threshold: float
    #: ``(time, x)`` of the first column to open, ``None`` if none did.
    first_opening: Optional[Tuple[float, float]]

    @classmethod
    def _from_json(cls, m: Dict[str, Any]) -> "Measures":
        frames = m["frames"]
        cols = m["columns"]
        first = m.get("first_opening")
        return cls(
            times=np.array([f["time"] for f in frames], dtype=float),
            x=np.array(cols["x"], dtype=float),
            center=float(cols["center"]),
            upper_nodes=np.array(cols["upper"], dtype=np.int64),
            lower_nodes=np.array(cols["lower"], dtype=np.int64),
            gap=np.array([f["gap"] for f in frames], dtype=float).reshape(len(frames), len(cols["x"])),
            open_fraction=np.array([f["open_fraction"] for f in frames], dtype=float),
            broken=np.array([f["broken"] for f in frames], dtype=np.int64),
            asymmetry=np.array([f["asymmetry"] for f in frames], dtype=float),
            open_threshold=float(m["open_threshold"]),
            first_opening=None if first is None else (float(first[0]), float(first[1])),
        )


class Run:
    """A run's directory, finished or interrupted, read into NumPy arrays (``F`` frames,
    ``N`` nodes, ``E`` elements). Made by :meth:`Scenario.run` and :func:`open_run`.

    The arrays are read from the files when first asked for, then kept. They are those of the
    complete frames listed in ``frames.pvd``: for an interrupted run, the frames written
    before it stopped (``interrupted`` says where).

    >>> run = sticky_lips.open_run("out/sticky_slabs")          # doctest: +SKIP
    >>> run.frames.shape, run.times[-1]                         # doctest: +SKIP
    ((41, 288, 3), 0.4)
    >>> deformed = run.rest + run.frames[-1]                    # doctest: +SKIP
    """

    def __init__(
        self, out: PathLike, *, _keep: Optional["tempfile.TemporaryDirectory[str]"] = None
    ) -> None:
        self._out = Path(os.fspath(out))
        # a temporary output directory lives as long as this object
        self._keep = _keep
        # read now: a directory that is not a run fails here
        self._summary: Dict[str, Any] = json.loads(_native.read_summary(os.fspath(self._out)))

    @property
    def out(self) -> Path:
        """The run's directory."""
        return self._out

    @property
    def summary(self) -> Dict[str, Any]:
        """``summary.json``: steps, simulated time, wall time, precision, backend, the
        stability report, the energies per frame, broken saliva counts, ..."""
        return self._summary

    @property
    def interrupted(self) -> Optional[Dict[str, Any]]:
        """``{"step": ..., "time": ...}`` where an interrupted run stopped, else ``None``."""
        return self._summary.get("interrupted")

    @cached_property
    def _data(self) -> Dict[str, Any]:
        return _native.read_frames(os.fspath(self._out))

    @property
    def times(self) -> np.ndarray:
        """Simulated time of each frame (s), shape ``(F,)``."""
        return self._data["times"]

    @property
    def frames(self) -> np.ndarray:
        """Node displacements at each frame (m), shape ``(F, N, 3)``, float64 (the values of
        the frame files: an f32 run's displacements are widened)."""
        return self._data["displacement"]

    @property
    def rest(self) -> np.ndarray:
        """Node positions at rest (m), shape ``(N, 3)``; ``rest + frames[k]`` is frame ``k``'s
        deformed mesh."""
        return self._data["rest"]

    @property
    def cells(self) -> np.ndarray:
        """The hexahedra's nodes (VTK order), shape ``(E, 8)``, int64."""
        return self._data["cells"]

    @property
    def material(self) -> np.ndarray:
        """Each element's material index, shape ``(E,)``, int32."""
        return self._data["material"]

    @property
    def frame_files(self) -> List[Path]:
        """The frame files (``frame_NNNNNN.vtu``), in order."""
        return [self._out / f for f in self._data["files"]]

    @property
    def saliva(self) -> Optional[Saliva]:
        """The saliva elements' state per frame, ``None`` for a model without saliva."""
        d = self._data
        if "saliva_elements" not in d:
            return None
        return Saliva(
            elements=d["saliva_elements"],
            broken=d["saliva_broken"],
            moisture=d["saliva_moisture"],
            breaking_point=d["saliva_Z"],
            stretch=d["saliva_Q"],
            broken_at=d["saliva_broken_at"],
        )

    @cached_property
    def measures(self) -> Optional[Measures]:
        """The lip measures (lip gap per column over time, open fraction, ...), ``None`` for a
        model without lips."""
        text = _native.read_measures(os.fspath(self._out))
        return None if text is None else Measures._from_json(json.loads(text))

    def __repr__(self) -> str:
        state = "interrupted" if self.interrupted else "finished"
        return f"<Run {str(self._out)!r}: {self._summary.get('frames')} frames, {state}>"


def open_run(out: PathLike) -> Run:
    """The run in the directory ``out``, finished or interrupted (its complete frames).

    Raises:
        FileNotFoundError: ``out`` has no ``summary.json``.
        InputError: its ``summary.json`` or a frame file is malformed (names the file).

    >>> run = sticky_lips.open_run("out/sticky_slabs")             # doctest: +SKIP
    >>> run.saliva.broken[-1].all()                                # doctest: +SKIP
    True
    """
    return Run(out)
