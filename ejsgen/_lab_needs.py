"""What a lab needs installed beyond the runtime's own packages, decided from its spec.

A built lab lists OpenCV (``opencv-python-headless``) in its ``requirements.txt`` and its
inline script metadata only when something in the spec runs on it: the web build's check
(:mod:`ejsgen._web_check`) already finds every such feature at its spec line (a camera's
real ``source:``, ``blur`` and ``distortion``, marker textures, the
OpenCV functions of ``ejsrl.vision`` and ``cv2`` in imports or code, ``ImageSource``, maps
read from image files), and a served lab decodes a 2D ``image`` element's ``file:`` with
OpenCV too (the web build does that at build time instead).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ejsgen.validate import Checked

__all__ = ["uses_opencv"]


def uses_opencv(checked: Checked, spec_path: Path) -> bool:
    """Whether the lab of ``checked`` (validated, loaded from ``spec_path``) imports OpenCV
    anywhere when it runs natively (served, headless or sweeping)."""
    from ejsgen._web_check import web_image_files, web_refusals

    if web_image_files(checked):
        return True
    return any("OpenCV" in error.message for error in web_refusals(checked, spec_path))
