"""A small composable chain of image functions (the EjsRL paper's "colour -> grey -> SUSAN").

    result = Pipeline("gray", "susan").run(rgb)
    result.image, result.points          # the last image and the last features found

Each step is an image function given by name (see ``STEPS``), by a callable, or as
``(name_or_callable, {options})``. A step returns an image (it becomes the next step's
input), features (an (N, 2) or (N, k) float array: recorded, the image passes through), or
``(image, features)``. Steps named in ``STEPS`` declare which; for other callables an
(N, 2) float array counts as features.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ejsrl.vision import _susan, color, edges, features, filters

__all__ = ["Pipeline", "PipelineResult", "STEPS"]

#: name -> (function, what it returns: "image", "features" or "both")
STEPS: dict[str, tuple[Callable[..., Any], str]] = {
    "gray": (color.to_gray, "image"),
    "grey": (color.to_gray, "image"),
    "rgb": (color.to_rgb, "image"),
    "invert": (color.invert, "image"),
    "threshold": (color.threshold, "image"),
    "otsu": (lambda img, **kw: color.threshold_otsu(img, **kw)[0], "image"),
    "equalize": (color.equalize_histogram, "image"),
    "gaussian": (filters.gaussian_blur, "image"),
    "median": (filters.median_blur, "image"),
    "box": (filters.box_filter, "image"),
    "sharpen": (filters.sharpen, "image"),
    "erode": (filters.erode, "image"),
    "dilate": (filters.dilate, "image"),
    "open": (filters.morph_open, "image"),
    "close": (filters.morph_close, "image"),
    "canny": (edges.canny, "image"),
    "gradient": (edges.gradient_magnitude, "image"),
    "susan": (_susan.susan_corners, "features"),
    "susan_corners": (_susan.susan_corners, "features"),
    "susan_edges": (_susan.susan_edges, "both"),
    "harris": (features.harris_corners, "features"),
    "shi_tomasi": (features.shi_tomasi_corners, "features"),
    "fast": (features.fast_corners, "features"),
    "blobs": (features.blobs, "features"),
    "hough_circles": (features.hough_circles, "features"),
    "hough_segments": (features.hough_segments, "features"),
}


@dataclass
class PipelineResult:
    """What a pipeline run gives: the final ``image``, ``features`` per step name, every step's ``images``."""

    image: NDArray
    features: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    images: list[NDArray] = field(default_factory=list)

    @property
    def points(self) -> NDArray[np.float64]:
        """The features of the last step that found any ((0, 2) if none did)."""
        if not self.features:
            return np.zeros((0, 2))
        return list(self.features.values())[-1]

    def __iter__(self) -> Iterator[Any]:
        """Unpack as ``image, points``."""
        yield self.image
        yield self.points


def _is_features(out: Any) -> bool:
    return isinstance(out, np.ndarray) and out.ndim == 2 and out.dtype.kind == "f" and out.shape[1] == 2


class Pipeline:
    """A chain of image functions run in order on one image.

    ``Pipeline("gray", ("gaussian", {"ksize": 3}), ("susan", {"t": 25}))`` or with callables
    ``Pipeline(to_gray, susan_corners)``. Call it (or ``run``) on an image to get a
    ``PipelineResult``.
    """

    def __init__(self, *steps: Any) -> None:
        if not steps:
            raise ValueError("a Pipeline needs at least one step")
        self.steps: list[tuple[str, Callable[..., Any], dict[str, Any], str | None]] = []
        names: dict[str, int] = {}
        for step in steps:
            opts: dict[str, Any] = {}
            if isinstance(step, tuple):
                step, opts = step[0], dict(step[1])
            if isinstance(step, str):
                if step not in STEPS:
                    import difflib

                    close = difflib.get_close_matches(step, list(STEPS), n=1)
                    hint = f"; did you mean {close[0]!r}?" if close else f"; known steps: {', '.join(sorted(STEPS))}"
                    raise ValueError(f"unknown pipeline step {step!r}{hint}")
                fn, kind = STEPS[step]
                name: str = step
            elif callable(step):
                fn, kind = step, None
                name = getattr(step, "__name__", type(step).__name__)
            else:
                raise TypeError(f"a pipeline step must be a name or a callable, not {type(step).__name__}")
            names[name] = names.get(name, 0) + 1
            if names[name] > 1:
                name = f"{name}_{names[name]}"
            self.steps.append((name, fn, opts, kind))

    def run(self, img: NDArray) -> PipelineResult:
        """Run every step on ``img``; returns the final image, the features and the intermediate images."""
        result = PipelineResult(image=np.asarray(img))
        cur = result.image
        for name, fn, opts, kind in self.steps:
            out = fn(cur, **opts)
            if kind == "both" or (kind is None and isinstance(out, tuple) and len(out) == 2 and isinstance(out[0], np.ndarray)):
                cur, feats = out[0], np.asarray(out[1], dtype=np.float64)
                result.features[name] = feats
            elif kind == "features" or (kind is None and _is_features(out)):
                result.features[name] = np.asarray(out, dtype=np.float64)
            else:
                cur = np.asarray(out)
            result.images.append(cur)
        result.image = cur
        return result

    __call__ = run

    def __repr__(self) -> str:
        return "Pipeline(" + " -> ".join(n for n, *_ in self.steps) + ")"
