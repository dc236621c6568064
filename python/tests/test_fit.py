"""stickslip.fit against `stickslip fit`: on a tiny scene and data the test makes from the
simulator plus seeded noise, the fit from Python with its evaluations on Dask writes the
command's four files byte for byte (the runs are the same library calls on the same scene
files and seeds, their frictions come back as the very floats, and the optimiser and
profiles are the library's: nothing differs, so nothing is compared "to rounding"); a
Python fit killed (SIGKILL) and called again continues its journal to the same files, and
so does a fit that continues a killed command's journal, and `stickslip resume` continues a
killed Python fit's journal; progress is a line per stage on stderr; bad input is the command's
one-line message as a ValueError, with nothing written."""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

import stickslip

# The tiny scene tests/suite/fit.rs shares: 30 junctions on a kinematic plate, strong bonds,
# linear law; well under a millisecond a run.
TINY = (Path(__file__).resolve().parents[2] / "tests" / "fixtures" / "fit-tiny.toml").read_text()
VELOCITIES = "0.1,0.3,1,3"
FREE = "junctions.k0,junctions.kon0"
# The kill tests fit one parameter (a tenth of the evaluations, each a round trip to Dask).
ONE = "junctions.k0"
FILES = ["fit.json", "fit.csv", "fit.toml", "fit.svg"]


@pytest.fixture(scope="module")
def inputs(cli, tmp_path_factory):
    """The scene file and DATA.csv: a 16-replica sweep at k0 = 0.5, kon0 = 0.2 plus
    Gaussian noise of 20 % of each value (seeded), with that sigma."""
    d = tmp_path_factory.mktemp("fit-inputs")
    scene = d / "tiny.toml"
    scene.write_text(TINY)
    p = cli("sweep", scene, "--param", "plate.v", "--values", VELOCITIES, "--replicas", "16",
            "--set", "junctions.k0=0.5", "--set", "junctions.kon0=0.2", "--set", "run.seed=99",
            "--set", "output.plot=false", "--out", d / "truth")
    assert p.returncode == 0, p.stderr
    table = stickslip._sweep.read_csv(str(d / "truth" / "sweep.csv"))
    rng = random.Random(13)
    lines = ["plate.v,friction,sigma"]
    for v, f in zip(table["plate.v"], table["friction_per_junction"]):
        s = 0.2 * f
        lines.append(f"{v!r},{f + rng.gauss(0.0, s)!r},{s!r}")
    data = d / "data.csv"
    data.write_text("\n".join(lines) + "\n")
    return scene, data


def command_fit(cli, scene, data, free, out):
    p = cli("fit", scene, data, "--free", free, "--replicas", "2", "--threads", "2", "--out", out)
    assert p.returncode == 0, p.stderr
    return out


@pytest.fixture(scope="module")
def cli_fit(cli, inputs, tmp_path_factory):
    return command_fit(cli, *inputs, FREE, tmp_path_factory.mktemp("fit-cli") / "cli")


@pytest.fixture(scope="module")
def cli_fit_one(cli, inputs, tmp_path_factory):
    return command_fit(cli, *inputs, ONE, tmp_path_factory.mktemp("fit-cli-one") / "cli")


def same_files(a: Path, b: Path) -> None:
    for f in FILES:
        assert (a / f).read_bytes() == (b / f).read_bytes(), f


def test_fit_on_dask_is_the_commands(cli_fit, inputs, client, tmp_path):
    scene, data = inputs
    r = stickslip.fit(scene, data, FREE, replicas=2, client=client, out=tmp_path / "py")
    same_files(cli_fit, tmp_path / "py")
    assert r.made == r.evaluations == r.record["evaluations"]
    assert set(r.parameters) == {"junctions.k0", "junctions.kon0"}
    assert list(r.table["plate.v"]) == [0.1, 0.3, 1.0, 3.0]
    assert r.toml.startswith("# The scene tiny with the values fitted")
    # Called again, every evaluation comes from the journal: none is made.
    again = stickslip.fit(scene, data, FREE, replicas=2, client=client, out=tmp_path / "py")
    assert again.made == 0 and again.record == r.record


KILLED = """
import sys
import stickslip
from distributed import Client, LocalCluster

if __name__ == "__main__":
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=":0") as c, Client(c) as cl:
        stickslip.fit(sys.argv[1], sys.argv[2], sys.argv[3], replicas=2, client=cl, out=sys.argv[4])
"""


def journal_lines(out: Path) -> int:
    try:
        return len((out / "journal.jsonl").read_text().splitlines())
    except FileNotFoundError:
        return 0


def kill_after(cmd: list, out: Path, lines: int) -> None:
    """Starts `cmd`, SIGKILLs it once `out`'s journal holds `lines` lines."""
    child = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    started = time.monotonic()
    while journal_lines(out) < lines and child.poll() is None and time.monotonic() - started < 120:
        time.sleep(0.005)
    child.send_signal(signal.SIGKILL)
    child.wait()
    assert not (out / "fit.json").exists(), "killed before it finished"


def killed_python_fit(inputs, tmp_path: Path, lines: int) -> Path:
    """A Python fit of ONE into `tmp_path / "cut"`, SIGKILLed once its journal holds `lines`
    lines."""
    scene, data = inputs
    script = tmp_path / "killed.py"
    script.write_text(textwrap.dedent(KILLED))
    out = tmp_path / "cut"
    kill_after([sys.executable, str(script), str(scene), str(data), ONE, str(out)], out, lines)
    return out


def test_a_killed_python_fit_continues_to_the_same_files(cli_fit_one, inputs, client, tmp_path):
    scene, data = inputs
    total = journal_lines(cli_fit_one)
    out = killed_python_fit(inputs, tmp_path, total // 3)
    kept = journal_lines(out) - 1
    r = stickslip.fit(scene, data, ONE, replicas=2, client=client, out=out)
    same_files(cli_fit_one, out)
    assert r.made == r.evaluations - kept and 0 < kept < r.evaluations
    assert journal_lines(out) == total


def test_python_continues_a_killed_commands_journal(cli, cli_fit_one, inputs, client, tmp_path):
    scene, data = inputs
    total = journal_lines(cli_fit_one)
    out = tmp_path / "cut"
    binary = os.environ.get("STICKSLIP_BIN", str(Path(__file__).resolve().parents[2] / "target/release/stickslip"))
    kill_after([binary, "fit", str(scene), str(data), "--free", ONE, "--replicas", "2", "--threads", "1",
                "--out", str(out)], out, total // 2)
    r = stickslip.fit(scene, data, ONE, replicas=2, client=client, out=out)
    same_files(cli_fit_one, out)
    assert 0 < r.made < r.evaluations


def test_stickslip_resume_continues_a_killed_python_fit(cli, cli_fit_one, inputs, tmp_path):
    total = journal_lines(cli_fit_one)
    out = killed_python_fit(inputs, tmp_path, total // 3)
    # The journal records the command of the same fit, on the scene written into out/input.
    assert (out / "input" / "tiny.toml").is_file()
    p = cli("resume", out)
    assert p.returncode == 0, p.stderr
    same_files(cli_fit_one, out)
    assert journal_lines(out) == total


def test_progress_is_a_line_per_stage(inputs, client, tmp_path, capsys):
    scene, data = inputs
    seen = []
    r = stickslip.fit(scene, data, ONE, replicas=2, client=client, out=tmp_path / "a",
                      progress=lambda n, best, stage: seen.append((n, best, stage)))
    assert [n for n, _, _ in seen] == list(range(1, r.evaluations + 1))
    stages = [s for _, _, s in seen]
    assert stages[0] == "search for the optimum" and stages[-1] == "profiles"
    assert stages.count("search for the optimum") == r.record["evaluations_search"]
    assert min(b for _, b, _ in seen) == seen[-1][1]
    capsys.readouterr()
    stickslip.fit(scene, data, ONE, replicas=2, client=client, out=tmp_path / "b", progress=True)
    err = capsys.readouterr().err.splitlines()
    assert err[0] == "stickslip.fit: search for the optimum"
    assert err[1].startswith("stickslip.fit: profiles (after ") and err[2].startswith(f"stickslip.fit: done, {r.evaluations} evaluations")
    assert len(err) == 3
    # Off when stderr is not a terminal (as under pytest), as the command's.
    stickslip.fit(scene, data, ONE, replicas=2, client=client, out=tmp_path / "c")
    assert capsys.readouterr().err == ""


def test_bad_input_is_the_commands_message_and_nothing_is_written(cli, inputs, client, tmp_path):
    scene, data = inputs
    bad = tmp_path / "bad.csv"
    bad.write_text("plate.v,force\n0.1,1\n0.3,2\n1,3\n")
    cases = [
        (bad, FREE, {}),
        (data, "junctions.nope", {}),
        (data, "junctions.k0=-1:1:lin", {}),
        (data, "junctions.k0,junctions.kon0,junctions.kappa,junctions.lambda,plate.k", {}),
    ]
    for i, (d, free, extra) in enumerate(cases):
        out = tmp_path / f"out{i}"
        p = cli("fit", scene, d, "--free", free, "--out", out)
        assert p.returncode == 2 and not out.exists(), p.stderr
        message = p.stderr.strip().removeprefix("error: ")
        with pytest.raises(ValueError) as e:
            stickslip.fit(scene, d, free, client=client, out=out, **extra)
        assert str(e.value) == message
        assert not out.exists()
    with pytest.raises(ValueError, match="replicas"):
        stickslip.fit(scene, data, FREE, replicas=0, client=client)
