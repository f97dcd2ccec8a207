"""The JSON Schema of the spec language (``ejsgen schema``; committed as specs/ejs.schema.json).

The view's elements are one-key mappings ``kind: {properties}``; pydantic cannot say that
directly, so the schema is assembled from the element models: a ``oneOf`` of single-key
objects for the GUI kinds (and ``scene``), and another for the 3D kinds.
"""

from __future__ import annotations

from typing import Any

from ejsgen import spec
from ejsgen.spec import GUI_ELEMENT_MODELS, Spec, Variable

__all__ = ["json_schema"]


def _one_key(kind: str, ref: dict[str, Any], description: str) -> dict[str, Any]:
    return {
        "type": "object",
        "description": description,
        "properties": {kind: ref},
        "required": [kind],
        "additionalProperties": False,
    }


def json_schema() -> dict[str, Any]:
    """The whole schema (draft 2020-12)."""
    scene_models = spec.SCENE_ELEMENT_MODELS  # derived from the kinds' declarations (ejsrl.world.kinds)
    schema = Spec.model_json_schema(ref_template="#/$defs/{model}")
    defs = schema.setdefault("$defs", {})
    for models in (GUI_ELEMENT_MODELS, scene_models):
        for cls in models.values():
            sub = cls.model_json_schema(ref_template="#/$defs/{model}")
            for name, d in sub.pop("$defs", {}).items():
                defs.setdefault(name, d)
            defs[cls.__name__] = sub
    var_schema = Variable.model_json_schema(ref_template="#/$defs/{model}")
    defs["Variable"] = var_schema
    scene_item = {
        "oneOf": [_one_key(k, {"$ref": f"#/$defs/{c.__name__}"}, c.__doc__ or k) for k, c in scene_models.items()],
    }
    defs["SceneItem"] = scene_item
    gui_items = [_one_key(k, {"$ref": f"#/$defs/{c.__name__}"}, c.__doc__ or k) for k, c in GUI_ELEMENT_MODELS.items()]
    gui_items.append(_one_key("scene", {"type": "array", "items": {"$ref": "#/$defs/SceneItem"}}, "The 3D world: a list of 3D elements."))
    defs["ViewItem"] = {"oneOf": gui_items}
    # children of folders, tabs and groups are view/scene items too
    defs["FolderEl"]["properties"]["children"]["items"] = {"$ref": "#/$defs/ViewItem"}
    defs["TabsEl"]["properties"]["tabs"]["additionalProperties"] = {"type": "array", "items": {"$ref": "#/$defs/ViewItem"}}
    defs["GroupEl"]["properties"]["children"]["items"] = {"$ref": "#/$defs/SceneItem"}
    schema["properties"]["view"]["items"] = {"$ref": "#/$defs/ViewItem"}
    schema["properties"]["model"] = {"$ref": "#/$defs/Model"} if "Model" in defs else schema["properties"]["model"]
    model_props = defs["Model"]["properties"]
    model_props["variables"]["additionalProperties"] = {
        "anyOf": [
            {"$ref": "#/$defs/Variable"},
            {"type": ["number", "boolean", "string"]},
            {"type": "array", "items": {"anyOf": [{"type": "number"}, {"type": "array"}]}},
        ]
    }
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "ejsgen spec (.ejs.yaml), version 1"
    return schema
