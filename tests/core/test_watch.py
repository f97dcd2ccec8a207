"""``ejsgen run --watch``: which values a reload keeps, how saves are seen (a half-written
file is not read), and what a failed build reports."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from ejsgen._watch import FileWatch, Rebuilder, error_report, kept_variables
from ejsgen.cli import load_plan

SPEC = """\
ejs: 1
title: Watched spring
model:
  variables:
    t: 0.0
    dt: 0.01
    N: 3
    x: {{value: 1.0, unit: m}}
    v: 0.0
    k: {{value: {k}, unit: N/m, doc: {doc}}}
    xs: {{expr: np.zeros(N)}}
    twice_k: {{expr: 2*k}}
    s: {s}
  evolution:
    - ode:
        equations:
          x: v
          v: -k*x
view:
  - slider: {{bind: k, min: 0.5, max: {kmax}, label: "{label}"}}
  - label: {{text: "x = {{x:.3f}}"}}
"""


def plan_of(tmp_path: Path, name: str = "lab", **fields: object):
    values = dict(k=4.0, doc="stiffness", s=0.5, kmax=20, label="Stiffness")
    values.update(fields)
    spec = tmp_path / f"{name}.ejs.yaml"
    spec.write_text(SPEC.format(**values))
    return load_plan(spec)


def test_a_view_only_edit_keeps_every_value(tmp_path: Path) -> None:
    old = plan_of(tmp_path, "a")
    new = plan_of(tmp_path, "b", label="Spring constant", kmax=50, doc="the spring's stiffness")
    assert kept_variables(old, new) == {"t", "dt", "N", "x", "v", "k", "xs", "twice_k", "s"}


def test_a_changed_initial_value_takes_the_new_one_and_so_does_what_reads_it(tmp_path: Path) -> None:
    old = plan_of(tmp_path, "a")
    kept = kept_variables(old, plan_of(tmp_path, "b", k=9.0, s=2.5))
    assert "k" not in kept and "s" not in kept
    assert "twice_k" not in kept  # expr: 2*k reads k
    assert {"t", "x", "v", "N", "xs"} <= kept


def test_a_changed_type_or_a_new_variable_is_not_kept_and_the_independent_variable_always_is(tmp_path: Path) -> None:
    old = plan_of(tmp_path, "a")
    new = plan_of(tmp_path, "b", s="1")  # float 0.5 -> int 1
    assert "s" not in kept_variables(old, new)
    spec = tmp_path / "c.ejs.yaml"
    spec.write_text(SPEC.format(k=4.0, doc="d", s=0.5, kmax=20, label="K").replace("t: 0.0", "t: 5.0")
                    .replace("    s: 0.5\n", "    s: 0.5\n    fresh: 1.0\n"))
    new = load_plan(spec)
    kept = kept_variables(old, new)
    assert "t" in kept and "fresh" not in kept
    spec.write_text(SPEC.format(k=4.0, doc="d", s=0.5, kmax=20, label="K").replace("N: 3", "N: 5"))
    kept = kept_variables(old, load_plan(spec))
    assert "N" not in kept and "xs" not in kept  # np.zeros(N): its size changes with N


def test_the_runtime_keeps_a_value_only_where_its_shape_still_fits(tmp_path: Path) -> None:
    """``carry_over`` is the runtime's half of the rule: a kept name whose value no longer
    has the shape of the new initial value takes the new one."""
    from ejsrl.app._reload import carry_over

    rb = Rebuilder(tmp_path / "a.ejs.yaml", tmp_path / "builds", [])
    plan_of(tmp_path, "a")
    old = rb.rebuild().build.make_app()
    old.model.x, old.model.k, old.model.xs = 0.25, 6.0, np.array([1.0, 2.0, 3.0])
    (tmp_path / "a.ejs.yaml").write_text(SPEC.format(k=4.0, doc="d", s=0.5, kmax=20, label="K").replace("N: 3", "N: 4"))
    new = rb.rebuild().build.make_app()
    carried = carry_over(old, new, {"x", "k", "xs", "N"})
    assert new.model.x == 0.25 and new.model.k == 6.0
    assert "xs" not in carried and new.model.xs.shape == (4,)
    assert new.model.twice_k == 8.0  # not kept: its declaration read the old k, the new model's runs again


def test_a_file_written_in_two_steps_is_read_once_whole(tmp_path: Path) -> None:
    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text("first version\n")
    writes = iter(["second ver", "second version, whole\n"])

    def sleep(_seconds: float) -> None:  # the editor's second write lands during the settle wait
        text = next(writes, None)
        if text is not None:
            spec.write_text(text)
            os.utime(spec, ns=(spec.stat().st_mtime_ns + 1_000_000,) * 2)

    watch = FileWatch([spec], sleep=sleep)
    assert not watch.changed()
    spec.write_text("second")
    os.utime(spec, ns=(spec.stat().st_mtime_ns + 1_000_000,) * 2)
    assert watch.changed()
    assert spec.read_text() == "second version, whole\n"
    assert not watch.changed()  # seen whole: no second build
    os.utime(spec, ns=(spec.stat().st_mtime_ns + 5_000_000,) * 2)  # saved again unchanged
    assert not watch.changed()


def test_a_file_gone_for_a_moment_and_back_counts_once(tmp_path: Path) -> None:
    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text("one\n")
    watch = FileWatch([spec], sleep=lambda s: None)
    spec.unlink()
    assert watch.changed()  # gone: a change (the build then says the file cannot be read)
    spec.write_text("two\n")
    assert watch.changed()


def test_a_failed_build_reports_what_validate_prints_with_the_line(tmp_path: Path) -> None:
    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(SPEC.format(k=4.0, doc="d", s=0.5, kmax=20, label="<b>K</b>").replace("v: -k*x", "v: -k*xx"))
    with pytest.raises(Exception) as info:
        load_plan(spec)
    report = error_report(info.value)
    validate_text = str(info.value)
    for line in validate_text.splitlines():
        assert line in report
    lines = report.splitlines()
    i = next(i for i, line in enumerate(lines) if "unknown name 'xx'" in line)
    assert ":18:" in lines[i] and "did you mean 'x'" in lines[i]
    assert lines[i + 1].strip() == "v: -k*xx"
    col = int(lines[i].split(":")[2])  # FILE:LINE:COL, 1-based
    assert lines[i + 2] == " " * (4 + col - 1) + "^"  # the caret under that column of the line shown
    assert spec.read_text().splitlines()[17][col - 1:].startswith("xx")


def test_rebuilder_gives_an_error_instead_of_raising_for_a_half_written_spec(tmp_path: Path) -> None:
    spec = tmp_path / "lab.ejs.yaml"
    text = SPEC.format(k=4.0, doc="d", s=0.5, kmax=20, label="K")
    spec.write_text(text[: len(text) // 2 + 7])  # cut mid-line
    rb = Rebuilder(spec, tmp_path / "builds", [])
    out = rb.rebuild()
    assert out.build is None and out.error and str(spec) in out.error
    spec.write_text(text)
    out = rb.rebuild()
    assert out.build is not None and out.error is None
    assert out.build.model_cls.VARIABLES["k"] == "float"


def test_the_files_a_spec_names_and_its_own_modules_are_watched_and_read_again(tmp_path: Path, monkeypatch) -> None:
    """A save of an asset or of a local module the spec imports rebuilds like a save of the
    spec; the module is imported afresh (not the copy Python already holds)."""
    (tmp_path / "helpers_watch_t.py").write_text("def gain():\n    return 3.0\n")
    (tmp_path / "table.csv").write_text("1,2\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(SPEC.format(k=4.0, doc="d", s=0.5, kmax=20, label="K")
                    .replace("title: Watched spring\n", "title: Watched spring\nimports: [from helpers_watch_t import gain]\n"
                             "assets: [table.csv]\n")
                    .replace("    s: 0.5\n", "    s: 0.5\n    g: {expr: gain()}\n"))
    rb = Rebuilder(spec, tmp_path / "builds", [])
    first = rb.rebuild()
    assert first.build is not None, first.error
    assert first.build.make_app().model.g == 3.0
    files = {p.name for p in rb.files(first.plan)}
    assert files == {"lab.ejs.yaml", "table.csv", "helpers_watch_t.py"}
    assert (first.build.base_dir / "table.csv").read_text() == "1,2\n"  # beside app.py, where the app looks
    watch = FileWatch(rb.files(first.plan), sleep=lambda s: None)
    (tmp_path / "helpers_watch_t.py").write_text("def gain():\n    return 5.0\n")
    assert watch.changed()
    again = rb.rebuild()
    assert again.build is not None and again.build.make_app().model.g == 5.0
    (tmp_path / "table.csv").write_text("3,4\n")
    assert watch.changed()
    assert (rb.rebuild().build.base_dir / "table.csv").read_text() == "3,4\n"


def test_watch_refuses_options_it_cannot_serve_with(tmp_path: Path) -> None:
    import subprocess
    import sys

    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(SPEC.format(k=4.0, doc="d", s=0.5, kmax=20, label="K"))
    for option, says in ((["--headless", "--duration", "1"], "headless"), (["--shared"], "--shared"),
                         (["--processes", "2"], "one process")):
        r = subprocess.run([sys.executable, "-P", "-m", "ejsgen", "run", "--watch", str(spec), *option],
                           capture_output=True, text=True, timeout=120)
        assert r.returncode == 2 and says in r.stderr, (option, r.stderr)
    r = subprocess.run([sys.executable, "-P", "-m", "ejsgen", "run", "--help"], capture_output=True, text=True, timeout=120)
    assert "--watch" in r.stdout and "one process" in " ".join(r.stdout.split())


def test_the_runtime_and_installed_packages_are_not_imported_again(tmp_path: Path) -> None:
    """Only the author's own modules are read afresh: importing ejsrl again would make new
    classes (a kept ``Robot`` would no longer be a ``Robot``) and cost a second a save."""
    import sys

    import ejsrl.robotics

    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(SPEC.format(k=4.0, doc="d", s=0.5, kmax=20, label="K")
                    .replace("title: Watched spring\n", "title: Watched spring\n"
                             "imports: [from ejsrl.robotics import models, import numpy.linalg, import json]\n"))
    rb = Rebuilder(spec, tmp_path / "builds", [])
    before = (sys.modules["ejsrl.robotics"], sys.modules["numpy.linalg"], sys.modules["json"])
    out = rb.rebuild()
    assert out.build is not None, out.error
    assert rb.modules == {} and rb.files(out.plan) == [spec]
    assert (sys.modules["ejsrl.robotics"], sys.modules["numpy.linalg"], sys.modules["json"]) == before
    assert before[0] is ejsrl.robotics


def test_with_o_dir_every_good_build_is_also_written_as_a_full_app(tmp_path: Path) -> None:
    import io

    from ejsgen._watch import Watcher
    from ejsrl.app._reload import LiveLab

    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text(SPEC.format(k=4.0, doc="d", s=0.5, kmax=20, label="First"))
    rb = Rebuilder(spec, tmp_path / "builds", [])
    first = rb.rebuild()
    out = tmp_path / "kept"
    watcher = Watcher(rb, LiveLab(), first, output=str(out), log=io.StringIO(), err=io.StringIO(), sleep=lambda s: None)
    watcher.start(first)
    assert "'First'" in (out / "app.py").read_text() and (out / "ejsrl").is_dir() and (out / "requirements.txt").is_file()
    spec.write_text(SPEC.format(k=4.0, doc="d", s=0.5, kmax=20, label="Second"))
    os.utime(spec, ns=(spec.stat().st_mtime_ns + 1_000_000,) * 2)
    assert watcher.poll_once() == "rebuilt"
    assert "'Second'" in (out / "app.py").read_text()
    assert [p.name for p in (tmp_path / "builds").iterdir()] == ["build-2"]  # the older build folder is gone


def test_a_saved_data_file_is_what_the_rebuilt_lab_reads(tmp_path: Path) -> None:
    """The data-fitting lab reads measured.csv by name; a save of the CSV rebuilds the lab
    and its new model holds the new data (the rebuilt app's assets are beside its app.py)."""
    import shutil

    from testkit import EXAMPLES

    shutil.copy2(EXAMPLES / "data_fitting.ejs.yaml", tmp_path)
    shutil.copytree(EXAMPLES / "data_fitting", tmp_path / "data_fitting")
    csv = tmp_path / "data_fitting" / "measured.csv"
    rb = Rebuilder(tmp_path / "data_fitting.ejs.yaml", tmp_path / "builds", [])
    first = rb.rebuild()
    assert first.build is not None, first.error
    app = first.build.make_app()
    assert app.error is None and app.model.data.shape == (81, 2)
    watch = FileWatch(rb.files(first.plan), sleep=lambda s: None)
    lines = csv.read_text().splitlines(keepends=True)
    csv.write_text("".join(lines[:-1]))  # one measurement fewer
    assert watch.changed()
    again = rb.rebuild()
    assert again.build is not None and again.build.make_app().model.data.shape == (80, 2)


def test_the_users_camera_is_kept_unless_the_author_changed_the_specs_camera() -> None:
    """A reload keeps the tab's camera where the user left it, unless the spec's 3D ``view``
    element changed (then the new view shows the camera the author asked for)."""
    from ejsrl.app._reload import _camera_spec
    from ejsrl.view.elements import Dynamic, Node3D, Scene

    def lab(preset: str, color: str, *, view: bool = True) -> list:
        nodes = [Node3D("sphere", "bob", position=Dynamic(lambda m: (m.x, 0, 0), "[x, 0, 0]"), color=color)]
        if view:
            nodes.insert(0, Node3D("view", "view1", props={"preset": preset, "follow": Dynamic(lambda m: "bob", "'bob'")}))
        return [Scene(nodes)]

    assert _camera_spec(lab("xz", "red")) == _camera_spec(lab("xz", "navy"))  # a colour: the camera stays
    assert _camera_spec(lab("xz", "red")) != _camera_spec(lab("xy", "red"))  # the spec's camera changed
    assert _camera_spec(lab("xz", "red")) != _camera_spec(lab("xz", "red", view=False))
    assert _camera_spec(lab("xz", "red", view=False)) == _camera_spec(lab("xz", "navy", view=False)) == []


def test_a_save_by_renaming_a_new_file_over_the_spec_is_seen(tmp_path: Path) -> None:
    """Editors that save atomically write a new file and rename it over the old one; the
    same size and (on a coarse clock) the same time still make a change."""
    spec = tmp_path / "lab.ejs.yaml"
    spec.write_text("k: 1.0\n")
    watch = FileWatch([spec], sleep=lambda s: None)
    new = tmp_path / ".lab.ejs.yaml.swp"
    new.write_text("k: 2.0\n")
    st = spec.stat()
    os.utime(new, ns=(st.st_atime_ns, st.st_mtime_ns))  # the same time and size as the old file
    new.replace(spec)
    assert watch.changed()
