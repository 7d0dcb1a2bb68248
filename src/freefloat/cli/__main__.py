"""``python -m freefloat.cli``: the ``freefloat`` command."""

import sys

from .main import main

sys.exit(main())
