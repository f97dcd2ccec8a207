"""What a build says about assets named in spec code: a path outside the spec's folder (directly
or through a link) is refused at FILE:LINE:COL, as is opening a file the app does not carry or
opening an asset for writing; the text of an f-string and a local named ``asset`` are not
taken for the app's function."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from ejsgen.cli import main

SPEC = """\
ejs: 1
title: Asset errors
assets: {assets}
model:
  variables:
    t: 0.0
    note: ""
  init: |
{init}"""


def _spec(tmp_path: Path, assets: str, init: str) -> Path:
    lab = tmp_path / "lab"
    lab.mkdir(exist_ok=True)
    (lab / "notes.txt").write_text("inside\n")
    spec = lab / "lab.ejs.yaml"
    spec.write_text(SPEC.format(assets=assets, init="".join(f"    {line}\n" for line in init.splitlines())))
    return spec


def _error(spec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> str:
    status = main(["build", str(spec), "-o", str(tmp_path / "dist")])
    err = capsys.readouterr().err
    assert status == 1, err
    assert not (tmp_path / "dist").exists()
    return err.splitlines()[0]


def test_an_asset_outside_the_spec_folder_is_refused_where_it_is_listed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "secret.csv").write_text("1,2\n")
    spec = _spec(tmp_path, "[notes.txt, ../secret.csv]", "note = open('notes.txt').read()")
    assert _error(spec, tmp_path, capsys) == (
        f"{spec}:3:21: error: the asset '../secret.csv' must be a path inside the spec's folder; "
        "copy the file next to the spec (or into a subfolder) and name it relative to the spec"
    )


def test_an_asset_linked_to_a_file_outside_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "secret.csv").write_text("1,2\n")
    spec = _spec(tmp_path, "[data.csv]", "note = str(np.loadtxt('data.csv', delimiter=','))")
    os.symlink(tmp_path / "secret.csv", spec.parent / "data.csv")
    assert _error(spec, tmp_path, capsys).startswith(f"{spec}:3:10: error: the asset 'data.csv' is a link to a file outside the spec's folder")


def test_open_reads_only_listed_assets(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = _spec(tmp_path, "[notes.txt]", "note = open('other.txt').read()")
    assert _error(spec, tmp_path, capsys) == (
        f"{spec}:9:12: error: 'open' is not available in spec code, except to read a file listed under 'assets:'; "
        "list the file under assets: and open it by its path, e.g. open('notes.txt')"
    )


def test_an_asset_cannot_be_opened_for_writing(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = _spec(tmp_path, "[notes.txt]", "with open('notes.txt', 'a') as fh:\n    fh.write('more')")
    assert _error(spec, tmp_path, capsys).startswith(f"{spec}:9:10: error: 'open' is not available in spec code, except to read")


def test_a_local_named_asset_beside_an_asset_path_is_an_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = _spec(tmp_path, "[notes.txt]", "asset = 1\nnote = open('notes.txt').read()")
    assert _error(spec, tmp_path, capsys) == (
        f"{spec}:10:17: error: 'notes.txt' names an asset, but 'asset' is a local name here; "
        "rename the local 'asset': the app reads its assets through the function asset()"
    )


def test_only_whole_strings_outside_f_string_text_name_an_asset(tmp_path: Path) -> None:
    spec = _spec(tmp_path, "[notes.txt]", "note = f'notes.txt has {len(open(\"notes.txt\").read())} characters' + ' notes.txt'")
    assert main(["build", str(spec), "-o", str(tmp_path / "dist")]) == 0
    text = (tmp_path / "dist" / "app.py").read_text()
    assert """self.note = f'notes.txt has {len(open(asset("notes.txt")).read())} characters' + ' notes.txt'""" in text


def test_a_file_beside_the_spec_read_by_name_must_be_listed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Read without being listed, it would be the working directory's file, not the app's."""
    spec = _spec(tmp_path, "[]", "note = str(np.loadtxt('data.csv', delimiter=','))")
    (spec.parent / "data.csv").write_text("1,2\n")
    assert _error(spec, tmp_path, capsys) == (
        f"{spec}:9:27: error: 'data.csv' is a file beside the spec, but it is not listed under 'assets:', "
        "so the built app would not have it; list it: assets: [data.csv]"
    )


def test_asset_of_a_name_not_listed_suggests_the_listed_one(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec = _spec(tmp_path, "[notes.txt]", "note = asset('note.txt')")
    assert _error(spec, tmp_path, capsys) == f"{spec}:9:18: error: 'note.txt' is not listed under 'assets:'; did you mean 'notes.txt'?"
