"""One run: :func:`run` drives the library's runner (the code behind ``stickslip run``)
into an output directory and reads the results back."""

from __future__ import annotations

import json
import os
import tempfile
import warnings
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from ._overrides import SceneLike, as_scene
from ._stickslip import Scene, run_to_dir

try:  # pandas is optional: DataFrames when it is there, numpy record arrays otherwise.
    import pandas as _pd
except ImportError:  # pragma: no cover - exercised only without pandas
    _pd = None


class StabilityWarning(RuntimeWarning):
    """A fixed step beyond the plate integrator's stability limit (``stickslip stability``)."""


def load(scene: SceneLike, **overrides: Any) -> Scene:
    """A validated :class:`Scene` from a scene file (or a Scene) with overrides.

    ``load("scenarios/fig2.toml", plate__v=0.5)`` is the scene of
    ``stickslip run scenarios/fig2.toml --set plate.v=0.5``. Bad input raises
    ``ValueError`` with the CLI's message.
    """
    return as_scene(scene, overrides)


@dataclass(frozen=True)
class Result:
    """What a run reported.

    ``summary`` is ``summary.json`` as a dict (``summary_json`` its text). ``trace``
    (columns ``t, x, v, friction, bond_force, attached_fraction``: one row per sample, the
    rows of ``trace.csv``) and ``events`` (``t, junction, kind, extension, tension``: the
    rows of ``events.csv``) are pandas DataFrames, or numpy record arrays without pandas,
    or ``None`` when the scene does not write them (``output.trace``, ``output.events``).
    ``out`` is the output directory when the run was given one.
    """

    summary: dict
    summary_json: str
    trace: Any = None
    events: Any = None
    out: Optional[str] = None
    scene: Optional[Scene] = field(default=None, repr=False)

    @property
    def friction_per_junction(self) -> float:
        """Mean friction per junction over ``[t_warmup, t_end]``."""
        return self.summary["friction_per_junction"]

    @property
    def regime(self) -> str:
        """``smooth`` or ``stick-slip``, or ``unstable`` for a fixed-step run whose plate step
        failed (its numbers are the scheme's, not the model's; ``docs/stability.md``)."""
        return self.summary["regime"]

    @property
    def stability(self) -> Optional[dict]:
        """Fixed-step runs: the plate step's ``growth_factor``, ``largest_stable_dt``,
        ``unstable`` (``predicted`` or ``seen``, when it is) and the locked period-2
        oscillation (``locked_steps``, ``locked_amplitude``); ``None`` otherwise."""
        return self.summary.get("stability")


def _table(columns, frames: bool):
    """The columns from the native module as a DataFrame or a numpy record array."""
    if columns is None:
        return None
    names, data, kinds = columns
    arrays = []
    for name, raw in zip(names, data):
        if name == "junction":
            arrays.append(np.frombuffer(raw, dtype=np.uint32).copy())
        elif name == "kind":
            codes = np.frombuffer(raw, dtype=np.uint8)
            if frames:
                arrays.append(_pd.Categorical.from_codes(codes.astype(np.int16), categories=kinds))
            else:
                arrays.append(np.asarray(kinds, dtype=str)[codes] if kinds else np.array([], dtype=str))
        else:
            arrays.append(np.frombuffer(raw, dtype=np.float64).copy())
    if frames:
        return _pd.DataFrame(dict(zip(names, arrays)))
    return np.rec.fromarrays(arrays, names=names)


def run(scene: SceneLike, *, out: Optional[str] = None, frames: Optional[bool] = None, **overrides: Any) -> Result:
    """Runs a scene: ``stickslip run SCENE --set ... --out OUT`` from Python.

    ``scene`` is a :class:`Scene` or a path to a scene file; ``overrides`` are scene
    fields (``plate__v=0.5`` or ``**{"plate.v": 0.5}``), applied and validated as ``--set``.
    With ``out`` (created if needed) the run writes there exactly the files the CLI writes
    (``trace.csv``, ``events.csv``, ``trace.svg`` as the scene asks, and ``summary.json``),
    byte for byte the same apart from the summary's ``wall_seconds``; without it they are
    written to a temporary directory, read, and removed. ``frames`` chooses DataFrames
    (default when pandas is installed) or numpy record arrays.

    The GIL is released while the engine runs, so other Python threads go on. Bad input
    raises ``ValueError`` (the CLI's message), a failed run ``RuntimeError``; a fixed step
    beyond the plate's stability limit warns (:class:`StabilityWarning`, the CLI's line).
    """
    s = as_scene(scene, overrides)
    frames = (_pd is not None) if frames is None else frames
    if frames and _pd is None:
        raise ValueError("frames=True: pandas is not installed (pip install pandas)")
    warning = s.stability_warning()
    if warning is not None:  # the line `stickslip run` prints on stderr
        warnings.warn(warning, StabilityWarning, stacklevel=2)
    if out is None:
        with tempfile.TemporaryDirectory(prefix="stickslip-") as tmp:
            text, trace, events = run_to_dir(s, tmp)
            return Result(json.loads(text), text, _table(trace, frames), _table(events, frames), None, s)
    os.makedirs(out, exist_ok=True)
    text, trace, events = run_to_dir(s, os.fspath(out))
    return Result(json.loads(text), text, _table(trace, frames), _table(events, frames), os.fspath(out), s)
