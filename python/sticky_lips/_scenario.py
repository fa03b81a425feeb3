"""Scenarios: what to run, read and checked (:class:`Scenario`), and their checks (:class:`Check`)."""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Tuple, Union

from . import _native
from ._run import Progress, Run
from .errors import InputError, RunInterrupted

PathLike = Union[str, "os.PathLike[str]"]

#: The name the quick face's scenario text stands for (its output directory is ``.``).
QUICK_FACE_NAME = "quick_face.toml"


@dataclass(frozen=True)
class Check:
    """A problem's mesh statistics, time settings and stability limits.

    What ``sticky-lips check`` prints, as numbers (lengths in m, volumes in m^3, times in s).
    """

    #: The input's name.
    source: str
    nodes: int
    #: Hexahedra, saliva elements included.
    elements: int
    #: Breaking saliva elements (0 for a model without saliva).
    saliva_elements: int
    materials: int
    bounding_box_min: Tuple[float, float, float]
    bounding_box_max: Tuple[float, float, float]
    total_volume: float
    min_element_volume: float
    max_element_volume: float
    #: Smallest ratio of minimum to maximum corner ``det J`` over the elements (1 for
    #: parallelepipeds).
    worst_jacobian_ratio: float
    #: The time step (for ``dt = "auto"``, the one chosen from the critical step).
    dt: float
    #: Steps of the whole run.
    steps: int
    total_time: float
    #: Steps between two frames.
    output_every: int
    #: Substeps of the saliva layer per step (1: none).
    subcycles: int
    #: ``2 / omega_max`` of ``M^-1 K`` (Lanczos): the limit a run's step is checked against.
    critical_time_step: float
    #: For a model with saliva, the critical step without the saliva's stiffness (the limit
    #: of a subcycled run's large step); else ``None``.
    tissue_critical_time_step: Optional[float]
    #: The smallest per-element estimate ``L_e / c_e`` and its element.
    element_estimate: float
    limiting_element: int
    lanczos_iterations: int

    @property
    def stable(self) -> bool:
        """Whether a run accepts the time step without ``force_dt``: ``dt`` within the
        critical step (with substeps: the substep within it, and the large step within the
        tissue's)."""
        if self.subcycles > 1:
            tissue = self.tissue_critical_time_step
            return self.dt / self.subcycles <= self.critical_time_step and (
                tissue is None or self.dt <= tissue
            )
        return self.dt <= self.critical_time_step


class Scenario:
    """A problem to run: a scenario (``.toml``) or a NiftySim model (``.xml``), read and
    checked when made, so that a bad input fails here with an :class:`InputError` naming
    the file and the line or field.

    ``Scenario(path, ...)`` is :meth:`from_file`. A scenario is immutable: the overrides and
    the time step give new ones.

    Examples:

    >>> import sticky_lips
    >>> s = sticky_lips.Scenario("examples/sticky_slabs.toml")
    >>> s.check().saliva_elements
    25
    >>> short = s.with_overrides({"time.total": 0.05})
    >>> run = short.run(threads=2)                   # doctest: +SKIP
    >>> run.frames.shape                             # doctest: +SKIP
    (6, 288, 3)
    """

    __slots__ = ("_problem", "_text", "_path", "_niftysim_compat")

    def __init__(
        self,
        path: PathLike,
        *,
        overrides: Optional[Mapping[str, Any]] = None,
        niftysim_compat: bool = False,
    ) -> None:
        text: Optional[str] = None
        p = os.fspath(path)
        if overrides:
            if Path(p).suffix.lower() != ".toml":
                raise InputError(
                    f"{p}: overrides apply to scenarios (.toml)",
                    file=p,
                    message="overrides apply to scenarios (.toml)",
                )
            text = _native.with_overrides(_native.read_text(p), p, _items(overrides))
            problem = _native.parse(text, p)
        else:
            problem = _native.load(p, niftysim_compat)
            if Path(p).suffix.lower() == ".toml":
                text = _native.read_text(p)
        self._init(problem, text, p, niftysim_compat)

    def _init(
        self, problem: _native.Problem, text: Optional[str], path: str, niftysim_compat: bool
    ) -> None:
        self._problem = problem
        self._text = text
        self._path = path
        self._niftysim_compat = niftysim_compat

    @classmethod
    def _of(cls, problem: _native.Problem, text: Optional[str], path: str) -> "Scenario":
        s = cls.__new__(cls)
        s._init(problem, text, path, False)
        return s

    @classmethod
    def from_file(
        cls,
        path: PathLike,
        *,
        overrides: Optional[Mapping[str, Any]] = None,
        niftysim_compat: bool = False,
    ) -> "Scenario":
        """The scenario or model in the file ``path``, read as its extension says.

        Args:
            path: a scenario (``.toml``) or a NiftySim model (``.xml``).
            overrides: dotted keys of the scenario set to new values before it is read
                (:meth:`with_overrides`); scenarios only.
            niftysim_compat: for a NiftySim model, reproduce NiftySim (centroid gradients
                and its timing), as ``--niftysim-compat`` does.

        Raises:
            FileNotFoundError: no such file.
            InputError: the file, or an override, is malformed or inconsistent.

        >>> s = Scenario.from_file("examples/cantilever.toml", overrides={"time.total": 0.01})
        >>> s.check().total_time
        0.01
        """
        return cls(path, overrides=overrides, niftysim_compat=niftysim_compat)

    @classmethod
    def from_toml(
        cls,
        text: str,
        *,
        name: PathLike = "<string>",
        overrides: Optional[Mapping[str, Any]] = None,
    ) -> "Scenario":
        """The scenario in ``text``, taken to be the file ``name``: errors name it, relative
        paths in the text (a mesh file) are read from its directory, and a run's summary
        gives it as its input.

        >>> text = open("examples/cantilever.toml").read()
        >>> Scenario.from_toml(text, name="examples/cantilever.toml").check().nodes
        625
        """
        p = os.fspath(name)
        if overrides:
            text = _native.with_overrides(text, p, _items(overrides))
        return cls._of(_native.parse(text, p), text, p)

    @classmethod
    def quick_face(cls, *, dt: Union[float, str, None] = None) -> "Scenario":
        """The default job: the sticky lips opening on the MakeHuman face at the quick
        resolution (the paper's run ``fig4_sticky``), what ``sticky-lips run`` runs with no
        input. The face is built into the package: nothing is read from disk. The text
        (:attr:`text`) stands for the file ``quick_face.toml``, which is not written: save it
        to run the same job with the command line.

        Args:
            dt: the time step, seconds or ``"auto"`` (the default: from the model's
                critical step).

        >>> s = sticky_lips.Scenario.quick_face()     # doctest: +SKIP
        >>> run = s.run()                            # doctest: +SKIP
        >>> run.measures.gap.shape                   # doctest: +SKIP
        (31, 41)
        """
        text = _native.quick_face_text(QUICK_FACE_NAME, dt)
        return cls._of(_native.parse(text, QUICK_FACE_NAME), text, QUICK_FACE_NAME)

    def with_overrides(self, overrides: Mapping[str, Any]) -> "Scenario":
        """This scenario with the dotted keys of ``overrides`` set (a key's tables are made
        where missing; an array's element is its index: ``"materials.0.mu"``).

        Values are converted to TOML: ``bool``, ``int``, ``float``, ``str`` (NumPy's
        numbers too), and lists and dicts of these; anything else is a ``TypeError``. The
        scenario is read again, so a bad value is an :class:`InputError` naming the field.

        Setting ``time.dt`` keeps ``output_every`` in steps; :meth:`with_dt` keeps the
        frames' interval in seconds instead.

        >>> s = Scenario("examples/sticky_slabs.toml")
        >>> s.with_overrides({"saliva.0.k_glue": 0.1, "time.total": 0.1}).check().steps
        10000
        """
        return self._rebuilt(lambda text: _native.with_overrides(text, self._path, _items(overrides)))

    def with_dt(self, dt: Union[float, str]) -> "Scenario":
        """This scenario at the time step ``dt`` (seconds, or ``"auto"``), with the frames'
        interval and the saliva's force decay (eq. 11) kept in seconds, as ``run --dt``.

        >>> Scenario("examples/sticky_slabs.toml").with_dt(5e-6).check().output_every
        2000
        """
        return self._rebuilt(lambda text: _native.with_dt(text, self._path, dt))

    def _rebuilt(self, change: Callable[[str], str]) -> "Scenario":
        if self._text is None:
            raise InputError(
                f"{self._path}: overrides and a new time step apply to scenarios (.toml)",
                file=self._path,
                message="overrides and a new time step apply to scenarios (.toml)",
            )
        text = change(self._text)
        return Scenario._of(_native.parse(text, self._path), text, self._path)

    @property
    def path(self) -> Path:
        """The file the scenario was read from (or stands for)."""
        return Path(self._path)

    @property
    def text(self) -> Optional[str]:
        """The scenario's TOML text, overrides applied (``None`` for a NiftySim model)."""
        return self._text

    @property
    def default_output(self) -> Optional[Path]:
        """The scenario's ``[output] dir``, relative to its directory (``None`` if it names
        none). :meth:`run` writes there only when given it as ``out``."""
        d = self._problem.default_output
        return None if d is None else Path(d)

    def check(self) -> Check:
        """The mesh statistics, time settings and stability limits (``sticky-lips check``).

        >>> c = Scenario("examples/cantilever.toml").check()
        >>> (c.nodes, c.elements, c.stable)
        (625, 384, True)
        """
        return Check(**_tuples(self._problem.check()))

    def run(
        self,
        out: Optional[PathLike] = None,
        *,
        precision: str = "f64",
        backend: str = "cpu",
        threads: Optional[int] = None,
        force_dt: bool = False,
        progress: Optional[Callable[[Progress], Any]] = None,
    ) -> Run:
        """Runs the problem and returns the :class:`Run`, its frames read as NumPy arrays.

        The stepping runs without the GIL (other Python threads go on), on ``threads``
        threads (default: every core; the result is the same bits for any count). The
        files written are those of ``sticky-lips run`` (frames, ``summary.json``,
        ``measures.json`` for a model with lips, the animation files for a face), with the
        same bytes.

        Args:
            out: the run's directory (made if missing; a previous run's files there are
                replaced). ``None``: a new temporary directory, removed when the returned
                ``Run`` is garbage collected (to keep the files, give ``out``).
            precision: ``"f64"`` or ``"f32"``.
            backend: ``"cpu"``, ``"gpu"`` or ``"auto"`` (the GPU where an adapter is found).
            threads: worker threads (at least 1).
            force_dt: run even if the time step is above the critical one.
            progress: called with a :class:`Progress` at the start, after every piece of at
                most 512 steps and at the end, on this thread. An exception it raises stops
                the run (as Ctrl-C does) and is raised here once the run has stopped; the
                partial run stays in ``out``.

        Raises:
            RunInterrupted: Ctrl-C (``KeyboardInterrupt``) stopped the run between two steps;
                its ``run`` is the partial run (complete frames, ``summary.json`` marked
                interrupted).
            UnstableTimeStepError: the step is above the critical one (without ``force_dt``).
            DivergedError: the run diverged.
            InputError, OSError: the output directory cannot be written, ...

        >>> s = Scenario("examples/sticky_slabs.toml", overrides={"time.total": 0.02})
        >>> seen = []
        >>> run = s.run(threads=1, progress=lambda p: seen.append(p.step))
        >>> seen[-1] == s.check().steps, run.frames.shape
        (True, (3, 288, 3))
        """
        keep: Optional[tempfile.TemporaryDirectory[str]] = None
        if out is None:
            keep = tempfile.TemporaryDirectory(prefix="sticky-lips-run-")
            out = keep.name
        out = os.fspath(out)
        hook = None if progress is None else _progress_hook(progress)
        try:
            self._problem.run(out, precision, backend, threads, force_dt, hook)
        except RunInterrupted as e:
            e.run = Run(out, _keep=keep)
            raise
        return Run(out, _keep=keep)

    def __repr__(self) -> str:
        return f"Scenario({self._path!r})"


def _items(overrides: Mapping[str, Any]) -> List[Tuple[str, Any]]:
    if not isinstance(overrides, Mapping):
        raise TypeError(f"overrides: a mapping of dotted keys to values, not {type(overrides).__name__}")
    return [(str(k), v) for k, v in overrides.items()]


def _tuples(d: Dict[str, Any]) -> Dict[str, Any]:
    return {k: tuple(v) if isinstance(v, list) else v for k, v in d.items()}


def _progress_hook(progress: Callable[[Progress], Any]) -> Callable[[Dict[str, Any]], None]:
    def hook(update: Dict[str, Any]) -> None:
        progress(Progress(**update))

    return hook
