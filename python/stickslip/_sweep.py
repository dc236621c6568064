"""Sweeps on Dask distributed.

The library prepares the sweep (validation, the grid, every run's seed: the rules of
``stickslip sweep``), Dask runs each run as one task, and the library builds the tables
from the summaries. A task is a pure function of its arguments (a scene's complete TOML
text, with the run's seed in it, and its name), so a task that Dask re-runs after a worker
died gives the same summary, and the table is the same bytes as the CLI's ``sweep.csv``.
With an output directory the client journals every finished run there (the CLI's
``journal.jsonl``), so a sweep whose client died continues where it stopped.
"""

from __future__ import annotations

import io
import numbers
import os
import time
from dataclasses import dataclass
from typing import Any, Callable, Optional, Sequence, Union

from ._overrides import SceneLike, as_scene, override_texts, value_text
from ._stickslip import Sweep, SweepOutcome, parse_values, run_summary_json

Values = Union[str, Sequence[Union[float, int, str]]]


def log_range(spec: str) -> list[str]:
    """``stickslip sweep --log-range LO:HI:COUNT``'s values (as scene texts)."""
    return parse_values("log-range", spec)


def linear_range(spec: str) -> list[str]:
    """``stickslip sweep --range LO:HI:COUNT``'s values (as scene texts)."""
    return parse_values("range", spec)


def run_one(scene_toml: str, name: str) -> str:
    """One run of a sweep, as a Dask task: ``summary.json``'s text (the GIL is released
    while the engine runs, so the worker keeps answering its scheduler)."""
    return run_summary_json(scene_toml, name)


def _texts(values: Values) -> list[str]:
    """Values as ``--values`` texts (numbers in their shortest round-trip form)."""
    if isinstance(values, str):
        return [values]
    return [value_text(v, "--values: value") for v in values]


def _axes(param: Union[str, Sequence[str]], values: Any, log: Any) -> list[tuple[str, list[str], bool]]:
    """The axes of a 1-D sweep (``param`` a field, ``values`` its values) or a 2-D one
    (two fields, two value lists)."""
    if isinstance(param, str):
        return [(param, _texts(values), bool(log))]
    params = list(param)
    if len(params) != 2 or len(values) != 2:
        raise ValueError(
            f"--param: {len(params)} fields given with {len(values)} value lists; a 2-D sweep takes "
            "param=(FIELD1, FIELD2) and values=(VALUES1, VALUES2)"
        )
    logs = tuple(log) if isinstance(log, (tuple, list)) else (bool(log), bool(log))
    if len(logs) != 2:
        raise ValueError(f"log={log!r}: a 2-D sweep takes one bool for both fields or two, one per field")
    return [(p, _texts(v), bool(lg)) for p, v, lg in zip(params, values, logs)]


def read_csv(source: Any):
    """A CSV file or text written by the library as a DataFrame, every number read back to
    the very float written (pandas 3 reads exactly by default; older versions need
    ``float_precision="round_trip"``)."""
    import pandas as pd

    if isinstance(source, str) and "\n" in source:
        source = io.StringIO(source)
    exact = {} if int(pd.__version__.split(".")[0]) >= 3 else {"float_precision": "round_trip"}
    return pd.read_csv(source, **exact)


@dataclass(frozen=True)
class SweepResult:
    """A finished sweep: ``table`` (``sweep.csv``) and ``runs`` (``runs.csv``) as
    DataFrames, ``outcome`` the library's (``sweep_csv()``, ``runs_csv()``,
    ``sweep_json()``, ``write(dir)``), ``plan`` the prepared sweep."""

    table: Any
    runs: Any
    outcome: SweepOutcome
    plan: Sweep


def run_sweep(
    scene: SceneLike,
    param: Union[str, Sequence[str]],
    values: Union[Values, Sequence[Values]],
    replicas: int = 1,
    client: Any = None,
    *,
    log: Union[bool, Sequence[bool]] = False,
    out: Optional[str] = None,
    n_workers: Optional[int] = None,
    run_task: Optional[Callable[[str, str], str]] = None,
    **overrides: Any,
) -> SweepResult:
    """As :func:`sweep`, returning both tables and the library's outcome."""
    if isinstance(replicas, bool) or not isinstance(replicas, numbers.Integral) or not 1 <= replicas <= 100_000:
        raise ValueError(f"--replicas {replicas!r}: must be a whole number from 1 to 100000")
    replicas = int(replicas)
    base = as_scene(scene, overrides)
    # Everything is validated and seeded before a cluster is started.
    plan = Sweep(base, _axes(param, values, log), replicas, override_texts(overrides))
    runs = plan.runs()
    task = run_task or run_one
    journal = None
    summaries: list[Optional[str]] = [None] * len(runs)
    if out is not None:
        # The journal the CLI keeps: runs it holds are not run again.
        os.makedirs(out, exist_ok=True)
        journal = plan.journal(os.fspath(out))
        summaries = journal.done()

    from dask.base import tokenize
    from distributed import Client, LocalCluster, as_completed

    own = client is None
    cluster = None
    if own:
        workers = n_workers or max(1, min(os.cpu_count() or 1, sum(s is None for s in summaries)))
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=":0"
        )
        client = Client(cluster)
    try:
        started = time.perf_counter()
        tomls = [s.to_toml() for _, _, s in runs]
        names = [s.name for _, _, s in runs]
        token = tokenize(tomls, names, task)
        todo = [i for i in range(len(runs)) if summaries[i] is None]
        keys = [f"stickslip-run-{i}-{token}" for i in todo]
        futures = client.map(task, [tomls[i] for i in todo], [names[i] for i in todo], key=keys, pure=False)
        index = {f.key: i for f, i in zip(futures, todo)}
        # Each run is journaled as soon as it is back, so a client that dies loses only
        # the runs in flight.
        # A future can come back here already lost again (its worker died after finishing
        # it, and Dask is computing it anew): ``result()`` waits for the new result rather
        # than reading the status once.
        for f in as_completed(futures):
            try:
                summary = f.result()
            except Exception:
                continue  # reported below, in the order of the runs
            summaries[index[f.key]] = summary
            if journal is not None:
                journal.append(index[f.key], summary)
        for i, f in zip(todo, futures):
            if summaries[i] is None:
                point, replica, s = runs[i]
                # The first failed run in the order of the runs, with the CLI's message
                # (SweepError::Run).
                raise RuntimeError(
                    f"the run for {plan.describe(point)}, replica {replica} (seed {s.seed}) failed: {f.exception()}"
                )
        workers = len(client.scheduler_info().get("workers", {}))
        outcome = plan.outcome(summaries, time.perf_counter() - started, workers)
        del futures
    finally:
        if own:
            client.close()
            cluster.close()
        del journal
    if out is not None:
        outcome.write(os.fspath(out))
    return SweepResult(read_csv(outcome.sweep_csv()), read_csv(outcome.runs_csv()), outcome, plan)


def sweep(
    scene: SceneLike,
    param: Union[str, Sequence[str]],
    values: Union[Values, Sequence[Values]],
    replicas: int = 1,
    client: Any = None,
    *,
    log: Union[bool, Sequence[bool]] = False,
    out: Optional[str] = None,
    n_workers: Optional[int] = None,
    run_task: Optional[Callable[[str, str], str]] = None,
    **overrides: Any,
):
    """A parameter sweep on Dask distributed: ``stickslip sweep`` from Python.

    ``scene`` (a :class:`Scene` or a scene file, with ``overrides`` applied as ``--set``)
    is run at every value of ``param`` (``"plate.v"``), ``replicas`` times each, with the
    CLI's seeds. ``values`` is a list of numbers (a numpy array too) or their texts, a
    ``--values`` text (``"0.1,1,10"``), or :func:`log_range` / :func:`linear_range` of a
    range; for a 2-D map give ``param=("plate.v", "plate.k")`` and ``values=(VALUES1,
    VALUES2)``. ``log`` draws the axis (or each axis) on a log scale in ``sweep.svg``.

    Runs are mapped onto ``client`` (a ``dask.distributed.Client``: a LocalCluster, a
    dask-jobqueue cluster, ...); without one a LocalCluster of ``n_workers`` processes
    (default: the cores, at most one per run) is started and closed again. A worker that
    dies is replaced and its tasks re-run by Dask, with the same results.

    Returns ``sweep.csv`` as a pandas DataFrame (the same table, from the same library
    code, as the CLI's file). With ``out`` the sweep's files (``sweep.csv``, ``runs.csv``,
    ``sweep.svg``, ``sweep.json``) are written there, as the CLI writes them, and every
    finished run is appended to ``out/journal.jsonl`` as it comes back: calling the sweep
    again with the same arguments (after the client died, say) runs only the runs the
    journal does not hold, as ``stickslip resume`` does; it continues a journal written by
    ``stickslip sweep`` as well. A journal of another sweep or scene is a ``ValueError``. ``run_task``
    replaces the function a worker calls for one run (``(scene_toml, name) -> summary
    JSON``), e.g. to wrap it; it must return what :func:`run_one` returns.

    Bad input raises ``ValueError`` with the CLI's message before anything runs; a failed
    run raises ``RuntimeError``.
    """
    return run_sweep(
        scene, param, values, replicas, client, log=log, out=out, n_workers=n_workers, run_task=run_task, **overrides
    ).table
