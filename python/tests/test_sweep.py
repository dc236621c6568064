"""stickslip.sweep on Dask distributed against `stickslip sweep`: the same tables, byte for
byte, on a LocalCluster of two worker processes, in 2-D, when a worker process dies in
the middle of the sweep or after finishing a run the client has not yet read, and when the sweep is continued from its journal (a killed CLI
sweep continued by Python, a killed Python client's sweep called again)."""

from __future__ import annotations

import functools
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import cloudpickle
import numpy as np
import pandas as pd
import pytest

import faults
import stickslip
from stickslip._stickslip import Sweep
from stickslip._sweep import read_csv

# Fig. 2 shortened: about 0.1 s a run; sliding, stick-slip and sliding again.
SCENE = "scenarios/fig2.toml"
SET = {"run.t_end": 300.0, "run.t_warmup": 100.0}
SET_ARGS = ["--set", "run.t_end=300", "--set", "run.t_warmup=100"]
VALUES = [0.3, 1, 3]

# Workers unpickle the fault-injecting task by value (they need not import tests/).
cloudpickle.register_pickle_by_value(faults)


def cli_sweep(cli, out: Path, *args: str) -> Path:
    p = cli("sweep", SCENE, *SET_ARGS, *args, "--out", out)
    assert p.returncode == 0, p.stderr
    return out


def assert_same_tables(cli_dir: Path, py_dir: Path, table: pd.DataFrame) -> None:
    for name in ["sweep.csv", "runs.csv"]:
        a, b = (cli_dir / name).read_bytes(), (py_dir / name).read_bytes()
        assert len(a) > 100 and a == b, name
    expected = read_csv(cli_dir / "sweep.csv")
    pd.testing.assert_frame_equal(table, expected, check_exact=True)


def test_a_sweep_on_a_local_cluster_of_two_processes_is_the_cli_sweep(cli, repo, tmp_path):
    c = cli_sweep(cli, tmp_path / "cli", "--param", "plate.v", "--values", "0.3,1,3", "--replicas", "2")
    # No client: the sweep starts (and closes) its own LocalCluster of 2 processes.
    table = stickslip.sweep(repo / SCENE, "plate.v", VALUES, 2, n_workers=2, out=str(tmp_path / "py"), **SET)
    assert_same_tables(c, tmp_path / "py", table)
    assert list(table["plate.v"]) == VALUES and (table["replicas"] == 2).all()
    assert table["regime"].nunique() > 1, "the table should not be uniform"
    for name in ["sweep.svg", "sweep.json"]:
        assert (tmp_path / "py" / name).stat().st_size > 100


def test_a_2d_sweep_on_a_client_is_the_cli_sweep(cli, repo, tmp_path, client):
    c = cli_sweep(cli, tmp_path / "cli", "--param", "plate.v", "--values", "0.5,2", "--param", "plate.k",
                  "--log-range", "5:45:3")
    r = stickslip.run_sweep(repo / SCENE, ("plate.v", "plate.k"), ([0.5, 2], stickslip.log_range("5:45:3")),
                            client=client, out=str(tmp_path / "py"), **SET)
    assert_same_tables(c, tmp_path / "py", r.table)
    assert len(r.table) == 6 and len(r.runs) == 6 and len(r.plan) == 6


def test_a_worker_killed_mid_sweep_changes_nothing(cli, repo, tmp_path, client):
    c = cli_sweep(cli, tmp_path / "cli", "--param", "plate.v", "--values", "0.3,1,3", "--replicas", "2")
    plan = Sweep(stickslip.load(repo / SCENE, **SET), [("plate.v", ["0.3", "1", "3"], False)], 2)
    victim = plan.runs()[3][2].seed  # grid point 1 (plate.v = 1), replica 1
    marker = tmp_path / "killed"
    before = set(client.scheduler_info()["workers"])
    task = functools.partial(faults.exit_once, str(marker), victim)
    table = stickslip.sweep(repo / SCENE, "plate.v", VALUES, 2, client, out=str(tmp_path / "py"), run_task=task, **SET)
    assert marker.exists(), "no worker was killed"
    assert set(client.scheduler_info()["workers"]) != before, "the dead worker was not replaced"
    assert_same_tables(c, tmp_path / "py", table)


def test_a_result_lost_before_the_client_reads_it_is_computed_again(cli, repo, tmp_path, client, monkeypatch):
    # The race a killed worker opens: a run finishes, and its worker dies before the sweep's
    # loop reads the result, so the future reaches the loop "lost" (Dask is computing it
    # again). Made certain here: the first finished run's worker process is ended, and the
    # future handed on only once Dask has marked it lost.
    import distributed

    real = distributed.as_completed
    seen = []

    def losing_as_completed(futures):
        for f in real(futures):
            if not seen:
                (holder,) = client.who_has([f])[f.key]
                # Killed from here by its process id (a call into a worker that dies under it
                # can wait out a connection timeout); its nanny starts a new one.
                pid = client.run(os.getpid, workers=[holder])[holder]
                os.kill(pid, signal.SIGKILL)
                deadline = time.monotonic() + 120
                while f.status == "finished":
                    assert time.monotonic() < deadline, "the killed worker's result was not lost"
                    time.sleep(0.001)
                seen.append(f.status)
            yield f

    monkeypatch.setattr(distributed, "as_completed", losing_as_completed)
    c = cli_sweep(cli, tmp_path / "cli", "--param", "plate.v", "--values", "0.3,1,3", "--replicas", "2")
    table = stickslip.sweep(repo / SCENE, "plate.v", VALUES, 2, client, out=str(tmp_path / "py"), **SET)
    assert seen and seen[0] != "finished"
    assert_same_tables(c, tmp_path / "py", table)


def test_numpy_values_and_overrides_are_the_numbers_they_hold(cli, repo, tmp_path, client):
    # numpy's scalars (from np.linspace, np.arange, a DataFrame's column) are numbers, as
    # values and as overrides, whose repr under numpy 2 is np.float64(0.3): the CLI's sweep.
    c = cli_sweep(cli, tmp_path / "cli", "--param", "plate.v", "--values", "0.3,1,3", "--replicas", "2")
    sets = {k: np.float64(v) for k, v in SET.items()}
    values = np.array(VALUES, dtype=float)
    table = stickslip.sweep(repo / SCENE, "plate.v", values, 2, client, out=str(tmp_path / "py"), **sets)
    assert_same_tables(c, tmp_path / "py", table)
    a = stickslip.load(repo / SCENE, junctions__n=np.int64(30), plate__v=np.float32(0.5), output__plot=np.False_)
    assert a == stickslip.load(repo / SCENE, junctions__n=30, plate__v=0.5, output__plot=False)
    with pytest.raises(ValueError, match=r"^--values: value None: expected a bool, a number or a str$"):
        stickslip.sweep(repo / SCENE, "plate.v", [0.5, None])


def test_bad_sweeps_are_value_errors_with_the_cli_message(cli, repo, monkeypatch, client):
    monkeypatch.chdir(repo)
    for args, kwargs in [
        (["--param", "plate.nope", "--values", "1"], dict(param="plate.nope", values=[1])),
        (["--param", "run.seed", "--values", "1,2"], dict(param="run.seed", values=[1, 2])),
        (["--param", "plate.v", "--values", "0.5,-1"], dict(param="plate.v", values=[0.5, -1])),
        (["--param", "plate.v", "--values", "0.5,abc"], dict(param="plate.v", values="0.5,abc")),
    ]:
        p = cli("sweep", SCENE, *args, "--out", repo / "target" / "py-bad-sweep-never-written")
        assert p.returncode == 2, p.stderr
        with pytest.raises(ValueError) as e:
            stickslip.sweep(SCENE, **kwargs)  # refused before any cluster starts
        assert p.stderr.strip() == "error: " + str(e.value)
    # A 2-D sweep's log flags are one or two: (True,) dropped the second field.
    for log in [(True,), [True, False, True]]:
        with pytest.raises(ValueError, match=r"^log=.*: a 2-D sweep takes one bool for both fields or two"):
            stickslip.sweep(SCENE, ("plate.v", "plate.k"), ([0.5, 1], [5, 50]), log=log)
    # The command's bounds of --replicas, whatever kind of integer gives them.
    assert len(stickslip.run_sweep(SCENE, "plate.v", [1], np.int64(2), client, **SET).runs) == 2
    for replicas in [0, 100_001, np.int64(0), 2.0, True]:
        with pytest.raises(ValueError, match=r"^--replicas .*: must be a whole number from 1 to 100000$"):
            stickslip.sweep(SCENE, "plate.v", [1], replicas)  # refused before any cluster starts


def test_a_failed_run_fails_the_sweep_with_the_cli_message(cli, repo, tmp_path, client):
    # A light plate diverges within steps under the explicit integrator: the first run in
    # the order of the sweep's runs is the one named.
    sets = {"plate.mass": "1e-6", "fixed.integrator": "explicit-euler"}
    args = [a for k, v in sets.items() for a in ("--set", f"{k}={v}")]
    p = cli("sweep", "scenarios/fig1.toml", *args, "--param", "plate.k", "--values", "150,1e9", "--replicas", "2",
            "--out", tmp_path / "cli")
    assert p.returncode == 1, p.stderr
    with pytest.raises(RuntimeError) as e:
        stickslip.sweep(repo / "scenarios/fig1.toml", "plate.k", "150,1e9", 2, client, **sets)
    assert p.stderr.strip() == "error: " + str(e.value)
    assert str(e.value).startswith("the run for plate.k = 150, replica 0 (seed ")


def journaled(out: Path) -> int:
    """Runs the journal in ``out`` holds (whole lines after the header)."""
    try:
        return max(0, (out / "journal.jsonl").read_bytes().count(b"\n") - 1)
    except FileNotFoundError:
        return 0


def kill_after(args: list, out: Path, k: int, **popen) -> None:
    """Starts ``args`` and kills it (SIGKILL) once ``out``'s journal holds ``k`` runs."""
    p = subprocess.Popen([str(a) for a in args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, **popen)
    deadline = time.monotonic() + 120
    while journaled(out) < k:
        assert p.poll() is None, f"ended before {k} runs were journaled: {p.stderr.read()}"
        assert time.monotonic() < deadline, "no progress"
        time.sleep(0.005)
    p.send_signal(signal.SIGKILL)
    p.wait()
    p.stderr.close()


def test_a_killed_cli_sweep_is_continued_by_python_on_dask(cli, repo, tmp_path, client):
    c = cli_sweep(cli, tmp_path / "cli", "--param", "plate.v", "--values", "0.3,1,3", "--replicas", "2")
    out = tmp_path / "killed"
    binary = os.environ.get("STICKSLIP_BIN", repo / "target" / "release" / "stickslip")
    args = [binary, "sweep", SCENE, *SET_ARGS, "--param", "plate.v", "--values", "0.3,1,3", "--replicas", "2",
            "--threads", "1", "--out", out]
    kill_after(args, out, 2, cwd=repo)
    kept = journaled(out)
    assert 2 <= kept < 6
    table = stickslip.sweep(repo / SCENE, "plate.v", VALUES, 2, client, out=str(out), **SET)
    assert journaled(out) == 6
    assert_same_tables(c, out, table)


def test_a_python_client_that_dies_is_continued_by_calling_the_sweep_again(cli, repo, tmp_path, client):
    c = cli_sweep(cli, tmp_path / "cli", "--param", "plate.v", "--values", "0.3,1,3", "--replicas", "2")
    out = tmp_path / "py"
    # A client process on the shared cluster, killed once it journaled a run; the cluster
    # lives on.
    script = (
        "import sys, stickslip\n"
        "from distributed import Client\n"
        "client = Client(sys.argv[1])\n"
        f"stickslip.sweep({str(repo / SCENE)!r}, 'plate.v', {VALUES!r}, 2, client, out=sys.argv[2], **{SET!r})\n"
    )
    kill_after([sys.executable, "-c", script, client.scheduler.address, out], out, 1)
    kept = journaled(out)
    assert 1 <= kept <= 6
    table = stickslip.sweep(repo / SCENE, "plate.v", VALUES, 2, client, out=str(out), **SET)
    assert journaled(out) == 6
    assert_same_tables(c, out, table)
    # The journal is the CLI's: `stickslip sweep` with the same arguments runs nothing more,
    # and `stickslip resume` points back to Python (no command line was recorded).
    again = cli("sweep", SCENE, *SET_ARGS, "--param", "plate.v", "--values", "0.3,1,3", "--replicas", "2", "--out", out)
    assert again.returncode == 0, again.stderr
    assert "6 of 6 runs were already done" in again.stdout
    assert_same_tables(c, out, table)
    r = cli("resume", out)
    assert r.returncode == 2 and "stickslip.sweep in Python" in r.stderr and r.stderr.count("\n") == 1, r.stderr


def test_a_journal_of_another_sweep_is_a_value_error_and_is_left_alone(cli, repo, tmp_path, client):
    out = cli_sweep(cli, tmp_path / "cli", "--param", "plate.v", "--values", "0.3,1", "--replicas", "1")
    before = (out / "journal.jsonl").read_bytes()
    with pytest.raises(ValueError) as e:
        stickslip.sweep(repo / SCENE, "plate.v", [0.3, 1], 2, client, out=str(out), **SET)
    assert "belongs to another study" in str(e.value)
    with pytest.raises(ValueError) as e:
        stickslip.sweep(repo / SCENE, "plate.v", [0.3, 1], 1, client, out=str(out), **{**SET, "plate.mass": 30.0})
    assert "written for another scene" in str(e.value)
    assert (out / "journal.jsonl").read_bytes() == before
