"""The pictures of a web build's 2D ``image`` files, decoded by the build for the page.

A 2D ``image`` element with ``file: photo.jpg`` is read by OpenCV when the lab is served; the
browser's Python has no OpenCV. :func:`decode_images` reads each such file of the built app
with the same OpenCV (:func:`ejsrl.view._image_file.write_web_copy`) and leaves in its place
the decoded copy (``photo.jpg.web.png``: the very pixels the served app shows, as a PNG the
page's runtime reads with zlib and NumPy). The file itself is not shipped: the page never
reads it. PNG, JPEG and every other format OpenCV reads are thus shown in the page as served;
a file OpenCV cannot read is refused before the build (:mod:`ejsgen._web_check`).
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["decode_images"]


def decode_images(spec_path: Path, app_dir: Path) -> dict[str, tuple[int, int]]:
    """Replace each 2D image file of the built app in ``app_dir`` (built from ``spec_path``) by
    its decoded copy; ``{file as written in the spec: (bytes of the file, bytes of the copy)}``."""
    from ejsrl.view._image_file import write_web_copy

    from ejsgen._web_check import web_image_files
    from ejsgen.validate import validate
    from ejsgen.yamlload import load_yaml

    checked = validate(load_yaml(Path(spec_path), display_name=str(spec_path)))
    done: dict[str, tuple[int, int]] = {}
    for rel in web_image_files(checked):
        file = app_dir / rel
        if not file.is_file():  # already replaced (the same file named twice)
            continue
        copy = write_web_copy(file, rel)
        done[rel] = (file.stat().st_size, copy.stat().st_size)
        file.unlink()
    return done
