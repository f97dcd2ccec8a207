"""The view's per-frame writes to viser handles, without viser's per-call overhead.

Every frame of every session sets a few properties: the bob's position, the rod's points,
the time readout, a label. Through viser 1.1's attribute setters each of these costs
about 0.1 ms: ``props_setattr`` builds ``npt.NDArray[...]`` typing aliases on every call
to compare against the property's hint, and the pose setters run ``np.allclose``. With 40
sessions at 30 frames/s that was half of the server's frame cost (``bench/classroom.py
--spy``). These functions do what viser's setters do for the values the view sends — the
same skip when nothing changed, the same stored state, the same update message — with
the type work done once per property; anything they do not know goes through viser's own
setter. ``tests/view/test_wire.py`` checks them message by message against viser's.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt
from viser import _messages
from viser._assignable_props_api import AssignablePropsBase

__all__ = ["set_markdown", "set_position", "set_prop", "set_wxyz"]

#: a property's type hint -> the dtype viser casts its arrays to
_ARRAY_HINTS: dict[Any, Any] = {
    npt.NDArray[np.float16]: np.float16,
    npt.NDArray[np.float32]: np.float32,
    npt.NDArray[np.float64]: np.float64,
}
_TUPLE_HINTS: dict[Any, Any] = {}
_SCALARS = (str, bool, int, float, type(None))


def set_prop(handle: Any, name: str, value: Any) -> None:
    """``handle.<name> = value`` for a plain viser property (no Python setter of its own)."""
    if not isinstance(handle, AssignablePropsBase):  # a stand-in (tests' fake scenes)
        setattr(handle, name, value)
        return
    hint = handle._prop_hints.get(name)
    dtype = _ARRAY_HINTS.get(hint) if hint is not None else None
    element_dtype = _tuple_of_arrays(hint) if dtype is None and isinstance(value, tuple) else None
    if element_dtype is not None:
        _set_arrays(handle, name, value, element_dtype)
        return
    if hint is None or isinstance(getattr(type(handle), name, None), property) or (
        dtype is None and not isinstance(value, _SCALARS)
    ):
        setattr(handle, name, value)  # colours, tuples, setters of its own: viser's own path
        return
    impl = _live(handle, name)
    current = getattr(impl.props, name)
    if dtype is None:
        if isinstance(current, np.ndarray):
            setattr(handle, name, value)
            return
        if current == value:
            return
        setattr(impl.props, name, value)
        queued = value
    else:
        arr = np.asarray(value).astype(dtype)
        if hasattr(current, "dtype"):
            if arr.dtype != current.dtype:
                arr = arr.astype(current.dtype)
            if np.array_equal(current, arr):
                return
        if hasattr(current, "shape") and arr.shape == current.shape:
            current[:] = arr
        else:
            setattr(impl.props, name, arr.copy())
        queued = arr  # astype made it ours: it aliases neither the caller's value nor the stored one
    handle._queue_update(name, queued)
    handle._on_prop_assigned(name)


def _tuple_of_arrays(hint: Any) -> Any:
    """The element dtype of a ``tuple[NDArray[...], ...]`` hint (a plot's data), else None."""
    try:
        return _TUPLE_HINTS[hint]
    except KeyError:
        args = getattr(hint, "__args__", ())
        dtype = None
        if getattr(hint, "__origin__", None) is tuple and len(args) == 2 and args[1] is ...:
            dtype = _ARRAY_HINTS.get(args[0])
        _TUPLE_HINTS[hint] = dtype
        return dtype
    except TypeError:  # an unhashable hint
        return None


def _live(handle: Any, name: str) -> Any:
    """The handle's state; viser's refusal of a write to a removed handle."""
    impl = handle._impl
    if impl.removed:
        raise RuntimeError(f"Cannot assign to {name!r} on a removed {type(handle).__name__}.")
    return impl


def _set_arrays(handle: Any, name: str, value: tuple[Any, ...], dtype: Any) -> None:
    impl = _live(handle, name)
    cast = tuple(np.asarray(v).astype(dtype) for v in value)
    setattr(impl.props, name, cast)
    handle._queue_update(name, cast)
    handle._on_prop_assigned(name)


def _close(a: tuple[float, ...], b: np.ndarray) -> bool:
    """``np.allclose(a, b)`` with its default tolerances, for a short vector."""
    for x, y in zip(a, b.tolist()):
        if not abs(x - y) <= 1e-8 + 1e-5 * abs(y):
            if not (math.isinf(x) and x == y):
                return False
    return True


def _pose(handle: Any, attr: str, value: Any, length: int, message: type) -> None:
    if not isinstance(handle, AssignablePropsBase):  # a stand-in (tests' fake scenes)
        setattr(handle, attr, value)
        return
    if isinstance(value, np.ndarray):
        if value.shape != (length,):
            raise ValueError(f"Expected vector of shape {(length,)}, but got {value.shape} instead")
        cast = tuple(value.astype(float).tolist())
    else:
        if len(value) != length:
            raise ValueError(f"Expected vector of length {length}, but got {len(value)} instead")
        cast = tuple(map(float, value))
    impl = handle._impl
    current = getattr(impl, attr)
    if _close(cast, current):
        return
    current[:] = cast
    impl.api._queue_scene_message(message(impl.name, cast))


def set_position(handle: Any, xyz: Any) -> None:
    """``handle.position = xyz`` for a scene node."""
    _pose(handle, "position", xyz, 3, _messages.SetPositionMessage)


def set_wxyz(handle: Any, wxyz: Any) -> None:
    """``handle.wxyz = wxyz`` for a scene node (a unit quaternion)."""
    _pose(handle, "wxyz", wxyz, 4, _messages.SetOrientationMessage)


def set_markdown(handle: Any, content: str) -> None:
    """``handle.content = content`` for a Markdown element whose text has no images
    (viser rewrites image links into data URLs; text with ``![`` goes through it)."""
    if "![" in content or not isinstance(handle, AssignablePropsBase):
        handle.content = content
        return
    object.__setattr__(handle, "_content", content)
    set_prop(handle, "_markdown", content)
