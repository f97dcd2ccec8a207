"""WebAssembly binaries for a web build: dropping what a browser never reads.

A WebAssembly module is a header and a list of sections (an id byte, a LEB128 size, the
payload). Custom sections (id 0) start with their name; ``name`` (function names for stack
traces) and ``.debug_*`` (DWARF) are for debuggers only: :func:`strip_debug` drops them,
which takes CPython's ``python.wasm`` from 99 MB to about 70 MB without changing what runs.
"""

from __future__ import annotations

__all__ = ["strip_debug", "sections", "WasmError"]

_MAGIC = b"\x00asm"


class WasmError(ValueError):
    """Not a WebAssembly module (or a truncated one)."""


def _leb128(data: bytes | memoryview, pos: int) -> tuple[int, int]:
    """The unsigned LEB128 number at ``pos`` and the position after it."""
    value, shift = 0, 0
    while True:
        if pos >= len(data):
            raise WasmError("truncated LEB128 number")
        byte = data[pos]
        pos += 1
        value |= (byte & 0x7F) << shift
        if not byte & 0x80:
            return value, pos
        shift += 7
        if shift > 35:
            raise WasmError("LEB128 number too long")


def sections(data: bytes) -> list[tuple[int, str, int, int]]:
    """Every section of ``data`` as ``(id, custom name or "", start, end)`` byte offsets of
    the whole section (id byte to end of payload)."""
    if data[:4] != _MAGIC or len(data) < 8:
        raise WasmError("not a WebAssembly module (no \\0asm header)")
    view = memoryview(data)
    out = []
    pos = 8
    while pos < len(data):
        start = pos
        section_id = data[pos]
        size, payload = _leb128(view, pos + 1)
        end = payload + size
        if end > len(data):
            raise WasmError(f"section at byte {start} runs past the end of the module")
        name = ""
        if section_id == 0:
            n, p = _leb128(view, payload)
            name = bytes(view[p : p + n]).decode("utf-8", "replace")
        out.append((section_id, name, start, end))
        pos = end
    return out


def strip_debug(data: bytes) -> bytes:
    """``data`` without its ``name`` and ``.debug_*`` custom sections."""
    keep = [data[:8]]
    for section_id, name, start, end in sections(data):
        if section_id == 0 and (name == "name" or name.startswith(".debug")):
            continue
        keep.append(data[start:end])
    return b"".join(keep)
