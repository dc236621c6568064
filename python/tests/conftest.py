"""Shared fixtures: the repository, the CLI binary the Python results are compared with
(``STICKSLIP_BIN``, default ``target/release/stickslip``, which .ci/run builds first), and
a small Dask cluster of two worker processes."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO


@pytest.fixture(scope="session")
def cli(repo):
    """Runs the ``stickslip`` binary; returns the completed process (text mode)."""
    binary = Path(os.environ.get("STICKSLIP_BIN", repo / "target" / "release" / "stickslip"))
    if not binary.is_file():
        pytest.fail(f"no CLI binary at {binary}: run `cargo build --release` first, or set STICKSLIP_BIN")

    def call(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([str(binary), *map(str, args)], cwd=repo, capture_output=True, text=True, timeout=300)

    return call


@pytest.fixture(scope="module")
def client():
    """A LocalCluster of 2 worker processes (one thread each) on the loopback interface."""
    from distributed import Client, LocalCluster

    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=":0"
    ) as cluster, Client(cluster) as c:
        yield c
