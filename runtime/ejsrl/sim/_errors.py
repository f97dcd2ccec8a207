"""The error every part of a running model reports the spec's mistakes with.

It lives apart from :mod:`ejsrl.sim.model` so that the parts the model drives (the FMUs of
:mod:`ejsrl.fmi`, the ODE engine) can raise it without importing the model: the model
imports them, never the other way round.
"""

from __future__ import annotations

__all__ = ["UserCodeError"]


class UserCodeError(Exception):
    """An error raised by the spec's code, with its spec location.

    ``message``: what went wrong, in words; ``where``: ``"file:line:col"`` in the spec
    (empty if unknown).
    """

    def __init__(self, message: str, where: str = "") -> None:
        super().__init__(f"{where}: {message}" if where else message)
        self.message = message
        self.where = where
