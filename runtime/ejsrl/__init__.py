"""ejsrl: the runtime that ejsgen apps import (simulation, view, world, robotics, vision)."""

__version__ = "0.1.0"

from ejsrl._needs import check_main as _check_main  # noqa: E402

_check_main()  # a generated app whose packages are missing: say which, and the command that installs them
