"""``stickslip.fit``: calibration (``stickslip fit``, docs/calibration.md) with its
evaluations on Dask distributed.

The library does everything that decides the result: it reads and checks the data and the
free parameters, seeds every run (common random numbers), runs the optimiser and the
profiles, journals every evaluation and writes the files. What Python adds is where the
runs go: each evaluation (every data point's replicas at one set of parameter values) is
handed to :func:`simulate`, which maps its runs onto the Dask cluster as tasks, pure
functions of their arguments (the run's complete scene file, its seed in it, and its name),
and gathers their mean frictions per junction in order. The same runs give the same
floats on any worker, so the fit, its files and its journal are those of the CLI.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import threading
from dataclasses import dataclass
from typing import Any, Callable, Optional, Sequence, Union

from ._overrides import SceneLike, as_scene
from ._stickslip import Fit, fit_run
from ._sweep import read_csv


def run_one(scene_toml: str, name: str) -> float:
    """One run of a fit, as a Dask task: its mean friction per junction (the GIL is
    released while the engine runs)."""
    return fit_run(scene_toml, name)


@dataclass(frozen=True)
class FitResult:
    """A finished fit: ``record`` (``fit.json``: per free field its value, 95 % interval,
    flags and profile; the misfit, degrees of freedom, p-value, evaluations) as a dict,
    ``table`` (``fit.csv``: data, fitted curve, band, residuals) as a DataFrame, ``toml``
    (``fit.toml``, the scene with the fitted values), ``out`` the directory of the files
    (``None`` when they went to a temporary one), ``evaluations`` and ``made`` (the
    evaluations this call made; the others came from the journal)."""

    record: dict
    table: Any
    toml: str
    out: Optional[str]
    evaluations: int
    made: int

    @property
    def parameters(self) -> dict:
        """``{field: fitted value}``."""
        return {k: v["value"] for k, v in self.record["parameters"].items()}


def simulator(client: Any, task: Callable[[str, str], float] = run_one) -> Callable[[list, list], list]:
    """The function the library calls with each evaluation's runs (their scene files and
    names): maps them onto ``client`` as tasks and returns their mean frictions in order.
    A run that fails raises its ``RuntimeError`` (naming its seed)."""
    from dask.base import tokenize

    def simulate(tomls: list, names: list) -> list:
        keys = [f"stickslip-fit-{tokenize(t, n, task)}" for t, n in zip(tomls, names)]
        futures = client.map(task, tomls, names, key=keys, pure=False)
        try:
            return [float(v) for v in client.gather(futures)]
        finally:
            del futures

    return simulate


class Progress:
    """The default ``progress=`` of :func:`fit`: one line on stderr when the fit enters a
    stage (the search for the optimum, the profiles) and when it ends, each with the
    evaluations made and the best misfit so far; on a terminal the count is also updated
    in place after every evaluation. Thread safe (the profiles' sides report at once)."""

    def __init__(self, stream: Any = None, live: Optional[bool] = None) -> None:
        self.stream = sys.stderr if stream is None else stream
        self.live = self.stream.isatty() if live is None else live
        self.stage: Optional[str] = None
        self.last = (0, float("inf"))
        self.lock = threading.Lock()

    def _line(self, text: str) -> None:
        self.stream.write(("\r\x1b[K" if self.live else "") + text + "\n")
        self.stream.flush()

    def __call__(self, evaluations: int, best: float, stage: str) -> None:
        with self.lock:
            if stage != self.stage:
                self.stage = stage
                n, b = self.last
                self._line(f"stickslip.fit: {stage}" + (f" (after {n} evaluations, best misfit {b:.6e})" if n else ""))
            self.last = (evaluations, best)
            if self.live:
                self.stream.write(f"\r\x1b[K  {stage}: {evaluations} evaluations, best misfit {best:.6e}")
                self.stream.flush()

    def done(self, evaluations: int) -> None:
        with self.lock:
            self._line(f"stickslip.fit: done, {evaluations} evaluations, best misfit {self.last[1]:.6e}")


def fit(
    scene: SceneLike,
    data: Union[str, os.PathLike],
    free: Union[str, Sequence[str]],
    *,
    replicas: int = 4,
    friction_scale: float = 1.0,
    max_evaluations: int = 5000,
    out: Optional[Union[str, os.PathLike]] = None,
    client: Any = None,
    n_workers: Optional[int] = None,
    run_task: Optional[Callable[[str, str], float]] = None,
    progress: Union[None, bool, Callable[[int, float, str], None]] = None,
    **overrides: Any,
) -> FitResult:
    """Fits scene fields to a measured friction curve: ``stickslip fit`` from Python.

    ``scene`` (a :class:`Scene` or a scene file, ``overrides`` applied as ``--set``), the
    data file ``data`` (``DATA.csv``: ``friction``, optional ``sigma``, condition columns
    named by scene fields) and ``free`` (``--free``: ``"junctions.k0,junctions.kon0"`` or a
    list, each ``FIELD[=LOW:HIGH[:lin|:log]]``), ``replicas``, ``friction_scale`` and
    ``max_evaluations`` are the command's. Bad input raises ``ValueError`` with the
    command's one-line message before anything runs or is written.

    Every evaluation's runs are mapped onto ``client`` (a ``dask.distributed.Client``);
    without one a LocalCluster of ``n_workers`` single-threaded processes (default: the
    cores) is started and closed again. The result is the command's for the same scene,
    data, options and seed: the same ``fit.json``, ``fit.csv``, ``fit.toml`` and
    ``fit.svg``, byte for byte, written into ``out`` (a temporary directory when not
    given), which is held while the fit runs as the command holds it. Every evaluation is
    appended to ``out/journal.jsonl``: calling the fit again with the same arguments
    after it was killed makes only the evaluations the journal lacks and gives the result
    of an uninterrupted fit; it continues a journal of ``stickslip fit`` too, and
    ``stickslip resume OUT`` continues a Python fit's journal (a new journal records the
    ``stickslip fit`` command of the same fit, its scene written to ``out/input/``).
    ``progress``: ``None`` (the default) shows progress on stderr when stderr is a
    terminal, as the command does (:class:`Progress`: a line per stage, the count updated
    in place); ``True`` always, ``False`` never; or a callable ``(evaluations,
    best_misfit, stage)`` called after each new evaluation, from the fit's threads. Ctrl-C stops the fit after the evaluations in progress and raises
    ``KeyboardInterrupt``, the journal kept. A run that fails raises ``RuntimeError``
    with the command's message. ``run_task`` replaces the function a worker calls for a
    run (``(scene_toml, name) -> friction``); it must return what :func:`run_one` does.
    """
    for name, v, lo in (("replicas", replicas, 1), ("max_evaluations", max_evaluations, 1)):
        if isinstance(v, bool) or not isinstance(v, int) or v < lo:
            raise ValueError(f"--{name.replace('_', '-')} {v}: must be a whole number >= {lo}")
    base = as_scene(scene, overrides)
    frees = [free] if isinstance(free, str) else list(free)
    plan = Fit(base, os.fspath(data), frees, replicas, float(friction_scale), max_evaluations)

    from distributed import Client, LocalCluster

    own = client is None
    cluster = None
    if own:
        workers = n_workers or max(1, min(os.cpu_count() or 1, plan.runs_per_evaluation()))
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=":0"
        )
        client = Client(cluster)
    scratch = tempfile.TemporaryDirectory(prefix="stickslip-fit-") if out is None else None
    directory = scratch.name if scratch is not None else os.fspath(out)
    try:
        os.makedirs(directory, exist_ok=True)
        shown = None
        if callable(progress):
            report = progress
        elif progress or (progress is None and sys.stderr.isatty()):
            report = shown = Progress()
        else:
            report = None
        evaluations, made = plan.run(directory, simulator(client, run_task or run_one), report)
        if shown is not None:
            shown.done(evaluations)
        with open(os.path.join(directory, "fit.json")) as f:
            record = json.load(f)
        with open(os.path.join(directory, "fit.toml")) as f:
            toml = f.read()
        table = read_csv(os.path.join(directory, "fit.csv"))
    finally:
        if own:
            client.close()
            cluster.close()
        if scratch is not None:
            scratch.cleanup()
    return FitResult(record, table, toml, None if scratch is not None else directory, evaluations, made)
