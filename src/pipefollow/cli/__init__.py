"""The ``pipefollow`` command line: the group in :mod:`.common`, the commands by subject.

Each command wires options to the library; the work is done in the modules it calls.
"""

from pipefollow.cli import experiments, run, suites, vision  # noqa: F401 - registers the commands
from pipefollow.cli.common import main

__all__ = ["main"]
