"""A small pure-Python MessagePack codec: the ``msgspec.msgpack`` viser's modules import, in a
browser build (msgspec is a C extension the WebAssembly Python does not have).

It covers what viser's messages carry: None, bool, int (-2**63 .. 2**64-1), float (always
written as float64, as msgspec does), str, bytes-likes (``bin``), lists/tuples (``array``) and
dicts (``map``). Decoding gives str, bytes, list and dict; ``DecodeError`` (a ``ValueError``)
for anything malformed, truncated or nested deeper than :data:`MAX_DEPTH`.
"""

from __future__ import annotations

import struct
from typing import Any

__all__ = ["DecodeError", "EncodeError", "encode", "decode", "MAX_DEPTH"]

#: the deepest nesting :func:`decode` accepts (a client's message is a few levels deep)
MAX_DEPTH = 64

_F64 = struct.Struct(">d")
_F32 = struct.Struct(">f")


class DecodeError(ValueError):
    """The bytes are not one well-formed MessagePack value."""


class EncodeError(TypeError):
    """A value MessagePack cannot carry."""


def encode(obj: Any) -> bytes:
    """``obj`` as MessagePack bytes."""
    out = bytearray()
    _encode(obj, out)
    return bytes(out)


def _encode(obj: Any, out: bytearray) -> None:  # noqa: C901 - one branch per MessagePack type
    if obj is None:
        out.append(0xC0)
    elif obj is True:
        out.append(0xC3)
    elif obj is False:
        out.append(0xC2)
    elif isinstance(obj, int):
        _encode_int(int(obj), out)
    elif isinstance(obj, float):
        out.append(0xCB)
        out += _F64.pack(obj)
    elif isinstance(obj, str):
        data = obj.encode("utf-8")
        _header(len(data), 0xA0, 32, _STR, out)
        out += data
    elif isinstance(obj, (bytes, bytearray, memoryview)):
        data = obj.cast("B") if isinstance(obj, memoryview) else obj
        _sized(len(data), _BIN, out, what="bytes")
        out += data
    elif isinstance(obj, (list, tuple)):
        _header(len(obj), 0x90, 16, _ARRAY, out)
        for item in obj:
            _encode(item, out)
    elif isinstance(obj, dict):
        _header(len(obj), 0x80, 16, _MAP, out)
        for key, value in obj.items():
            _encode(key, out)
            _encode(value, out)
    else:
        raise EncodeError(f"cannot encode a {type(obj).__name__} as MessagePack")


# the wider forms of each kind, narrowest first: (type byte, bytes of the number that follows)
_UINT = ((0xCC, 1), (0xCD, 2), (0xCE, 4), (0xCF, 8))
_INT = ((0xD0, 1), (0xD1, 2), (0xD2, 4), (0xD3, 8))
_STR = ((0xD9, 1), (0xDA, 2), (0xDB, 4))
_BIN = ((0xC4, 1), (0xC5, 2), (0xC6, 4))
_ARRAY = ((0xDC, 2), (0xDD, 4))
_MAP = ((0xDE, 2), (0xDF, 4))


def _sized(n: int, forms: tuple[tuple[int, int], ...], out: bytearray, *, signed: bool = False, what: str = "length") -> None:
    """``n`` in the narrowest of ``forms`` that holds it: its type byte, then ``n`` big-endian
    in its size (two's complement if ``signed``), as msgspec writes it."""
    for code, size in forms:
        bits = 8 * size - 1 if signed else 8 * size
        if (-(1 << bits) if signed else 0) <= n < 1 << bits:
            out.append(code)
            out += n.to_bytes(size, "big", signed=signed)
            return
    raise EncodeError(f"{what} {n} is out of MessagePack's range")


def _header(n: int, fix: int, fix_limit: int, forms: tuple[tuple[int, int], ...], out: bytearray) -> None:
    """A string's, an array's or a map's header: the fix form (``fix | n``) below ``fix_limit``,
    else the narrowest of ``forms``."""
    if n < fix_limit:
        out.append(fix | n)
    else:
        _sized(n, forms, out)


def _encode_int(n: int, out: bytearray) -> None:
    if 0 <= n < 0x80:
        out.append(n)  # positive fixint
    elif -32 <= n < 0:
        out.append(n & 0xFF)  # negative fixint
    elif n >= 0:
        _sized(n, _UINT, out, what="integer")
    else:
        _sized(n, _INT, out, signed=True, what="integer")


def decode(data: bytes | bytearray | memoryview) -> Any:
    """The one value in ``data`` (bytes-like)."""
    buf = bytes(data)
    value, end = _Decoder(buf).read(0, 0)
    if end != len(buf):
        raise DecodeError(f"{len(buf) - end} bytes left after the value")
    return value


class _Decoder:
    def __init__(self, buf: bytes) -> None:
        self.buf = buf

    def _take(self, pos: int, n: int) -> tuple[bytes, int]:
        end = pos + n
        if end > len(self.buf):
            raise DecodeError("truncated MessagePack data")
        return self.buf[pos:end], end

    def _uint(self, pos: int, n: int) -> tuple[int, int]:
        raw, pos = self._take(pos, n)
        return int.from_bytes(raw, "big"), pos

    def read(self, pos: int, depth: int) -> tuple[Any, int]:  # noqa: C901 - one branch per type
        if depth > MAX_DEPTH:
            raise DecodeError("MessagePack data nested too deeply")
        if pos >= len(self.buf):
            raise DecodeError("truncated MessagePack data")
        b = self.buf[pos]
        pos += 1
        if b < 0x80:
            return b, pos
        if b >= 0xE0:
            return b - 0x100, pos
        if 0xA0 <= b <= 0xBF:
            return self._str(pos, b & 0x1F)
        if 0x90 <= b <= 0x9F:
            return self._array(pos, b & 0x0F, depth)
        if 0x80 <= b <= 0x8F:
            return self._map(pos, b & 0x0F, depth)
        if b == 0xC0:
            return None, pos
        if b == 0xC2:
            return False, pos
        if b == 0xC3:
            return True, pos
        if b in (0xC4, 0xC5, 0xC6):
            n, pos = self._uint(pos, 1 << (b - 0xC4))
            raw, pos = self._take(pos, n)
            return raw, pos
        if b == 0xCA:
            raw, pos = self._take(pos, 4)
            return _F32.unpack(raw)[0], pos
        if b == 0xCB:
            raw, pos = self._take(pos, 8)
            return _F64.unpack(raw)[0], pos
        if 0xCC <= b <= 0xCF:
            return self._uint(pos, 1 << (b - 0xCC))
        if 0xD0 <= b <= 0xD3:
            raw, pos = self._take(pos, 1 << (b - 0xD0))
            return int.from_bytes(raw, "big", signed=True), pos
        if b in (0xD9, 0xDA, 0xDB):
            n, pos = self._uint(pos, 1 << (b - 0xD9))
            return self._str(pos, n)
        if b in (0xDC, 0xDD):
            n, pos = self._uint(pos, 2 if b == 0xDC else 4)
            return self._array(pos, n, depth)
        if b in (0xDE, 0xDF):
            n, pos = self._uint(pos, 2 if b == 0xDE else 4)
            return self._map(pos, n, depth)
        raise DecodeError(f"unsupported MessagePack type byte 0x{b:02x}")

    def _str(self, pos: int, n: int) -> tuple[str, int]:
        raw, pos = self._take(pos, n)
        try:
            return raw.decode("utf-8"), pos
        except UnicodeDecodeError as exc:
            raise DecodeError("invalid UTF-8 in a MessagePack string") from exc

    def _array(self, pos: int, n: int, depth: int) -> tuple[list[Any], int]:
        if n > len(self.buf) - pos:  # each item takes at least a byte
            raise DecodeError("truncated MessagePack data")
        items = []
        for _ in range(n):
            item, pos = self.read(pos, depth + 1)
            items.append(item)
        return items, pos

    def _map(self, pos: int, n: int, depth: int) -> tuple[dict[Any, Any], int]:
        if 2 * n > len(self.buf) - pos:
            raise DecodeError("truncated MessagePack data")
        out: dict[Any, Any] = {}
        for _ in range(n):
            key, pos = self.read(pos, depth + 1)
            if not isinstance(key, (str, int, float, bool, type(None), bytes)):
                raise DecodeError("a MessagePack map key must be a scalar")
            out[key], pos = self.read(pos, depth + 1)
        return out, pos
