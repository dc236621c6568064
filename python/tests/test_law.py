"""stickslip.friction_law against `stickslip friction-law`: the same four files, byte for
byte, from a sweep's directory and from a sweep run on Dask; bad input is the CLI's
one-line message as a ValueError, with nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest

import stickslip

SCENE = "scenarios/fig2.toml"
SET_ARGS = ["--set", "run.t_end=300", "--set", "run.t_warmup=100", "--set", "junctions.bond=weak"]
SET = {"run.t_end": 300.0, "run.t_warmup": 100.0, "junctions.bond": "weak"}
AXES = ["--param", "plate.v", "--values", "0.1,1,10", "--param", "junctions.temperature", "--values", "0.5,2"]
SCALES = dict(l0=2e-9, t0=3e-6, t_ref=300.0, normal_load=1e-9)
SCALE_ARGS = ["--l0", "2e-9", "--t0", "3e-6", "--t-ref", "300", "--normal-load", "1e-9"]
FILES = ["law.csv", "abaqus.inp", "ansys.mac", "law.json"]


def same_files(a: Path, b: Path) -> None:
    for f in FILES:
        assert (a / f).read_bytes() == (b / f).read_bytes(), f


def test_law_from_a_sweep_directory_is_the_commands(cli, tmp_path):
    swept = tmp_path / "swept"
    p = cli("sweep", SCENE, *SET_ARGS, *AXES, "--replicas", "2", "--out", swept)
    assert p.returncode == 0, p.stderr
    p = cli("friction-law", "--from", swept, "--out", tmp_path / "cli", *SCALE_ARGS)
    assert p.returncode == 0, p.stderr
    r = stickslip.friction_law(swept, out=tmp_path / "py", **SCALES)
    same_files(tmp_path / "cli", tmp_path / "py")
    # The result holds what the files hold.
    assert len(r.table) == 6
    steady = r.table[r.table["steady"]]
    assert r.table["mu"].notna().tolist() == r.table["steady"].tolist()
    assert r.abaqus.count("\n*FRICTION\n") == 1
    assert r.ansys.count("TBDATA,1,") == len(steady)
    assert len(r.record["left_out"]) == 6 - len(steady)
    # Without out, the sweep's own directory.
    stickslip.friction_law(swept, **SCALES)
    same_files(tmp_path / "cli", swept)


def test_law_from_a_sweep_on_dask_is_the_commands(cli, client, tmp_path):
    p = cli("friction-law", SCENE, *SET_ARGS, *AXES, "--replicas", "2", "--out", tmp_path / "cli", *SCALE_ARGS)
    assert p.returncode == 0, p.stderr
    result = stickslip.run_sweep(
        SCENE,
        ("plate.v", "junctions.temperature"),
        ("0.1,1,10", "0.5,2"),
        replicas=2,
        client=client,
        **SET,
    )
    stickslip.friction_law(result, out=tmp_path / "py", **SCALES)
    same_files(tmp_path / "cli", tmp_path / "py")


def test_law_bad_input_is_one_line_and_writes_nothing(cli, tmp_path):
    swept = tmp_path / "swept"
    p = cli("sweep", SCENE, *SET_ARGS, "--param", "plate.v", "--values", "0.1,10", "--out", swept)
    assert p.returncode == 0, p.stderr
    out = tmp_path / "law"
    for missing in ["l0", "t0", "t_ref", "normal_load"]:
        scales = dict(SCALES, **{missing: None})
        option = "--" + missing.replace("_", "-")
        with pytest.raises(ValueError, match=f"^{option}: missing;"):
            stickslip.friction_law(swept, out=out, **scales)
    with pytest.raises(ValueError, match="^--t0 -1: must be a number from 1e-150 to 1e150"):
        stickslip.friction_law(swept, out=out, **dict(SCALES, t0=-1.0))
    with pytest.raises(ValueError, match="plate.v and junctions.temperature"):
        stickslip.friction_law(swept, out=out, **SCALES)
    assert not out.exists()
    assert not any((swept / f).exists() for f in FILES)
