"""The exceptions of ``sticky_lips``.

Every error of the library arrives as one of these (or as an ``OSError``), with what the
library knows about it as attributes:

======================================  ===============================================
The library's error                     Python exception
======================================  ===============================================
malformed or inconsistent input         :class:`InputError` (a ``ValueError``):
                                        ``file``, ``line``, ``field``, ``message``
a file that cannot be read or written   ``OSError``, its subclass for the errno
                                        (``FileNotFoundError``, ``PermissionError``,
                                        ...), ``filename`` set
time step above the critical one        :class:`UnstableTimeStepError`
run diverged                            :class:`DivergedError`
static solver did not converge          :class:`SimulationError`
GPU backend unavailable or failed       :class:`GpuError` (a ``RuntimeError``)
run stopped by Ctrl-C                   :class:`RunInterrupted` (a ``KeyboardInterrupt``)
face build stopped by Ctrl-C            ``KeyboardInterrupt``
======================================  ===============================================

Wrong Python arguments (an unknown precision, a value with no TOML equivalent) are
``ValueError`` and ``TypeError`` as usual.

>>> import sticky_lips
>>> try:
...     sticky_lips.Scenario("examples/cantilever.toml", overrides={"time.dt": -1.0})
... except sticky_lips.InputError as e:
...     print(e.file, e.field, e.message, sep=" | ")
examples/cantilever.toml | time.dt | time step must be positive, got -1
>>> try:
...     sticky_lips.Scenario("examples/nowhere.toml")
... except FileNotFoundError as e:
...     print(e.filename)
examples/nowhere.toml
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Optional

if TYPE_CHECKING:  # pragma: no cover
    from ._run import Run

__all__ = [
    "StickyLipsError",
    "InputError",
    "SimulationError",
    "UnstableTimeStepError",
    "DivergedError",
    "GpuError",
    "RunInterrupted",
]


class StickyLipsError(Exception):
    """Base class of the package's own errors (not of ``OSError`` or ``RunInterrupted``)."""


class InputError(StickyLipsError, ValueError):
    """Malformed or inconsistent input: a scenario, a model, an override, a run directory.

    ``str(e)`` is the whole message as the command line prints it
    (``FILE:LINE: field `FIELD`: MESSAGE``); the parts are attributes.

    Attributes:
        file: the file (or the command-line option, for a job's own values) at fault.
        line: its line (1-based), where the error has one, else ``None``.
        field: the dotted field at fault (``time.dt``, ``materials[0].mu``), else ``None``.
        message: what is wrong, without the file and the place.
    """

    def __init__(
        self,
        text: str,
        *,
        file: Optional[str] = None,
        line: Optional[int] = None,
        field: Optional[str] = None,
        message: Optional[str] = None,
    ) -> None:
        super().__init__(text)
        self.file = file
        self.line = line
        self.field = field
        self.message = text if message is None else message


class SimulationError(StickyLipsError, RuntimeError):
    """A run or a static solve that did not succeed (the static solver did not converge)."""


class UnstableTimeStepError(SimulationError):
    """The time step is above the critical one: the run refuses it before the first step.

    Give a smaller ``dt`` (or ``dt = "auto"``), or run anyway with ``force_dt=True``.

    Attributes:
        dt: the step asked for (s).
        critical_time_step: the limit (s): ``2 / omega_max``, or for a run with saliva
            substeps the tissue's limit of its large step.
        element: the element whose own estimate is smallest (``None`` for a subcycled run).
        subcycles: substeps of the saliva layer per step (1 without subcycling).
    """

    def __init__(
        self,
        text: str,
        *,
        dt: float,
        critical_time_step: float,
        element: Optional[int],
        subcycles: int,
    ) -> None:
        super().__init__(text)
        self.dt = dt
        self.critical_time_step = critical_time_step
        self.element = element
        self.subcycles = subcycles


class DivergedError(SimulationError):
    """The run diverged (an inverted element, a non-finite value); nothing after it written.

    Attributes:
        step: the step at which it was found.
        time: its simulated time (s).
        element: the element at fault, where known.
        node: the node at fault, where known.
    """

    def __init__(
        self,
        text: str,
        *,
        step: int,
        time: float,
        element: Optional[int],
        node: Optional[int],
    ) -> None:
        super().__init__(text)
        self.step = step
        self.time = time
        self.element = element
        self.node = node


class GpuError(StickyLipsError, RuntimeError):
    """The GPU backend is unavailable (no adapter, no f64 support) or failed."""


class RunInterrupted(KeyboardInterrupt):
    """A run stopped by Ctrl-C (``KeyboardInterrupt``) between two steps.

    The frames written before it are complete and listed in ``frames.pvd``, and
    ``summary.json`` says where the run stopped (``summary["interrupted"]``): the partial run
    is read with :func:`sticky_lips.open_run` (``open_run(e.out)``), or is ``e.run`` when
    raised by :meth:`sticky_lips.Scenario.run` (which keeps a temporary output directory
    alive through it). A ``KeyboardInterrupt``, so that an ``except Exception`` does not
    swallow Ctrl-C; the original one is its ``__cause__``.

    Attributes:
        out: the run's directory.
        step: the steps taken.
        time: the simulated time reached (s).
        run: the partial :class:`sticky_lips.Run` (``None`` until ``Scenario.run`` sets it).
    """

    def __init__(self, text: str, *, out: Optional[str], step: int, time: float) -> None:
        super().__init__(text)
        self.out = out
        self.step = step
        self.time = time
        self.run: Optional["Run"] = None
