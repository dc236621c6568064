"""Fault injection for the sweep tests: a run task that kills its worker process the first
time it runs a chosen run."""

from __future__ import annotations

import os

from stickslip._sweep import run_one


def exit_once(marker: str, victim_seed: int, scene_toml: str, name: str) -> str:
    """``run_one``, except that the first task (across all processes) to run the scene with
    ``run.seed = victim_seed`` creates ``marker`` and ends its process at once, as a crash
    or an OOM kill would; the nanny starts a new worker and Dask runs the task again."""
    if f"seed = {victim_seed}\n" in scene_toml:
        try:
            fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            pass
        else:
            os.write(fd, str(os.getpid()).encode())
            os.close(fd)
            os._exit(1)
    return run_one(scene_toml, name)
