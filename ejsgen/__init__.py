"""ejsgen: turn a .ejs.yaml spec into a standalone interactive simulation app."""

from __future__ import annotations

__version__ = "0.1.0"
__all__ = ["__version__"]
