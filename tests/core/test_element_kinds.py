"""Every 3D element kind is declared once (ejsrl.world.kinds) and reaches every consumer.

The consumers: the spec language's pydantic models, the JSON Schema, the reference tables
of specs/language.md, the compiler's property types, the world's node classes and their
defaults, the scene binding, and the browser mirror's drawing handlers. A kind missing
from any of them fails here; a kind added to the declarations alone shows up in all.
"""

from __future__ import annotations

import importlib
import inspect
import json
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from pydantic import ValidationError

from ejsgen import _docs, _view_union, spec, validate
from ejsgen.cli import main
from ejsgen._view_compile import _ELEMENT_COMPILERS, _OWN_PROPS, _PROP_COMPILERS, own_props
from ejsgen._view_union import view_adapter
from ejsgen.schema import json_schema
from ejsrl.view import _scene_mirror as mirror_mod
from ejsrl.view.elements import Node3D
from ejsrl.world import binding, kinds, scene
from ejsrl.world.kinds import COMMON, DRAW_STYLES, KINDS, PROP_TYPES, REQUIRED, Kind, Prop

ROOT = Path(__file__).resolve().parents[2]


def _node_class(kind: Kind) -> type[scene.Node]:
    if kind.node_module is None:
        return scene.NODE_KINDS[kind.name]
    module = importlib.import_module(kind.node_module)
    found = [c for c in vars(module).values() if isinstance(c, type) and issubclass(c, scene.Node) and c.__dict__.get("kind") == kind.name]
    assert len(found) == 1, f"{kind.node_module} defines no node class for '{kind.name}'"
    return found[0]


def _required(kind: Kind) -> dict[str, Any]:
    """Values for a kind's required properties."""
    out: dict[str, Any] = {p.name: "x" for p in kind.props if p.required and p.type in ("text", "file", "expr", "bind")}
    out |= {p.name: [0, 0, 1] for p in kind.props if p.required and p.type in ("vec3", "vec")}
    out |= {p.name: [[0, 0, 0]] for p in kind.props if p.required and p.type == "mat"}
    return out


# -- every declared kind reaches every consumer -------------------------------------------------


@pytest.mark.parametrize("name", list(KINDS))
def test_each_kind_has_a_spec_model_with_its_declared_properties(name: str) -> None:
    kind = KINDS[name]
    model = spec.SCENE_ELEMENT_MODELS[name]
    common = [p.name for p in COMMON]  # a kind may give a common key its own meaning (an ellipse's position): in its place
    assert list(model.model_fields) == common + [p.name for p in kind.props if p.name not in common]
    assert model.__doc__ == kind.doc
    for p in kind.props:
        info = model.model_fields[p.name]
        assert info.description == p.doc
        assert info.is_required() == p.required, p.name
    element = model.model_validate(_required(kind))
    for p in kind.props:
        if not p.required:
            got = getattr(element, p.name)
            assert got == (list(p.default) if isinstance(p.default, tuple) else p.default), p.name


@pytest.mark.parametrize("name", list(KINDS))
def test_each_kind_is_validated_in_a_scene_and_a_group(name: str) -> None:
    props = _required(KINDS[name])
    (scene_item,) = view_adapter.validate_python([{"scene": [{"group": {"children": [{name: props}]}}]}])
    (inner,) = scene_item.scene[0].group.children
    assert type(getattr(inner, name)).__name__ == f"{name.capitalize()}El"
    with pytest.raises(ValidationError):
        view_adapter.validate_python([{name: props}])  # a 3D element outside a scene


def test_every_view_element_kind_is_validated_and_compiled() -> None:
    assert set(_ELEMENT_COMPILERS) == set(spec.GUI_ELEMENT_MODELS) | {"scene"}
    assert set(_view_union.gui_models) == set(spec.GUI_ELEMENT_MODELS)
    assert list(_view_union.scene_models) == list(KINDS)


@pytest.mark.parametrize("name", list(KINDS))
def test_each_kind_is_in_the_json_schema_and_the_committed_one(name: str) -> None:
    committed = json.loads((ROOT / "specs" / "ejs.schema.json").read_text(encoding="utf-8"))
    for schema in (json_schema(), committed):
        items = schema["$defs"]["SceneItem"]["oneOf"]
        (item,) = [i for i in items if name in i["properties"]]
        ref = item["properties"][name]["$ref"].rsplit("/", 1)[1]
        props = schema["$defs"][ref]["properties"]
        assert set(props) == {p.name for p in COMMON} | {p.name for p in KINDS[name].props}
        assert [props[p.name]["description"] for p in KINDS[name].props] == [p.doc for p in KINDS[name].props]


def test_each_kind_has_a_table_in_the_language_reference() -> None:
    text = (ROOT / "specs" / "language.md").read_text(encoding="utf-8")
    listed = _docs.generate("scene-elements")
    per_kind = _docs.generate("scene-properties")
    for name, kind in KINDS.items():
        assert f"[`{name}`](#{name})" in listed and f"[`{name}`](#{name})" in text
        for p in kind.props:
            assert f"| `{p.name}` |" in per_kind and p.doc.replace("|", "\\|") in per_kind, (name, p.name)
    assert per_kind in text  # the committed reference is current


@pytest.mark.parametrize("name", list(KINDS))
def test_each_kind_has_compiled_property_types(name: str) -> None:
    kind = KINDS[name]
    assert _OWN_PROPS[name] == {p.name: p.type for p in kind.props if p.is_value}
    for ptype in _OWN_PROPS[name].values():
        assert ptype in _PROP_COMPILERS, f"the compiler cannot compile a '{ptype}' property"


@pytest.mark.parametrize("name", list(KINDS))
def test_each_kind_has_a_world_node_holding_its_properties(name: str) -> None:
    kind = KINDS[name]
    cls = _node_class(kind)
    held = set(cls.DEFAULTS) | set(inspect.signature(cls.__init__).parameters)  # a robot takes model, q, base itself
    for p in kind.props:
        if p.in_node:
            assert p.name in held, f"the {name} node does not hold '{p.name}'"
    if kind.node_module is None:
        node = cls("n")
        assert set(kind.node_extra) <= set(node.props)
        for p in kind.props:
            if p.in_node:
                assert np.array_equal(np.asarray(node.props[p.name], dtype=object), np.asarray(p.initial(), dtype=object)), p.name
    else:
        assert name in binding._FACTORIES, f"'{name}' has its node elsewhere but the scene binding cannot make it"


@pytest.mark.parametrize("name", list(KINDS))
def test_each_kind_has_mirror_handlers(name: str) -> None:
    style = KINDS[name].draw
    assert style in DRAW_STYLES
    assert mirror_mod._style(name) == style
    assert style in mirror_mod._BUILDERS and style in mirror_mod._PROP_UPDATERS


def test_every_style_and_property_type_has_its_handlers() -> None:
    assert set(mirror_mod._BUILDERS) == set(DRAW_STYLES) == set(mirror_mod._PROP_UPDATERS)
    assert set(spec._ANNOTATIONS) == set(PROP_TYPES)
    value_types = {t for t in PROP_TYPES if Prop("p", t, None, "").is_value} - {"name", "flag", "color"}  # common-only types
    assert value_types <= set(_PROP_COMPILERS)
    assert set(_PROP_COMPILERS) <= set(PROP_TYPES)


def test_the_runtime_record_of_a_3d_element_is_checked_against_the_declarations() -> None:
    """An app (or a script) that names a kind or property no kind declares hears so at once,
    instead of the property being silently dropped from the world."""
    Node3D("sphere", "ball", props={"radius": 0.1})
    with pytest.raises(ValueError, match=r"lab.ejs.yaml:3:5: a sphere has no property 'radus'; did you mean 'radius'\?"):
        Node3D("sphere", "ball", props={"radus": 0.1}, where="lab.ejs.yaml:3:5")
    with pytest.raises(ValueError, match=r"unknown 3D element kind 'cylindre'; did you mean 'cylinder'\?"):
        Node3D("cylindre", "post")
    with pytest.raises(ValueError, match=r"a group has no property 'size' \(it has: none\)"):
        Node3D("group", "g", props={"size": 1.0})


def test_a_declaration_with_an_unknown_type_or_style_is_refused() -> None:
    with pytest.raises(ValueError, match="unknown property type 'vector3'"):
        Prop("tip", "vector3", REQUIRED, "Where its tip is.")
    with pytest.raises(ValueError, match="unknown drawing style 'cone'"):
        Kind("cone", "A cone.", (), draw="cone")


def test_the_dead_copies_of_the_kind_lists_are_gone() -> None:
    import ejsrl.view.elements as elements

    assert not hasattr(spec, "VIEW_KINDS") and not hasattr(elements, "GUI_KINDS")


# -- one declaration is enough --------------------------------------------------------------------


class _FakeScene:
    """Records what a SceneMirror asks viser to add."""

    def __init__(self) -> None:
        self.added: list[tuple[str, str]] = []

    def __getattr__(self, name: str) -> Any:
        if not name.startswith("add_"):
            raise AttributeError(name)

        def add(path: str, *args: Any, **kwargs: Any) -> Any:
            self.added.append((name, path))
            return SimpleNamespace(remove=lambda: None, on_update=lambda fn: fn)

        return add


def test_a_kind_added_to_the_declarations_alone_reaches_every_consumer(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cone = Kind(
        "cone",
        "A cone along its local z axis.",
        (
            Prop("radius", "num", 0.25, "Base radius in metres."),
            Prop("tip", "vec3", REQUIRED, "Where its tip is.", node_default=(0.0, 0.0, 1.0)),
            Prop("size", "num", 0.3, "Axis length."),
        ),
        draw="frame",
    )
    monkeypatch.setitem(kinds.KINDS, "cone", cone)

    models = spec._scene_models()
    assert list(models["cone"].model_fields)[-3:] == ["radius", "tip", "size"]
    assert models["cone"].model_validate({"tip": [0, 0, 2]}).radius == 0.25
    with pytest.raises(Exception, match="tip"):
        models["cone"].model_validate({})
    monkeypatch.setattr(spec, "SCENE_ELEMENT_MODELS", models)
    schema = json_schema()
    assert any("cone" in item["properties"] for item in schema["$defs"]["SceneItem"]["oneOf"])
    assert schema["$defs"]["ConeEl"]["properties"]["radius"]["description"] == "Base radius in metres."
    assert "[`cone`](#cone)" in _docs.generate("scene-elements")
    assert "Where its tip is." in _docs.generate("scene-properties")

    assert own_props()["cone"] == {"radius": "num", "tip": "vec3", "size": "num"}

    # validated and compiled: a spec with a cone builds into an app that declares it
    gui_models, scene_models, adapter = _view_union._build()
    monkeypatch.setattr(validate, "view_adapter", adapter)
    monkeypatch.setattr(validate, "scene_models", scene_models)
    monkeypatch.setattr(validate, "SCENE_ELEMENT_MODELS", models)
    spec_file = tmp_path / "cone.ejs.yaml"
    spec_file.write_text("ejs: 1\ntitle: Cone\nmodel:\n  variables:\n    h: 2.0\nview:\n  - scene:\n      - cone: {tip: [0, 0, h]}\n")
    assert main(["build", str(spec_file), "-o", str(tmp_path / "app")]) == 0
    app = (tmp_path / "app" / "app.py").read_text(encoding="utf-8")
    assert "kind='cone'" in app and "'radius': 0.25" in app and "'[0, 0, h]'" in app
    spec_file.write_text("ejs: 1\ntitle: Cone\nview:\n  - scene:\n      - cone: {radius: 1}\n")
    assert main(["validate", str(spec_file)]) == 1
    assert "5:15: error: missing required key 'tip'" in capsys.readouterr().err

    classes = scene._node_classes()
    node_cls = classes["cone"]
    assert node_cls.DEFAULTS == {"radius": 0.25, "tip": (0.0, 0.0, 1.0), "size": 0.3}
    monkeypatch.setattr(scene, "NODE_KINDS", classes)
    monkeypatch.setattr(binding, "NODE_KINDS", classes)
    sync = binding.SceneSync([Node3D(kind="cone", name="c", props={"radius": 0.5, "tip": (1.0, 2.0, 3.0), "size": 0.3})])
    node = sync.world["c"]
    assert node.kind == "cone" and node.props["radius"] == 0.5 and node.props["tip"] == (1.0, 2.0, 3.0)

    fake = _FakeScene()
    m = mirror_mod.SceneMirror(fake)
    m.sync(sync.world)
    assert ("add_frame", "/ejs/c/g0") in fake.added  # drawn in its declared style
