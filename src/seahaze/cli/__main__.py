"""``python -m seahaze.cli``: the ``seahaze`` command."""

import sys

from . import main

sys.exit(main())
