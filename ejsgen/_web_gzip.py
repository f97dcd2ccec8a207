"""The gzip copy of a web build's python.wasm at the smallest size gzip allows: zopfli.

A page fetches the ``.gz`` copies and inflates them itself (a static host such as
``python -m http.server`` sends no brotli), so the ``.gz`` of python.wasm is most of what a
student downloads. Zopfli writes the same gzip format, which every gzip decoder (the browser's
``DecompressionStream``) reads, 3.9% smaller than zlib's level 9: python.wasm's 85.3 MB come to
19.33 MB against 20.11 MB, in 85 s of CPU once per machine (the copy is cached with python.wasm;
one iteration: five gained 0.2% more for 30% more time). Without the ``zopfli`` package
(``pip install 'ejsgen[web]'``), zlib's level 9 is kept.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["smallest_gzip", "gzip_tag"]


def gzip_tag() -> str:
    """What names the kind of ``.gz`` the cache holds: ``"-zopfli"``, or ``""`` (zlib's)."""
    try:
        import zopfli.gzip  # noqa: F401
    except ImportError:
        return ""
    return "-zopfli"


def smallest_gzip(path: Path) -> int:
    """Rewrite ``path`` + ``.gz`` (the gzip copy of ``path``) with zopfli when it is installed;
    the size of the ``.gz``."""
    gz = Path(f"{path}.gz")
    if gzip_tag():
        import zopfli.gzip

        gz.write_bytes(zopfli.gzip.compress(Path(path).read_bytes(), numiterations=1))
    return gz.stat().st_size
