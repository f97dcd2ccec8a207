"""``python -m ejsgen`` is the ``ejsgen`` command."""

import sys

from ejsgen.cli import main

sys.exit(main())
