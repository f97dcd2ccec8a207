"""The language reference (specs/language.md) and the tutorial (specs/tutorial.md).

- The reference's tables are generated from the models; a stale table fails with the
  command that regenerates it, and every kind and key of the models is documented (and
  nothing else is).
- Every complete spec in the two documents builds with ``ejsgen build`` and runs headless.
- The tutorial's snippets are the step files in examples/tutorial/, and each step file
  builds, runs, and does what its step teaches, checked against independent references
  (closed forms, Denavit-Hartenberg written out here, a pinhole projection).
"""

from __future__ import annotations

import io
import re
from math import pi, sqrt
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from scipy.special import ellipk

from ejsgen.cli import main
from ejsgen.spec import GUI_ELEMENT_MODELS, SCENE_ELEMENT_MODELS, Model, Ode, OdeEvent, Program, Simulation, Spec, Variable
from testkit import EXAMPLES, ROOT

LANGUAGE = ROOT / "specs" / "language.md"
TUTORIAL = ROOT / "specs" / "tutorial.md"
STEPS = sorted((EXAMPLES / "tutorial").glob("step*.ejs.yaml"))


# -- reading the documents --------------------------------------------------------------------


def yaml_blocks(path: Path) -> list[str]:
    return re.findall(r"^```yaml\n(.*?)^```", path.read_text(encoding="utf-8"), re.S | re.M)


def is_complete(block: str) -> bool:
    """A complete spec: its first line that is not a comment is ``ejs: 1``."""
    lines = [ln for ln in block.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    return bool(lines) and lines[0].split("#")[0].strip() == "ejs: 1"


def complete_specs() -> list[tuple[str, str]]:
    out = []
    for doc in (LANGUAGE, TUTORIAL):
        for i, block in enumerate(yaml_blocks(doc)):
            if is_complete(block):
                out.append((f"{doc.stem}-{i}", block))
    return out


def section(text: str, name: str) -> str:
    m = re.search(rf"<!-- generated: {name} -->\n(.*?)<!-- end generated -->", text, re.S)
    assert m, f"specs/language.md has no generated section '{name}'"
    return m.group(1)


def table_keys(markdown: str) -> list[str]:
    """The first column of a Markdown table's rows: ``| `key` | ...``."""
    return re.findall(r"^\| `([A-Za-z_0-9]+)` \|", markdown, re.M)


def kind_tables(markdown: str) -> dict[str, list[str]]:
    """``#### `kind` `` headings and the keys of the table under each."""
    parts = re.split(r"^#### `([a-z0-9_]+)`\n", markdown, flags=re.M)
    return {parts[i]: table_keys(parts[i + 1]) for i in range(1, len(parts), 2)}


# -- the reference is generated and complete ---------------------------------------------------


def test_the_reference_tables_are_current() -> None:
    from ejsgen._docs import REGENERATE, stale_sections, update

    text = LANGUAGE.read_text(encoding="utf-8")
    stale = stale_sections(text)
    assert not stale and update(text) == text, f"specs/language.md is stale (sections {stale}); regenerate it with `{REGENERATE}`"


def test_every_kind_and_key_of_the_models_is_documented_and_nothing_else() -> None:
    text = LANGUAGE.read_text(encoding="utf-8")
    gui = kind_tables(section(text, "view-properties"))
    assert set(gui) == set(GUI_ELEMENT_MODELS)
    for kind, keys in gui.items():
        assert keys == list(GUI_ELEMENT_MODELS[kind].model_fields), kind
    scene = kind_tables(section(text, "scene-properties"))
    assert set(scene) == set(SCENE_ELEMENT_MODELS)
    common = table_keys(section(text, "scene-common"))
    assert {"name", "position", "rotation", "transform", "color", "visible"} <= set(common)
    for kind, keys in scene.items():
        assert set(keys) | set(common) == set(SCENE_ELEMENT_MODELS[kind].model_fields), kind
        first = next(iter(SCENE_ELEMENT_MODELS.values())).model_fields
        redefined = {k for k in keys if k in common and SCENE_ELEMENT_MODELS[kind].model_fields[k].description != first[k].description}
        assert not (set(keys) & set(common)) - redefined, kind  # a common key only where the kind gives it its own meaning
    listed = re.findall(r"^\| \[?`([a-z0-9_]+)`", section(text, "view-elements"), re.M)
    assert listed == [*GUI_ELEMENT_MODELS, "scene"]
    assert re.findall(r"^\| \[`([a-z0-9_]+)`", section(text, "scene-elements"), re.M) == list(SCENE_ELEMENT_MODELS)
    for name, model in [("top-level", Spec), ("variable", Variable), ("model", Model), ("ode", Ode), ("events", OdeEvent),
                        ("program", Program), ("simulation", Simulation)]:
        assert table_keys(section(text, name)) == list(model.model_fields), name
    # every kind heading anywhere in the document is a kind of the language
    headings = set(re.findall(r"^#### `([a-z0-9_]+)`", text, re.M))
    assert headings == set(GUI_ELEMENT_MODELS) | set(SCENE_ELEMENT_MODELS)


def test_the_prelude_table_lists_what_the_compiler_accepts() -> None:
    from ejsgen.validate import PRELUDE_NAMES

    text = LANGUAGE.read_text(encoding="utf-8")
    prelude = section(text, "prelude")
    first_cells = [row.split(" | ")[0] for row in prelude.splitlines() if row.startswith("| `")]
    documented = {name for cell in first_cells for name in re.findall(r"`([a-z_0-9]+)[(`]", cell)}
    assert set(PRELUDE_NAMES) <= documented
    assert documented - set(PRELUDE_NAMES) == set()
    # and a spec that names a variable after one of them is refused, as the page says
    assert "`capture`" in section(text, "reserved") and "`eval`" in section(text, "reserved")


def _check_view_items(items: Any, where: str) -> None:
    """Each item is a one-key mapping of a known kind whose properties the model accepts."""
    assert isinstance(items, list), where
    for item in items:
        assert isinstance(item, dict) and len(item) == 1, f"{where}: {item!r}"
        (kind, props), = item.items()
        if kind == "scene":
            _check_scene_items(props, where)
            continue
        assert kind in GUI_ELEMENT_MODELS, f"{where}: '{kind}' is not a view element"
        GUI_ELEMENT_MODELS[kind].model_validate(props)
        if kind == "folder":
            _check_view_items(props.get("children", []), where)
        if kind == "tabs":
            for children in props["tabs"].values():
                _check_view_items(children, where)


def _check_scene_items(items: Any, where: str) -> None:
    assert isinstance(items, list), where
    for item in items:
        (kind, props), = item.items()
        assert kind in SCENE_ELEMENT_MODELS, f"{where}: '{kind}' is not a 3D element"
        SCENE_ELEMENT_MODELS[kind].model_validate(props)
        if kind == "group":
            _check_scene_items(props.get("children", []), where)


def test_the_references_snippets_use_only_known_kinds_and_keys() -> None:
    checked = 0
    for i, block in enumerate(yaml_blocks(LANGUAGE)):
        data = yaml.safe_load(block)
        where = f"specs/language.md yaml block {i}"
        if isinstance(data, dict) and "view" in data:
            _check_view_items(data["view"], where)
            checked += 1
        elif isinstance(data, list):
            _check_view_items(data, where)
            checked += 1
        elif isinstance(data, dict) and "model" in data:
            Model.model_validate(data["model"])
            checked += 1
    assert checked >= 8


# -- every complete spec in the documents builds and runs -------------------------------------------


def run_headless(app_dir: Path, duration: float) -> dict[str, np.ndarray]:
    from ejsrl.app import load_app

    app = load_app(app_dir)
    assert app.error is None, app.error
    out = io.StringIO()
    assert app.run_headless(duration, csv_file=out, log=io.StringIO()) == 0
    data = np.genfromtxt(io.StringIO(out.getvalue()), delimiter=",", names=True, deletechars="")
    return {name: np.atleast_1d(data[name]) for name in data.dtype.names}


@pytest.mark.parametrize("name,block", complete_specs(), ids=[n for n, _ in complete_specs()])
def test_every_complete_spec_in_the_docs_builds_and_runs(tmp_path: Path, name: str, block: str) -> None:
    from ejsrl.app import load_app

    spec = tmp_path / f"{name}.ejs.yaml"
    spec.write_text(block, encoding="utf-8")
    assert main(["build", str(spec), "-o", str(tmp_path / "app")]) == 0
    app = load_app(tmp_path / "app")
    assert app.error is None, app.error
    if app.model.INDEPENDENT is not None:
        d = run_headless(tmp_path / "app", 1.0)
        t = d[app.model.INDEPENDENT]
        assert len(t) > 2 and t[-1] == pytest.approx(t[0] + 1.0, abs=0.05)


def test_the_docs_hold_several_complete_specs() -> None:
    names = [n for n, _ in complete_specs()]
    assert sum(n.startswith("language") for n in names) >= 4
    assert sum(n.startswith("tutorial") for n in names) >= 2


# -- the tutorial shows the step files -------------------------------------------------------------


def test_the_tutorials_snippets_are_the_step_files() -> None:
    shown: set[str] = set()
    for block in yaml_blocks(TUTORIAL):
        first = block.splitlines()[0]
        m = re.match(r"# (examples/tutorial/\S+\.ejs\.yaml)", first)
        if m is None:
            continue
        path = ROOT / m.group(1)
        assert path.is_file(), f"the tutorial shows {m.group(1)}, which does not exist"
        shown.add(path.name)
        lines = path.read_text(encoding="utf-8").splitlines()
        if is_complete(block):
            assert block.splitlines() == lines, f"the tutorial's copy of {path.name} differs from the file"
            continue
        # a fragment: its lines appear in the file in the same order ("..." skips lines)
        at = 0
        for line in block.splitlines()[1:]:
            if line.strip() == "...":
                continue
            try:
                at = lines.index(line, at) + 1
            except ValueError:
                pytest.fail(f"the tutorial's snippet of {path.name} has a line the file does not have (in that order): {line!r}")
    assert shown == {p.name for p in STEPS}
    assert len(STEPS) == 7


def test_the_error_the_docs_show_is_the_one_ejsgen_prints(tmp_path: Path, monkeypatch, capsys) -> None:
    step1 = next(p for p in STEPS if p.name.startswith("step1_"))
    (tmp_path / "pendulum.ejs.yaml").write_text(step1.read_text().replace("sin(theta)", "sin(thta)"))
    monkeypatch.chdir(tmp_path)
    assert main(["validate", "pendulum.ejs.yaml"]) == 1
    printed = capsys.readouterr().err.strip()
    for doc in (TUTORIAL, LANGUAGE):
        shown = re.findall(r"^ *(pendulum\.ejs\.yaml:\d+:\d+: error: .*)$", doc.read_text(encoding="utf-8"), re.M)
        assert shown == [printed], doc.name


# -- each step builds, runs and does what it teaches -----------------------------------------------


@pytest.fixture(scope="module")
def step_app(tmp_path_factory: pytest.TempPathFactory):
    """Build a tutorial step through the ``ejsgen build`` command: ``step_app(3)`` -> App."""
    from ejsrl.app import load_app

    built: dict[int, Path] = {}

    def _load(n: int, **overrides: Any):
        if n not in built:
            spec = next(p for p in STEPS if p.name.startswith(f"step{n}_"))
            out = tmp_path_factory.mktemp("tutorial") / spec.name.split(".")[0]
            assert main(["build", str(spec), "-o", str(out)]) == 0
            built[n] = out
        app = load_app(built[n], overrides=overrides or None)
        assert app.error is None, app.error
        return app, built[n]

    return _load


def elements(view: list[Any]):
    from ejsrl.view.elements import Folder, Tabs

    for e in view:
        yield e
        if isinstance(e, Folder):
            yield from elements(e.children)
        elif isinstance(e, Tabs):
            for _, children in e.tabs:
                yield from elements(children)


def control(app, bind: str):
    from ejsrl.view.elements import Control

    return next(c for c in elements(app.view) if isinstance(c, Control) and c.bind == bind)


def button(app, label: str):
    from ejsrl.view.elements import Button

    return next(b for b in elements(app.view) if isinstance(b, Button) and b.label == label)


def set_from_ui(app, bind: str, value: Any) -> None:
    """What a browser does: the value is validated (clamped) first, then applied."""
    from ejsrl.view._validate import validate_control

    c = control(app, bind)
    checked = validate_control(c, value)
    assert checked.ok, checked.message
    app.apply_control(c, checked.value)


def run_for(app, duration: float, names: list[str]) -> dict[str, np.ndarray]:
    """Step the app for ``duration`` simulated seconds, recording ``names`` after each step."""
    m = app.model
    rows = [[float(getattr(m, n)) for n in names]]
    t_end = m.t + duration
    app.play()
    while m.t < t_end - 1e-9:
        app.step_once()
        rows.append([float(getattr(m, n)) for n in names])
    assert app.error is None, app.error
    return dict(zip(names, np.array(rows).T))


def upward_crossings(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    i = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    return t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])


def pendulum_period(L: float, theta0: float, g: float = 9.81) -> float:
    """The exact period of a pendulum released at rest from ``theta0``: 4 sqrt(L/g) K(sin²(θ0/2))."""
    return 4 * sqrt(L / g) * ellipk(np.sin(theta0 / 2) ** 2)


def test_step0_ejsgen_new_writes_a_damped_spring_that_oscillates_at_its_frequency(tmp_path: Path, capsys) -> None:
    from ejsrl.app import load_app

    assert main(["new", str(tmp_path / "spring")]) == 0
    assert "ejsgen docs" in (tmp_path / "spring.ejs.yaml").read_text()
    assert main(["build", str(tmp_path / "spring.ejs.yaml"), "-o", str(tmp_path / "app")]) == 0
    m = load_app(tmp_path / "app").model
    k, mass, c = m.k, m.m, m.c
    d = run_headless(tmp_path / "app", 20.0)
    ups = upward_crossings(d["t"], d["x"])
    omega_d = sqrt(k / mass - (c / (2 * mass)) ** 2)
    assert len(ups) >= 4
    assert np.diff(ups).mean() == pytest.approx(2 * pi / omega_d, rel=1e-4)


def test_step1_small_swings_have_the_period_2pi_sqrt_L_over_g(step_app) -> None:
    app, folder = step_app(1, theta=0.02)
    d = run_for(app, 12.0, ["t", "theta"])
    period = np.diff(upward_crossings(d["t"], d["theta"])).mean()
    assert period == pytest.approx(2 * pi * sqrt(1.0 / 9.81), rel=1e-4)  # (1 + θ0²/16) = 1 + 2.5e-5
    # the spec's own swing (0.2 rad) is already 0.25 % slower: the exact period, not the small-angle one
    app, _ = step_app(1)
    d = run_for(app, 12.0, ["t", "theta"])
    period = np.diff(upward_crossings(d["t"], d["theta"])).mean()
    assert period == pytest.approx(pendulum_period(1.0, 0.2), rel=2e-5)
    assert period / (2 * pi * sqrt(1.0 / 9.81)) > 1.002


def test_step2_plots_theta_and_omega_and_the_energy_stays_constant(step_app) -> None:
    from ejsrl.view.elements import Plot

    app, _ = step_app(2)
    plots = [e for e in elements(app.view) if isinstance(e, Plot)]
    assert [len(p.series) for p in plots] == [2, 1]
    d = run_for(app, 5.0, ["t", "E"])
    assert d["E"][0] == pytest.approx(9.81 * (1 - np.cos(0.2)), rel=1e-12)  # the fixed relation ran after init
    assert np.ptp(d["E"]) / d["E"][0] < 1e-6


def test_step3_the_length_slider_changes_the_period_and_is_clamped_and_kick_pushes(step_app) -> None:
    app, _ = step_app(3, theta=0.02)
    set_from_ui(app, "L", 2.0)
    assert app.model.L == 2.0
    d = run_for(app, 12.0, ["t", "theta"])
    assert np.diff(upward_crossings(d["t"], d["theta"])).mean() == pytest.approx(2 * pi * sqrt(2.0 / 9.81), rel=1e-4)
    set_from_ui(app, "L", 10.0)  # beyond the slider's max
    assert app.model.L == 3.0
    omega = app.model.omega
    app.run_action(button(app, "Kick"))
    assert app.model.omega == pytest.approx(omega + 1.0)
    # damping: small swings lose energy as exp(-b t) on average
    app, _ = step_app(3)
    set_from_ui(app, "b", 0.4)
    d = run_for(app, 10.0, ["t", "E"])
    assert d["E"][-1] / d["E"][0] == pytest.approx(np.exp(-0.4 * 10), rel=0.15)


def test_step4_the_event_measures_the_exact_period(step_app) -> None:
    app, _ = step_app(4)
    run_for(app, 9.0, ["t"])
    m = app.model
    exact = pendulum_period(1.0, 0.2)
    assert m.period == pytest.approx(exact, rel=1e-7)  # located in time, far better than dt = 0.01
    assert m.passes == int((9.0 - 0.75 * exact) // exact) + 1  # first pass going right at 3/4 of a period
    assert m.T_small == pytest.approx(2 * pi * sqrt(1.0 / 9.81))


def test_step5_the_bob_in_the_scene_is_where_the_pendulum_is(step_app) -> None:
    app, _ = step_app(5)
    run_for(app, 0.37, ["t"])
    m = app.model
    pose = app.world_functions().object_pose("bob")
    assert np.allclose(pose[:3, 3], [m.L * np.sin(m.theta), 0.0, -m.L * np.cos(m.theta)], atol=1e-9)
    set_from_ui(app, "L", 2.0)  # the drawing follows a slider at once
    pose = app.world_functions().object_pose("bob")
    assert np.linalg.norm(pose[:3, 3]) == pytest.approx(2.0)
    assert all(name in app.world for name in ("support", "rod", "bob", "path"))


def dh(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """One standard Denavit-Hartenberg link transform Rz(theta) Tz(d) Tx(a) Rx(alpha), written out."""
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0.0, sa, ca, d], [0.0, 0.0, 0.0, 1.0]])


def rrr_tool(q: np.ndarray) -> np.ndarray:
    """The tool position of the 3R arm (d1 = 0.4, alpha1 = 90°; a2 = 0.4; a3 = 0.3)."""
    T = dh(q[0], 0.4, 0.0, pi / 2) @ dh(q[1], 0.0, 0.4, 0.0) @ dh(q[2], 0.0, 0.3, 0.0)
    return T[:3, 3]


def test_step6_joint_sliders_move_the_tool_and_reach_solves_inverse_kinematics(step_app) -> None:
    app, _ = step_app(6)
    m = app.model
    assert [control(app, f"q[{j}]").bind for j in range(3)] == ["q[0]", "q[1]", "q[2]"]
    set_from_ui(app, "q[1]", 0.5)
    set_from_ui(app, "q[0]", -1.0)
    assert m.q.tolist() == pytest.approx([-1.0, 0.5, -1.2], abs=1e-9)
    assert np.allclose(m.tool, rrr_tool(m.q), atol=1e-12)
    for j, value in enumerate([0.35, -0.2, 0.6]):
        set_from_ui(app, f"target[{j}]", value)
    app.run_action(button(app, "Reach"))
    assert m.status == "Reached."
    assert np.allclose(rrr_tool(m.q), [0.35, -0.2, 0.6], atol=1e-6)
    assert np.allclose(m.tool, [0.35, -0.2, 0.6], atol=1e-6)
    q = m.q.copy()
    for j, value in enumerate([1.0, 1.0, 1.2]):  # 1.4 m from the shoulder; the arm is 0.7 m long
        set_from_ui(app, f"target[{j}]", value)
    app.run_action(button(app, "Reach"))
    assert m.status == "Out of reach."
    assert np.array_equal(m.q, q)


def test_step7_the_camera_sees_the_red_block_where_a_pinhole_projects_it(step_app) -> None:
    app, _ = step_app(7)
    image = app.capture("eye")
    assert image.shape == (240, 320, 3) and image.dtype == np.uint8
    # an independent look-at pose and pinhole projection of the block's centre
    eye, target = np.array([1.1, -0.8, 0.9]), np.array([0.15, 0.15, 0.35])
    z = (target - eye) / np.linalg.norm(target - eye)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    p = np.array([0.3, 0.3, 0.05]) - eye
    f = 0.5 * 240 / np.tan(np.radians(50) / 2)
    u, v = f * (p @ x) / (p @ z) + 159.5, f * (p @ y) / (p @ z) + 119.5
    red = (image[..., 0] > 150) & (image[..., 1] < 80) & (image[..., 2] < 80)
    rows, cols = np.nonzero(red)
    assert red.sum() > 100
    assert abs(cols.mean() - u) < 4 and abs(rows.mean() - v) < 4
    # the arm moves in the image when a joint slider moves
    set_from_ui(app, "q[0]", 1.5)
    assert np.abs(app.capture("eye").astype(int) - image.astype(int)).sum() > 1000


def test_ejsgen_docs_prints_the_reference_and_says_where_the_tutorial_is(capsys) -> None:
    assert main(["docs"]) == 0
    assert capsys.readouterr().out == LANGUAGE.read_text(encoding="utf-8")
    assert main(["docs", "tutorial", "--path"]) == 0
    assert Path(capsys.readouterr().out.strip()).read_text(encoding="utf-8") == TUTORIAL.read_text(encoding="utf-8")


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def test_every_link_inside_the_documents_leads_to_a_heading() -> None:
    anchors = {}
    for doc in (LANGUAGE, TUTORIAL):
        text = doc.read_text(encoding="utf-8")
        anchors[doc.name] = {slug(h) for h in re.findall(r"^#+ (.*)$", text, re.M)}
    for doc in (LANGUAGE, TUTORIAL):
        for target_doc, anchor in re.findall(r"\]\(((?:language|tutorial)\.md)?#([^)]+)\)", doc.read_text(encoding="utf-8")):
            assert anchor in anchors[target_doc or doc.name], f"{doc.name} links to #{anchor}, which is no heading of {target_doc or doc.name}"


def test_the_wheel_ships_the_documents_for_ejsgen_docs() -> None:
    import tomllib

    from ejsgen._docs import DOC_FILES, docs_dir

    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert config["package-dir"]["ejsgen.specs"] == "specs" and "ejsgen.specs" in config["packages"]
    assert "*.md" in config["package-data"]["ejsgen.specs"]
    assert docs_dir() is not None
    for name in DOC_FILES.values():
        assert (docs_dir() / name).is_file()


def test_readme_points_to_the_shipped_reference_and_tutorial() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "specs/language.md" in readme and "specs/tutorial.md" in readme
    assert "../shared" not in readme
    for doc in (LANGUAGE, TUTORIAL):  # every relative link in the documents leads to a file
        for target in re.findall(r"\]\(((?:\.\./|[a-z])[^)#:]*)(?:#[^)]*)?\)", doc.read_text(encoding="utf-8")):
            assert (doc.parent / target).exists(), f"{doc.name} links to {target}, which does not exist"
