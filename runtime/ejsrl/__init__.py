"""ejsrl: the runtime that ejsgen apps import (simulation, view, world, robotics, vision)."""

__version__ = "0.1.0"
