"""A file listed under ``assets:`` and opened by its name in spec code is that file wherever
the app runs: from another working directory, headless, from a lone ``.pyz`` (extracted once
into a read-only per-user cache), in a sweep's worker processes and on a remote worker that
receives the app as an archive. Each value is checked against the file read here directly.
"""

from __future__ import annotations

import csv
import io
import os
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ejsgen.cli import build

SPEC = """\
ejs: 1
title: Assets everywhere
imports: [import cv2]
assets: [data/measured.csv, notes.txt, x.npy, scene.png]
model:
  variables:
    t: 0.0
    dt: 0.1
    k: 1.0
    mean: {expr: "float(np.loadtxt('data/measured.csv', delimiter=',')[:, 1].mean())"}
    words: 0
    weights: 0.0
    red: 0
    total: 0.0
  init: |
    with open('notes.txt') as fh:
        words = len(fh.read().split())
    weights = float(np.load(asset('x' + '.npy')).sum())  # a computed name
    red = int(cv2.imread('scene.png')[2, 3, 2])
  evolution:
    - ode:
        equations: {weights: 0.0}
  fixed_relations: |
    total = k * mean
metrics:
  kmean: total
"""


def _project(root: Path) -> tuple[Path, dict[str, float]]:
    """The spec and its assets in ``root``; returns (spec, the values read here from the files)."""
    import cv2

    (root / "data").mkdir(parents=True)
    rng = np.random.default_rng(7)
    table = np.c_[np.arange(20.0), 3.0 + rng.normal(size=20)]
    np.savetxt(root / "data" / "measured.csv", table, delimiter=",")
    (root / "notes.txt").write_text("five words are in here\n")
    np.save(root / "x.npy", np.array([0.25, 0.5, 2.0]))
    img = np.zeros((5, 6, 3), np.uint8)
    img[2, 3] = (10, 20, 201)  # BGR: red is 201
    cv2.imwrite(str(root / "scene.png"), img)
    spec = root / "lab.ejs.yaml"
    spec.write_text(SPEC)
    mean = float(np.loadtxt(root / "data" / "measured.csv", delimiter=",")[:, 1].mean())
    return spec, {"mean": mean, "words": 5.0, "weights": 2.75, "red": 201.0}


def _rows(text: str) -> list[dict[str, float]]:
    return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(io.StringIO(text))]


def _check(rows: list[dict[str, float]], want: dict[str, float], k: float = 1.0) -> None:
    assert rows, "no rows"
    for row in rows:
        for name, value in want.items():
            assert row[name] == pytest.approx(value, rel=1e-12), name
        assert row["total"] == pytest.approx(k * want["mean"], rel=1e-12)


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, dict[str, float]]:
    root = tmp_path_factory.mktemp("assets")
    spec, want = _project(root / "src")
    out = build(spec, root / "dist" / "lab", bundle=True)
    return spec, out, want


def _run(args: list[str], cwd: Path, **env: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, timeout=300, cwd=cwd,
                          env=dict(os.environ, PYTHONDONTWRITEBYTECODE="1", **env))


def test_code_names_the_asset_by_its_path_and_app_py_says_so(lab: tuple[Path, Path, dict[str, float]]) -> None:
    _spec, out, _want = lab
    text = (out / "app.py").read_text()
    assert "np.loadtxt(asset('data/measured.csv'), delimiter=',')" in text
    assert "with open(asset('notes.txt')) as fh:" in text
    assert "np.load(asset('x' + '.npy'))" in text  # a computed name goes through asset() as written
    assert "cv2.imread(asset('scene.png'))" in text
    assert "asset = app_assets(__file__)" in text


def test_the_app_finds_its_assets_from_another_working_directory(lab: tuple[Path, Path, dict[str, float]], tmp_path: Path) -> None:
    _spec, out, want = lab
    r = _run([str(out / "app.py"), "--headless", "--duration", "0.2", "--csv", "-"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    _check(_rows(r.stdout), want)
    assert not any(tmp_path.iterdir())  # nothing read or written where it was started


def test_a_lone_pyz_extracts_its_assets_once_read_only_into_the_users_cache(lab: tuple[Path, Path, dict[str, float]], tmp_path: Path) -> None:
    _spec, out, want = lab
    lone = tmp_path / "share" / "lab.pyz"
    lone.parent.mkdir()
    lone.write_bytes((out / "lab.pyz").read_bytes())  # one file, away from the app folder and its assets
    cache, elsewhere = tmp_path / "cache", tmp_path / "cwd"
    elsewhere.mkdir()
    args = [str(lone), "--headless", "--duration", "0.2", "--csv", "-"]
    r = _run(args, cwd=elsewhere, XDG_CACHE_HOME=str(cache))
    assert r.returncode == 0, r.stderr
    _check(_rows(r.stdout), want)
    (folder,) = (cache / "ejsgen" / "assets").iterdir()  # one folder, named by the assets' content
    files = sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())
    assert files == ["data/measured.csv", "notes.txt", "scene.png", "x.npy"]
    assert (folder / "notes.txt").read_text() == "five words are in here\n"
    assert all(not (p.stat().st_mode & (stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH)) for p in folder.rglob("*") if p.is_file())
    assert stat.S_IMODE((cache / "ejsgen" / "assets").stat().st_mode) == 0o700
    first = (folder / "x.npy").stat().st_mtime_ns
    r = _run(args, cwd=elsewhere, XDG_CACHE_HOME=str(cache))
    assert r.returncode == 0, r.stderr
    assert (folder / "x.npy").stat().st_mtime_ns == first  # the second run reuses the folder
    (folder / "notes.txt").unlink()  # a cache someone tidied: extracted again, whole
    r = _run(args, cwd=elsewhere, XDG_CACHE_HOME=str(cache))
    assert r.returncode == 0, r.stderr
    _check(_rows(r.stdout), want)
    assert [p.name for p in (cache / "ejsgen" / "assets").iterdir()] == [folder.name]


def test_a_pyz_whose_asset_was_tampered_with_refuses_to_run(lab: tuple[Path, Path, dict[str, float]], tmp_path: Path) -> None:
    import zipfile

    _spec, out, _want = lab
    bad = tmp_path / "bad.pyz"
    with zipfile.ZipFile(out / "lab.pyz") as src, zipfile.ZipFile(bad, "w") as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            dst.writestr(item, b"six words are in here now\n" if item.filename == "notes.txt" else data)
    r = _run([str(bad), "--headless", "--duration", "0.1"], cwd=tmp_path, XDG_CACHE_HOME=str(tmp_path / "cache"))
    assert r.returncode != 0
    assert "the asset 'notes.txt' does not match the archive's manifest" in r.stderr
    assert not [p for p in (tmp_path / "cache" / "ejsgen" / "assets").iterdir() if not p.name.startswith(".")]


def test_every_run_of_a_sweep_reads_the_assets_in_its_worker_process(lab: tuple[Path, Path, dict[str, float]], tmp_path: Path) -> None:
    from testkit.sweeps import ejsgen, read

    spec, _out, want = lab
    proc = ejsgen("sweep", str(spec), "-o", str(tmp_path / "app"), "--grid", "k=1:3:3", "--duration", "0.2",
                  "--out", str(tmp_path / "runs.csv"), "--workers", "2", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    summary = read(tmp_path / "runs.summary.csv")
    assert summary["status"] == ["ok"] * 3
    assert [float(v) for v in summary["kmean"]] == pytest.approx([k * want["mean"] for k in (1, 2, 3)], rel=1e-12)
    runs = read(tmp_path / "runs.csv")
    assert {float(v) for v in runs["red"]} == {201.0} and {float(v) for v in runs["words"]} == {5.0}


def test_a_pyz_sweeps_itself_with_its_assets(lab: tuple[Path, Path, dict[str, float]], tmp_path: Path) -> None:
    from testkit.sweeps import read

    _spec, out, want = lab
    r = _run([str(out / "lab.pyz"), "--sweep", "--grid", "k=2:4:2", "--duration", "0.2", "--workers", "2", "--out", str(tmp_path / "pyz.csv")],
             cwd=tmp_path, XDG_CACHE_HOME=str(tmp_path / "cache"))
    assert r.returncode == 0, r.stderr
    summary = read(tmp_path / "pyz.summary.csv")
    assert [float(v) for v in summary["kmean"]] == pytest.approx([2 * want["mean"], 4 * want["mean"]], rel=1e-12)


def test_a_remote_worker_reads_the_assets_from_the_archive_it_is_sent(lab: tuple[Path, Path, dict[str, float]], tmp_path: Path) -> None:
    """What a Dask worker on another machine does: the app folder is not there, its zip is."""
    from ejsrl.app.sweep_design import Run
    from ejsrl.app.sweep_worker import AppRef, RunOptions, app_ref, loaded, run_one

    _spec, out, want = lab
    shipped = app_ref(out).with_archive()
    remote = AppRef(str(tmp_path / "not-on-this-machine"), shipped.digest + "-remote", shipped.archive)
    result = run_one(loaded(remote), Run(0, (("k", "2"),)), RunOptions(duration=0.2))
    assert result.status == "ok", result.error
    assert result.metrics["kmean"] == pytest.approx(2 * want["mean"], rel=1e-12)


@pytest.mark.slow
def test_a_sweep_on_a_dask_local_cluster_reads_the_assets(lab: tuple[Path, Path, dict[str, float]], tmp_path: Path) -> None:
    from testkit.sweeps import ejsgen, read

    spec, _out, want = lab
    proc = ejsgen("sweep", str(spec), "-o", str(tmp_path / "app"), "--grid", "k=1:2:2", "--duration", "0.2", "--dask",
                  "--workers", "2", "--out", str(tmp_path / "dask.csv"), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "on a Dask LocalCluster of 2 workers" in proc.stderr
    assert [float(v) for v in read(tmp_path / "dask.summary.csv")["kmean"]] == pytest.approx([want["mean"], 2 * want["mean"]], rel=1e-12)


def test_a_cache_folder_others_may_write_into_is_not_used(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from ejsrl.app._assets import asset_cache_root

    shared = tmp_path / "xdg"
    (shared / "ejsgen" / "assets").mkdir(parents=True)
    (shared / "ejsgen" / "assets").chmod(0o777)  # as a folder another user planted would be
    monkeypatch.setenv("XDG_CACHE_HOME", str(shared))
    monkeypatch.setattr("tempfile.gettempdir", lambda: str(tmp_path / "tmp"))
    root = asset_cache_root()
    assert root == tmp_path / "tmp" / f"ejsgen-assets-{os.getuid()}"
    assert stat.S_IMODE(root.stat().st_mode) == 0o700
