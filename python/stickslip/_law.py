"""``stickslip.friction_law``: a friction law for continuum codes from a map over
``plate.v`` and ``junctions.temperature`` (docs/friction-law.md), built by the library
exactly as ``stickslip friction-law`` builds it."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any, Optional, Union

from ._stickslip import FrictionLaw
from ._stickslip import friction_law as _friction_law
from ._sweep import SweepResult, read_csv


@dataclass(frozen=True)
class FrictionLawResult:
    """A friction law: ``table`` (``law.csv``) as a DataFrame, ``record`` (``law.json``:
    the scales, the points left out, the fitted form) as a dict, and the texts of
    ``abaqus.inp`` and ``ansys.mac``."""

    table: Any
    record: dict
    abaqus: str
    ansys: str
    law: FrictionLaw


def friction_law(
    source: Union[str, os.PathLike, SweepResult],
    *,
    l0: Optional[float],
    t0: Optional[float],
    t_ref: Optional[float],
    normal_load: Optional[float],
    force_unit: Optional[float] = None,
    fit_degree: int = 2,
    out: Optional[Union[str, os.PathLike]] = None,
) -> FrictionLawResult:
    """The friction law of a V-T map: ``stickslip friction-law`` from Python.

    ``source`` is a finished sweep's directory (``stickslip sweep`` or
    :func:`stickslip.sweep` with ``out=``) or the :class:`SweepResult` of
    :func:`stickslip.run_sweep`; its fields must be ``plate.v`` and
    ``junctions.temperature``. The scales are the command's options: ``l0`` (m), ``t0``
    (the time unit M/eta, s), ``t_ref`` (K), ``normal_load`` (N) and ``force_unit`` (N,
    default kB T_ref / l0); ``fit_degree`` 1 or 2.

    The files (``law.csv``, ``abaqus.inp``, ``ansys.mac``, ``law.json``, the bytes the
    command writes) go to ``out``, or into the sweep's directory when ``source`` is one and
    ``out`` is not given; a :class:`SweepResult` without ``out`` writes nothing.

    Bad input (a scale missing or not > 0, a sweep not over V and T, an unfinished sweep)
    raises ``ValueError`` with the command's one-line message, before anything is written.
    """
    if isinstance(source, SweepResult):
        law = _friction_law(source.outcome, l0, t0, t_ref, normal_load, force_unit, fit_degree)
    else:
        law = _friction_law(os.fspath(source), l0, t0, t_ref, normal_load, force_unit, fit_degree)
        out = source if out is None else out
    if out is not None:
        os.makedirs(out, exist_ok=True)
        law.write(os.fspath(out))
    return FrictionLawResult(read_csv(law.law_csv()), json.loads(law.law_json()), law.abaqus_inp(), law.ansys_mac(), law)
