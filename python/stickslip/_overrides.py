"""Overrides from Python values: ``plate__v=0.5`` or ``{"plate.v": 0.5}`` to the CLI's
``--set plate.v=0.5`` text, which the library reads and validates like the scene file."""

from __future__ import annotations

import math
import os
from typing import Any, Mapping, Union

from ._stickslip import Scene

SceneLike = Union[Scene, str, "os.PathLike[str]"]


def value_text(value: Any) -> str:
    """A Python value as the text after ``=`` in ``--set section.key=value``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        # repr is the shortest text that reads back to the same float; TOML reads
        # 'inf'/'nan' too, and the scene's validation refuses them with its message.
        return repr(value) if math.isfinite(value) else ("nan" if math.isnan(value) else ("inf" if value > 0 else "-inf"))
    if isinstance(value, str):
        return value
    raise ValueError(f"override value {value!r}: expected a bool, int, float or str")


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
