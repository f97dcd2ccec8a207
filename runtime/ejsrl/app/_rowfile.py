"""Files that end on a whole row, whatever the disk does.

A text file handed to ``csv.writer`` flushes its buffer wherever the buffer ends: when the
disk fills, the last line on disk is cut inside a number (and still parses, silently
wrong). ``RowFile`` writes whole rows only: rows collect in a buffer that goes to the file
in ``os.write`` calls, each row's end is remembered, and when a write fails (disk full,
quota, read-only remount, I/O error) the file is cut back to the end of the last row that
reached it whole, and ``CannotWrite`` says which file and why.

``CannotWrite.line()`` is the one line a command prints: ``error: cannot write FILE: <reason>``.
"""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Sequence
from typing import Any, TextIO

__all__ = ["CannotWrite", "RowFile"]


class CannotWrite(Exception):
    """Writing ``path`` failed: ``reason`` in words (``No space left on device``); ``lines``:
    the lines (rows, a header included) the file keeps, each whole (None if unknown)."""

    def __init__(self, path: str, reason: str, lines: int | None = None) -> None:
        super().__init__(f"cannot write {path}: {reason}")
        self.path = path
        self.reason = reason
        self.lines = lines

    def line(self) -> str:
        """``error: cannot write FILE: <reason>`` and what the file keeps."""
        kept = "" if self.lines is None else f" (the file keeps its first {self.lines:,} lines, each whole)"
        return f"error: cannot write {self.path}: {self.reason}{kept}"


def reason_of(exc: OSError) -> str:
    """An ``OSError`` in words: ``No space left on device``, ``Read-only file system``, ..."""
    return exc.strerror or str(exc)


class RowFile:
    """Whole CSV rows into a file descriptor (see the module docstring).

    ``fd``: an open, writable descriptor positioned where rows go (its current offset is
    kept as the last good end); ``path``: the name errors give; ``flush_bytes``: how much
    buffered text triggers a write (rows are also written by ``flush()``).
    """

    def __init__(self, fd: int, path: str, *, flush_bytes: int = 1 << 16) -> None:
        self.fd = fd
        self.path = path
        self.flush_bytes = flush_bytes
        self.good = os.lseek(fd, 0, os.SEEK_CUR)  # end of the last whole row on disk
        self.rows_on_disk = 0
        self._parts: list[bytes] = []
        self._size = 0
        self._text = io.StringIO()
        self._csv = csv.writer(self._text, lineterminator="\n")

    @classmethod
    def over(cls, fh: TextIO, **kw: Any) -> RowFile:
        """A ``RowFile`` on the descriptor of an open text file (flushed first); the file
        object must not be written to afterwards."""
        fh.flush()
        return cls(fh.fileno(), getattr(fh, "name", "the output file"), **kw)

    def write_row(self, row: Sequence[Any]) -> None:
        """Add one row (quoted as ``csv`` quotes); written once ``flush_bytes`` collect."""
        self._text.seek(0)
        self._text.truncate()
        self._csv.writerow(row)
        data = self._text.getvalue().encode("utf-8")
        self._parts.append(data)
        self._size += len(data)
        if self._size >= self.flush_bytes:
            self.flush()

    def flush(self) -> None:
        """Write every buffered row; on failure cut the file back to its last whole row and
        raise ``CannotWrite``."""
        parts, self._parts, self._size = self._parts, [], 0
        if not parts:
            return
        data = b"".join(parts)
        done = 0
        try:
            while done < len(data):
                n = os.write(self.fd, data[done:])
                if n <= 0:
                    raise OSError(28, os.strerror(28))
                done += n
        except OSError as exc:
            whole, end = 0, 0
            for part in parts:  # the rows that reached the file whole
                if end + len(part) > done:
                    break
                end += len(part)
                whole += 1
            self._cut(self.good + end)
            self.rows_on_disk += whole
            raise CannotWrite(self.path, reason_of(exc), self.rows_on_disk) from None
        self.good += done
        self.rows_on_disk += len(parts)

    def _cut(self, size: int) -> None:
        try:
            os.ftruncate(self.fd, size)
            os.lseek(self.fd, size, os.SEEK_SET)
        except OSError:
            pass  # a read-only remount may refuse even this; what is there ends where the kernel stopped
