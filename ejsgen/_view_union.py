"""The view tree as one pydantic type: lists of elements discriminated on their key.

A view element is a one-key mapping ``kind: {properties}``; each kind is a one-field model
(``SliderItem`` with the field ``slider: SliderEl``) tagged with its kind, and a list of
elements is a list of their union, discriminated on the mapping's only key. Folders, tabs,
scenes and groups hold such lists, so one ``validate_python`` checks the whole tree.

Only the kinds a list may hold are its tags: a GUI list (the view, a folder's children, a
tab) holds the GUI kinds and ``scene``; a 3D list (a scene, a group's children) holds the
3D kinds. An item that is not a one-key mapping of such a kind fails with the error type
``VIEW_ELEMENT`` or ``SCENE_ELEMENT`` at the item; ``ejsgen.validate`` words it.

The element models of ``ejsgen.spec`` stay as they are (they make the JSON Schema): the
models here are subclasses whose ``children``/``tabs`` are typed as element lists.
"""

from __future__ import annotations

from typing import Annotated, Any, Union

from pydantic import Discriminator, Field, Tag, TypeAdapter, create_model

from ejsgen import spec
from ejsgen.spec import GUI_ELEMENT_MODELS, Derived, Strict

__all__ = ["VIEW_ELEMENT", "SCENE_ELEMENT", "view_adapter", "gui_models", "scene_models", "element_key"]

#: the pydantic error types of an item that is not an element of its list
VIEW_ELEMENT = "view_element"
SCENE_ELEMENT = "scene_element"


def element_key(kinds: Any) -> Any:
    """A discriminator: the key of a one-key mapping whose key is one of ``kinds``, else None."""

    def key(value: Any) -> str | None:
        if isinstance(value, dict) and len(value) == 1:
            (kind,) = value
            if kind in kinds:
                return kind
        elif isinstance(value, Strict):  # an already validated item
            return next(iter(value.model_fields_set), None)
        return None

    return key


def _items(models: dict[str, Any], error_type: str, what: str) -> Any:
    tagged = [
        Annotated[create_model(f"{name.capitalize()}Item", __base__=Derived, **{name: (model, ...)}), Tag(name)]  # type: ignore[call-overload]
        for name, model in models.items()
    ]
    return Annotated[Union[tuple(tagged)], Discriminator(element_key(set(models)), custom_error_type=error_type, custom_error_message=what)]


def _build() -> tuple[dict[str, Any], dict[str, Any], Any]:
    scene_models: dict[str, Any] = dict(spec.SCENE_ELEMENT_MODELS)
    gui_models: dict[str, Any] = dict(GUI_ELEMENT_MODELS)
    # the lists refer to the models that hold lists: declared by name, resolved below
    scene_models["group"] = create_model("GroupEl", __base__=scene_models["group"], children=("list[SceneElement]", Field(default_factory=list)))
    gui_models["folder"] = create_model("FolderEl", __base__=(gui_models["folder"], Derived), children=("list[ViewElement]", Field(default_factory=list)))
    gui_models["tabs"] = create_model("TabsEl", __base__=(gui_models["tabs"], Derived), tabs=("dict[str, list[ViewElement]]", ...))
    scene_element = _items(scene_models, SCENE_ELEMENT, "not a 3D element")
    gui_models["scene"] = list[scene_element]  # type: ignore[valid-type]
    view_element = _items(gui_models, VIEW_ELEMENT, "not a view element")
    names = {"SceneElement": scene_element, "ViewElement": view_element}
    for model in (scene_models["group"], gui_models["folder"], gui_models["tabs"]):
        model.model_rebuild(_types_namespace=names)
    del gui_models["scene"]
    return gui_models, scene_models, TypeAdapter(list[view_element])  # type: ignore[valid-type]


gui_models, scene_models, view_adapter = _build()
