"""Overrides from Python values: ``plate__v=0.5`` or ``{"plate.v": 0.5}`` to the CLI's
``--set plate.v=0.5`` text, which the library reads and validates like the scene file."""

from __future__ import annotations

import math
import numbers
import os
from typing import Any, Mapping, Union

from ._stickslip import Scene

SceneLike = Union[Scene, str, "os.PathLike[str]"]


def value_text(value: Any, what: str = "override value") -> str:
    """A Python value as the text after ``=`` in ``--set section.key=value``: a bool, an
    integer or a real number (numpy's scalars included) or a text. ``what`` names the value
    in the error."""
    if isinstance(value, bool) or (getattr(value, "shape", None) == () and value.dtype.kind == "b"):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        # repr of a float is the shortest text that reads back to it (numpy's scalars are
        # made floats first: their repr is ``np.float64(0.5)``); TOML reads 'inf'/'nan'
        # too, and the scene's validation refuses them with its message.
        x = float(value)
        return repr(x) if math.isfinite(x) else ("nan" if math.isnan(x) else ("inf" if x > 0 else "-inf"))
    if isinstance(value, str):
        return value
    raise ValueError(f"{what} {value!r}: expected a bool, a number or a str")


def override_texts(overrides: Mapping[str, Any]) -> list[str]:
    """``{"plate__v": 0.5}`` -> ``["plate.v=0.5"]`` (in the order given)."""
    return [f"{key.replace('__', '.')}={value_text(v)}" for key, v in overrides.items()]


def as_scene(scene: SceneLike, overrides: Mapping[str, Any]) -> Scene:
    """A :class:`Scene` from a scene, a path, or TOML text, with ``overrides`` applied."""
    texts = override_texts(overrides)
    if isinstance(scene, Scene):
        return scene.with_overrides(texts) if texts else scene
    if isinstance(scene, (str, os.PathLike)):
        return Scene.from_file(os.fspath(scene), texts)
    raise TypeError(f"scene: expected a Scene or a path to a scene file, got {type(scene).__name__}")
