"""stickslip.run and stickslip.Scene against the CLI: the same files byte for byte, the
same one-line errors, arrays that hold exactly the numbers of the files, and the GIL
released while a run goes on."""

from __future__ import annotations

import json
import pickle
import threading
import time

import numpy as np
import pandas as pd
import pytest

import stickslip
from stickslip._sweep import read_csv

# (scene file, overrides): the fixed engine on the letter's Fig. 1 with events, and the
# exact engine on Fig. 2 (shortened) with its trace.svg.
SCENES = [
    ("scenarios/fig1.toml", {"output.events": True, "plate.v": 0.25}),
    ("scenarios/fig2.toml", {"run.t_end": 400.0, "run.t_warmup": 100.0, "output.events": True}),
]


def without_wall_time(text: str) -> list[str]:
    """summary.json's lines, except the wall-clock time (not reproducible)."""
    lines = text.splitlines()
    assert sum('"wall_seconds"' in line for line in lines) == 1
    return [line for line in lines if '"wall_seconds"' not in line]


@pytest.mark.parametrize("path,overrides", SCENES)
def test_a_python_run_writes_the_cli_files_byte_for_byte(cli, repo, tmp_path, path, overrides):
    sets = [a for k, v in overrides.items() for a in ("--set", f"{k}={stickslip._overrides.value_text(v)}")]
    p = cli("run", path, *sets, "--out", tmp_path / "cli")
    assert p.returncode == 0, p.stderr
    r = stickslip.run(repo / path, out=str(tmp_path / "py"), **overrides)

    names = sorted(f.name for f in (tmp_path / "cli").iterdir())
    assert names == sorted(f.name for f in (tmp_path / "py").iterdir())
    assert {"summary.json", "trace.csv", "events.csv"} <= set(names)
    for name in names:
        a, b = (tmp_path / "cli" / name).read_bytes(), (tmp_path / "py" / name).read_bytes()
        if name == "summary.json":
            assert without_wall_time(a.decode()) == without_wall_time(b.decode())
        else:
            assert len(a) > 100 and a == b, name
    assert (tmp_path / "py" / "summary.json").read_text() == r.summary_json
    assert r.summary == json.loads(r.summary_json) and r.out == str(tmp_path / "py")

    # The arrays hold exactly the files' numbers (shortest round-trip text).
    for table, name in [(r.trace, "trace.csv"), (r.events, "events.csv")]:
        expected = read_csv(tmp_path / "cli" / name)
        assert len(table) == len(expected) > 10
        got = table.assign(kind=table["kind"].astype(str)) if "kind" in table else table
        pd.testing.assert_frame_equal(got, expected, check_exact=True, check_dtype=False)
    assert r.events["junction"].dtype == np.uint32
    assert set(r.events["kind"].cat.categories) <= {"rupture", "formation"}


def test_a_run_without_out_gives_the_same_results_and_record_arrays(repo):
    path, overrides = SCENES[0]
    a = stickslip.run(repo / path, **overrides)
    b = stickslip.run(stickslip.load(repo / path, **overrides), frames=False)
    assert a.out is None and without_wall_time(a.summary_json) == without_wall_time(b.summary_json)
    assert isinstance(b.trace, np.recarray) and b.trace.dtype.names == tuple(a.trace.columns)
    np.testing.assert_array_equal(b.trace["friction"], a.trace["friction"].to_numpy())
    np.testing.assert_array_equal(b.events["kind"], a.events["kind"].astype(str).to_numpy())
    # A scene that writes no events has none.
    assert stickslip.run(repo / path).events is None


# Bad input, each as the CLI sees it: (CLI arguments after `run`, Python call).
BAD = [
    (["scenarios/fig1.toml", "--set", "junctions.n=-1"], lambda r: stickslip.run("scenarios/fig1.toml", **{"junctions.n": -1})),
    (["scenarios/fig1.toml", "--set", "plate.v=-0.5"], lambda r: stickslip.run("scenarios/fig1.toml", plate__v=-0.5)),
    (["scenarios/fig1.toml", "--set", "run.engine=warp"], lambda r: stickslip.load("scenarios/fig1.toml", run__engine="warp")),
    (["scenarios/fig1.toml", "--set", "plate.nope=1"], lambda r: stickslip.load("scenarios/fig1.toml", plate__nope=1)),
    (["scenarios/no-such-scene.toml"], lambda r: stickslip.run("scenarios/no-such-scene.toml")),
]


@pytest.mark.parametrize("args,call", BAD)
def test_bad_input_is_a_value_error_with_the_cli_message(cli, repo, monkeypatch, args, call):
    monkeypatch.chdir(repo)  # the messages name the path as given
    p = cli("run", *args, "--out", repo / "target" / "py-bad-input-never-written")
    assert p.returncode == 2 and p.stdout == ""
    line = p.stderr.strip()
    assert line.startswith("error: ") and "\n" not in line
    with pytest.raises(ValueError) as e:
        call(repo)
    assert "error: " + str(e.value) == line


def test_a_bad_scene_text_is_a_value_error(repo):
    text = (repo / "scenarios/fig1.toml").read_text()
    with pytest.raises(ValueError, match=r"^fig1:\d+:\d+: TOML syntax error"):
        stickslip.Scene(text + "\n[plate\n", "fig1")
    with pytest.raises(ValueError, match=r"^--set plate\.v: expected section\.key=value$"):
        stickslip.Scene(text, "fig1", ["plate.v"])
    assert stickslip.Scene(text, "fig1") == stickslip.load(repo / "scenarios/fig1.toml")


def test_a_failed_run_is_a_runtime_error_with_the_cli_message(cli, repo, tmp_path):
    # A stiff plate far beyond the explicit integrator's limit diverges within steps.
    overrides = {"plate.mass": "1e-6", "plate.k": "1e9", "fixed.integrator": "explicit-euler"}
    sets = [a for k, v in overrides.items() for a in ("--set", f"{k}={v}")]
    p = cli("run", "scenarios/fig1.toml", *sets, "--out", tmp_path / "cli")
    assert p.returncode == 1
    with pytest.raises(RuntimeError) as e, pytest.warns(stickslip.StabilityWarning) as w:
        stickslip.run(repo / "scenarios/fig1.toml", out=str(tmp_path / "py"), **overrides)
    # The CLI's two lines: the stability warning, then the error.
    assert p.stderr.splitlines() == [str(w[0].message), "error: " + str(e.value)]
    assert not (tmp_path / "py" / "summary.json").exists()


def test_scenes_pickle_and_read_back_to_the_same_scene(repo):
    s = stickslip.load(repo / "scenarios/fig2.toml", plate__v=0.7, run__seed=12)
    t = pickle.loads(pickle.dumps(s))
    assert t == s and t.name == "fig2" and t.seed == 12
    assert stickslip.Scene(s.to_toml(), s.name) == s
    assert json.loads(s.to_json())["plate"]["v"] == 0.7
    assert s.with_overrides(["plate.v=0.7"]) == s and s.with_overrides(["plate.v=0.8"]) != s


def test_a_run_releases_the_gil(repo):
    """Another Python thread keeps running while the engine runs: with the GIL held it
    would stall for the whole run."""
    scene = stickslip.load(repo / "scenarios/fig2.toml", run__t_end=20000.0, output__trace=False, output__plot=False)
    done = threading.Event()
    span = {}

    def work():
        span["start"] = time.perf_counter()
        stickslip.run(scene)
        span["end"] = time.perf_counter()
        done.set()

    ticks = []
    t = threading.Thread(target=work)
    t.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    t.join()
    run_time = span["end"] - span["start"]
    assert run_time > 0.3, f"the run took {run_time:.3f} s, too short to tell"
    inside = [x for x in ticks if span["start"] <= x <= span["end"]]
    gaps = np.diff([span["start"], *inside, span["end"]])
    # Held, the GIL would leave one gap as long as the run; released, the counter ticks
    # every millisecond or so (generous bound for a loaded machine).
    assert len(inside) > 50 and gaps.max() < 0.25 * run_time, (len(inside), gaps.max(), run_time)


def test_a_run_into_a_directory_a_cli_run_holds_is_refused_and_the_cli_run_finishes(cli, repo, tmp_path):
    import os
    import re
    import subprocess

    binary = os.environ.get("STICKSLIP_BIN", str(repo / "target" / "release" / "stickslip"))
    out = tmp_path / "held"
    long = subprocess.Popen(
        [binary, "run", "scenarios/fig1-exact.toml", "--set", "run.t_end=40000", "--out", str(out)],
        cwd=repo,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    lock = out / ".stickslip.lock"
    deadline = time.monotonic() + 60
    while not (lock.exists() and lock.read_text() == f"{long.pid}\n"):
        assert long.poll() is None, "the CLI run ended before it was seen holding its directory"
        assert time.monotonic() < deadline
        time.sleep(0.005)
    with pytest.raises(ValueError, match="^" + re.escape(f"output directory {out} is in use by process {long.pid} ")):
        stickslip.run(repo / "scenarios/fig1-exact.toml", out=str(out))
    assert long.poll() is None, "the CLI run ended before the Python run was refused: lengthen it"
    assert long.wait(timeout=300) == 0, long.stderr.read()
    assert sorted(f.name for f in out.iterdir()) == ["summary.json", "trace.csv", "trace.svg"]
