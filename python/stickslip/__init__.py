"""stickslip: junction (bond) friction, the Filippov-Klafter-Urbakh model, from Python.

The simulator is the Rust crate ``stickslip`` (exact event-driven kinetic Monte Carlo and
the letter's fixed-step scheme); this package binds it with PyO3:

- :class:`Scene` -- a validated scene, from a TOML file or text, with overrides;
- :func:`run` -- one run, the same files as ``stickslip run`` (byte for byte) and the
  summary as a dict, the trace and events as pandas DataFrames (numpy record arrays
  without pandas);
- :func:`sweep` -- a parameter sweep on Dask distributed (a LocalCluster when no client is
  given), the same seeds and the same ``sweep.csv`` table as ``stickslip sweep``;
- :func:`fit` -- calibration: scene fields fitted to a measured friction curve, with 95 %
  intervals, its evaluations on Dask distributed, the files of ``stickslip fit``;
- :func:`friction_law` -- a map over ``plate.v`` and ``junctions.temperature`` as a friction
  law for continuum codes, the files of ``stickslip friction-law``.

Bad input raises ``ValueError`` with the command line's one-line message; a run that fails
(numerical trouble) raises ``RuntimeError``. Overrides are ``section.key=value`` fields,
given as keyword arguments with ``__`` for the dot (``plate__v=0.5``) or as a dict
(``**{"plate.v": 0.5}``).
"""

from ._stickslip import Scene, __version__
from ._run import Result, StabilityWarning, load, run
from ._sweep import SweepResult, log_range, linear_range, run_sweep, sweep
from ._law import FrictionLawResult, friction_law
from ._fit import FitResult, fit

__all__ = [
    "Scene",
    "Result",
    "StabilityWarning",
    "SweepResult",
    "FrictionLawResult",
    "FitResult",
    "fit",
    "friction_law",
    "load",
    "run",
    "sweep",
    "run_sweep",
    "log_range",
    "linear_range",
    "__version__",
]
