"""The same sweep on a real Dask LocalCluster (processes, 2 workers) gives the local run's tables bit for bit."""

from __future__ import annotations

from pathlib import Path

import pytest

from testkit.sweeps import SPECS, ejsgen, read

pytestmark = pytest.mark.slow

ARGS = ["--grid", "k=1:4:4", "--values", "m=1,0", "--duration", "0.4", "--every", "4"]


def _without_seconds(table: dict) -> dict:
    return {k: v for k, v in table.items() if k != "seconds"}


def test_a_sweep_on_a_dask_local_cluster_equals_the_local_pool_bit_for_bit(tmp_path: Path) -> None:
    spec = str(SPECS / "springs.ejs.yaml")
    local = ejsgen("sweep", spec, *ARGS, "--workers", "2", "--out", str(tmp_path / "local.parquet"))
    assert local.returncode == 0, local.stderr
    dask = ejsgen("sweep", spec, *ARGS, "--dask", "--workers", "2", "--out", str(tmp_path / "dask.parquet"))
    assert dask.returncode == 0, dask.stderr
    assert "on a Dask LocalCluster of 2 workers" in dask.stderr
    assert "8 runs (4 ok, 4 failed)" in dask.stderr  # m = 0 fails on Dask as it does locally
    assert read(tmp_path / "dask.parquet") == read(tmp_path / "local.parquet")
    assert _without_seconds(read(tmp_path / "dask.summary.parquet")) == _without_seconds(read(tmp_path / "local.summary.parquet"))
    # 11 rows of each run that went to its end, the first row of each that failed (as its headless CSV has)
    assert len(read(tmp_path / "dask.parquet")["run"]) == 4 * 11 + 4


def test_a_sweep_on_a_running_scheduler_ships_the_app_to_its_workers(tmp_path: Path) -> None:
    from distributed import LocalCluster

    from ejsgen.cli import build
    from ejsrl.app.sweep import sweep

    app = build(SPECS / "springs.ejs.yaml", tmp_path / "app")
    local = sweep(app, grid=["c=0:1:3"], duration=0.3, workers=0)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
        remote = sweep(app, grid=["c=0:1:3"], duration=0.3, scheduler=cluster.scheduler_address)
    assert [r.status for r in remote.results] == ["ok"] * 3
    assert remote.results_table().to_pydict() == local.results_table().to_pydict()
    assert _without_seconds(remote.summary().to_pydict()) == _without_seconds(local.summary().to_pydict())
