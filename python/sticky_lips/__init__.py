"""sticky-lips from Python: the TLED solver of "Physically-based Sticky Lips" (Leach &
Maddock) with NumPy arrays in and out.

- :class:`Scenario`: what to run, from a file, a TOML string, or either with overrides;
  :meth:`Scenario.quick_face` is the default job (the MakeHuman face, quick resolution).
- :meth:`Scenario.check`: mesh statistics and the critical time step (:class:`Check`).
- :meth:`Scenario.run`: runs it without the GIL, with a progress callback, stopped cleanly
  by Ctrl-C; returns a :class:`Run`, whose frames, saliva state, lip measures and summary are
  NumPy arrays and dicts. :func:`open_run` reads a run's directory again.
- :func:`face`: a user's head (OBJ) to a runnable model.
- Errors are :mod:`sticky_lips.errors`' exceptions, naming the file and the line or field.

The lip gap of the quick face over time:

>>> import sticky_lips                                              # doctest: +SKIP
>>> run = sticky_lips.Scenario.quick_face().run()                   # doctest: +SKIP
>>> m = run.measures                                                # doctest: +SKIP
>>> m.gap.max(axis=1)[-1] > m.open_threshold                        # doctest: +SKIP
True
"""

from __future__ import annotations

try:
    from . import _native  # noqa: F401
except ImportError as e:  # pragma: no cover
    raise ImportError(
        f"sticky_lips: no native module beside {__file__}: this looks like the sources "
        "(python/sticky_lips) rather than the installed package; install it with "
        "`pip install ./python` and import it from another directory"
    ) from e

from ._face import FaceModel, face
from ._native import VERSION as __version__
from ._run import Measures, Progress, Run, Saliva, open_run
from ._scenario import Check, Scenario
from .errors import (
    DivergedError,
    GpuError,
    InputError,
    RunInterrupted,
    SimulationError,
    StickyLipsError,
    UnstableTimeStepError,
)

__all__ = [
    "Check",
    "DivergedError",
    "FaceModel",
    "GpuError",
    "InputError",
    "Measures",
    "Progress",
    "Run",
    "RunInterrupted",
    "Saliva",
    "Scenario",
    "SimulationError",
    "StickyLipsError",
    "UnstableTimeStepError",
    "__version__",
    "face",
    "open_run",
]
