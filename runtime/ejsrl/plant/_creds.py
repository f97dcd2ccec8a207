"""Credentials and TLS settings of a plant connection: from the environment or a file named on
the command line, never from the spec, the generated app or the browser.

The file holds ``key = value`` lines (``#`` starts a comment): ``username``, ``password``,
``tls_ca`` (a CA bundle path: TLS on), ``tls_cert`` and ``tls_key`` (a client certificate).
The environment variables ``EJSRL_PLANT_USERNAME``, ``EJSRL_PLANT_PASSWORD``, ``EJSRL_PLANT_TLS_CA``,
``EJSRL_PLANT_TLS_CERT`` and ``EJSRL_PLANT_TLS_KEY`` give the same settings and win over the file.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Credentials", "load_credentials"]

_KEYS = ("username", "password", "tls_ca", "tls_cert", "tls_key")


@dataclass(frozen=True)
class Credentials:
    username: str | None = None
    password: str | None = None
    tls_ca: str | None = None
    tls_cert: str | None = None
    tls_key: str | None = None

    def __repr__(self) -> str:  # never print a password, even in a traceback
        return f"Credentials(username={'set' if self.username else None}, password={'set' if self.password else None}, tls={'on' if self.tls_ca else 'off'})"

    __str__ = __repr__


def load_credentials(path: str | os.PathLike[str] | None = None) -> Credentials:
    """Read the settings from ``path`` (if given) and the environment; raise ``ValueError`` on a bad file line."""
    values: dict[str, str] = {}
    if path:
        for n, line in enumerate(Path(path).read_text(encoding="utf-8").splitlines(), 1):
            line = line.split("#", 1)[0].strip()
            if not line:
                continue
            key, sep, value = line.partition("=")
            key = key.strip().lower()
            if not sep or key not in _KEYS:
                raise ValueError(f"{path}:{n}: expected 'key = value' with key one of {', '.join(_KEYS)}")
            values[key] = value.strip()
    for key in _KEYS:
        env = os.environ.get(f"EJSRL_PLANT_{key.upper()}")
        if env:
            values[key] = env
    return Credentials(**values)
