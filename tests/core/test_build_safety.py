"""A build copies only files that really lie inside the spec's folder, and only meshes the app can read.

The links are made at run time in ``tmp_path`` (a repository should not carry links to
``/etc/passwd``). Each case checks what a user would see: the error at the spec location
that names the file, exit status 1, and no app folder, ``.pyz`` or stray file left behind,
and, above all, that the outside file's content was copied nowhere.
"""

from __future__ import annotations

import os
import zipfile
from pathlib import Path

import pytest

from ejsgen.cli import main
from ejsgen.errors import EjsError
from ejsgen.generate import write_app
from ejsgen.plan import AppPlan

SECRET = b"root:x:0:0:secret outside the spec folder\n"

TRIANGLE_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"

SPEC = """\
ejs: 1
title: Links
{assets}model:
  variables:
    t: 0.0
    dt: 0.01
    q: [0.0]
view:
  - scene:
{scene}"""


def _project(tmp_path: Path, *, assets: str = "", scene: str = "      - sphere: {radius: 0.1}\n") -> tuple[Path, Path]:
    """A spec folder ``lab/`` with a secret file outside it; returns (spec, outside file)."""
    outside = tmp_path / "outside"
    outside.mkdir()
    secret = outside / "secret.obj"
    secret.write_bytes(SECRET)
    lab = tmp_path / "lab"
    lab.mkdir()
    spec = lab / "lab.ejs.yaml"
    spec.write_text(SPEC.format(assets=assets, scene=scene))
    return spec, secret


def _build_fails(spec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], *, bundle: bool = False) -> str:
    out = tmp_path / "dist" / "lab"
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    status = main(["build", str(spec), "-o", str(out), *(["--bundle"] if bundle else [])])
    err = capsys.readouterr().err
    assert status == 1
    assert "Traceback" not in err
    assert not (tmp_path / "dist").exists(), "a refused build must not leave a folder"
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before, "nothing new may be written"
    return err.splitlines()[0]


@pytest.mark.parametrize("bundle", [False, True], ids=["folder", "bundle"])
def test_a_mesh_linked_to_a_file_outside_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str], bundle: bool) -> None:
    spec, secret = _project(tmp_path, scene="      - mesh: {file: link.obj}\n")
    os.symlink(secret, spec.parent / "link.obj")
    first = _build_fails(spec, tmp_path, capsys, bundle=bundle)
    assert first == (
        f"{spec}:10:22: error: the mesh file 'link.obj' is a link to a file outside the spec's folder; "
        "only files inside the spec's folder are copied into an app; copy the file there instead of linking to it"
    )


def test_a_link_to_etc_passwd_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec, _ = _project(tmp_path, assets="assets: [passwd.txt]\n")
    os.symlink("/etc/passwd", spec.parent / "passwd.txt")
    first = _build_fails(spec, tmp_path, capsys)
    assert first.startswith(f"{spec}:3:10: error: the asset 'passwd.txt' is a link to a file outside the spec's folder")


def test_a_robot_mesh_linked_outside_is_refused_at_its_list_entry(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec, secret = _project(tmp_path, scene='      - robot: {model: "None", q: q, meshes: [base.obj, link.obj]}\n')
    (spec.parent / "base.obj").write_text(TRIANGLE_OBJ)
    os.symlink(secret, spec.parent / "link.obj")
    first = _build_fails(spec, tmp_path, capsys)
    assert first.startswith(f"{spec}:10:57: error: the mesh file 'link.obj' is a link to a file outside the spec's folder")


def test_a_linked_folder_that_leads_outside_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec, secret = _project(tmp_path, scene="      - mesh: {file: meshes/secret.obj}\n")
    os.symlink(secret.parent, spec.parent / "meshes")
    first = _build_fails(spec, tmp_path, capsys)
    assert first.startswith(f"{spec}:10:22: error: the mesh file 'meshes/secret.obj' is a link to a file outside the spec's folder")


def test_a_dangling_link_is_reported_as_such(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec, _ = _project(tmp_path, scene="      - mesh: {file: gone.obj}\n")
    os.symlink(tmp_path / "nowhere.obj", spec.parent / "gone.obj")
    first = _build_fails(spec, tmp_path, capsys)
    assert first == f"{spec}:10:22: error: the mesh file 'gone.obj' is a link to a file that does not exist"


def test_a_parent_path_is_refused_even_when_the_file_exists(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec, _ = _project(tmp_path, scene="      - mesh: {file: ../outside/secret.obj}\n")
    first = _build_fails(spec, tmp_path, capsys)
    assert first.startswith(f"{spec}:10:22: error: the mesh file '../outside/secret.obj' must be a path inside the spec's folder")


def test_a_link_inside_the_folder_is_copied_as_a_regular_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    spec, _ = _project(tmp_path, scene="      - mesh: {file: alias.obj}\n")
    (spec.parent / "parts").mkdir()
    (spec.parent / "parts" / "real.obj").write_text(TRIANGLE_OBJ)
    os.symlink(Path("parts") / "real.obj", spec.parent / "alias.obj")
    out = tmp_path / "dist" / "lab"
    assert main(["build", str(spec), "-o", str(out), "--bundle"]) == 0, capsys.readouterr().err
    copied = out / "alias.obj"
    assert copied.is_file() and not copied.is_symlink()
    assert copied.read_text() == TRIANGLE_OBJ
    with zipfile.ZipFile(out / "lab.pyz") as z:
        assert z.read("alias.obj").decode() == TRIANGLE_OBJ


def test_no_built_file_holds_the_outside_content(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Even with a good mesh beside the bad link, the secret reaches no file and no archive."""
    spec, secret = _project(tmp_path, scene="      - mesh: {file: good.obj}\n      - mesh: {file: link.obj}\n")
    (spec.parent / "good.obj").write_text(TRIANGLE_OBJ)
    os.symlink(secret, spec.parent / "link.obj")
    _build_fails(spec, tmp_path, capsys, bundle=True)
    written = [p for p in tmp_path.rglob("*") if p.is_file() and not p.is_symlink() and p != secret]
    assert all(SECRET not in p.read_bytes() for p in written)


def test_the_generator_refuses_a_linked_asset_in_a_plan(tmp_path: Path) -> None:
    """The last guard: a plan that names a link (a bug upstream) is never copied."""
    from ejsgen.cli import load_plan

    spec, secret = _project(tmp_path)
    plan: AppPlan = load_plan(spec)
    link = spec.parent / "link.obj"
    os.symlink(secret, link)
    plan.assets = [(link, "link.obj")]
    with pytest.raises(EjsError, match="not a regular file"):
        write_app(plan, tmp_path / "dist" / "lab")
    assert not (tmp_path / "dist" / "lab").exists()
    plan.assets = [(spec, "../escape.ejs.yaml")]
    with pytest.raises(EjsError, match="outside the app folder"):
        write_app(plan, tmp_path / "dist" / "lab")
    assert not (tmp_path / "dist" / "lab").exists()
