"""``python -m seahaze.cli``: the ``seahaze`` command."""

from . import entry

entry()
