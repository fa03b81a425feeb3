"""A user's head to a runnable model (:func:`face`, as ``sticky-lips face``)."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import List, Optional, Sequence, Union

from . import _native
from ._scenario import Scenario

PathLike = Union[str, "os.PathLike[str]"]


@dataclass(frozen=True)
class FaceModel:
    """What :func:`face` made: the model's directory and what the pipeline decided."""

    #: The model's directory: ``scenario.toml``, ``mesh.vtu``, ``model.xml``, ``groups.png``,
    #: the cropped face and head (OBJ, JSON).
    out: Path
    #: The unit detected from the head's size (``"mm"``, ...), when ``units="auto"``.
    detected_unit: Optional[str]
    #: What the pipeline decided on the way (axes detected, folds trimmed, ...).
    notes: List[str] = field(default_factory=list)
    #: Wall time (s).
    seconds: float = 0.0

    @property
    def scenario_path(self) -> Path:
        """The model's scenario: Table 1, the wide jaw opening with stickiness."""
        return self.out / "scenario.toml"

    def scenario(self) -> Scenario:
        """The model's scenario, read (it writes its run into ``out/run`` when given that as
        ``out``; :meth:`Scenario.run` uses a temporary directory otherwise)."""
        return Scenario.from_file(self.scenario_path)


def _axis(v: Optional[Sequence[float]], name: str) -> str:
    if v is None:
        return "auto"
    xs = [float(c) for c in v]
    if len(xs) != 3:
        raise ValueError(f"{name}: three components, got {len(xs)}")
    return ",".join(repr(c) for c in xs)


def face(
    input: PathLike,
    out: PathLike,
    *,
    rig: Optional[PathLike] = None,
    units: str = "auto",
    up: Optional[Sequence[float]] = None,
    forward: Optional[Sequence[float]] = None,
    params: Optional[PathLike] = None,
    resolution: float = 1.0,
) -> FaceModel:
    """Builds the model of the head in ``input`` (OBJ) into the directory ``out``, as
    ``sticky-lips face`` does: the head read and checked, its units and axes detected or
    taken as given, the lips found, the hexahedral model built, and its files and a scenario
    that runs on it written together (a refusal or Ctrl-C leaves nothing in ``out``).

    Args:
        input: the head, a triangle or quad mesh (OBJ).
        out: the model's directory.
        rig: a rig (JSON): named lips, jaw weights, blend-shape targets.
        units: the head's length unit (``"m"``, ``"dm"``, ``"cm"``, ``"mm"``, ``"in"``) or
            ``"auto"`` (from its size).
        up, forward: the head's up and forward axes, both given or both ``None`` (detected).
        params: the crop parameters (TOML).
        resolution: the model's resolution (1: the paper's; 0.25 builds quickly).

    Raises:
        InputError: the head or a parameter is refused; its ``field`` names the command
            line's option (``--units``, ``--up``, ...), as the library reports it.
        KeyboardInterrupt: Ctrl-C stopped the build (nothing written).

    >>> m = sticky_lips.face("head.obj", "out/head", resolution=0.25)   # doctest: +SKIP
    >>> run = m.scenario().run(m.out / "run")                          # doctest: +SKIP
    """
    report = _native.face(
        os.fspath(input),
        os.fspath(out),
        rig=None if rig is None else os.fspath(rig),
        units=units,
        up=_axis(up, "up"),
        forward=_axis(forward, "forward"),
        params=None if params is None else os.fspath(params),
        resolution=float(resolution),
    )
    return FaceModel(
        out=Path(os.fspath(out)),
        detected_unit=report["detected_unit"],
        notes=list(report["notes"]),
        seconds=float(report["seconds"]),
    )
