"""``python -m campar.cli``: the ``campar`` command."""

import sys

from . import main

sys.exit(main())
