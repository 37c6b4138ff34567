"""Progress on stderr: a bar on a terminal, a line at intervals otherwise (a log file, CI).

``pipefollow train > log`` or a CI job shows no bar (it would fill the log with carriage
returns), but silence for minutes looks like a hang; so when stderr is not a terminal a line
``LABEL: DONE/TOTAL (P %), T s`` is written every :data:`INTERVAL_S` seconds and when work that
lasted that long ends.
"""

from __future__ import annotations

import sys
import time
from contextlib import contextmanager

INTERVAL_S = 10.0


class _Lines:
    """``update(n)`` like click's progress bar; writes a line when :data:`INTERVAL_S` has passed."""

    def __init__(self, length: int, label: str, file, unit: str):
        self.length, self.label, self.file, self.unit = length, label, file, unit
        self.pos = 0
        self.t0 = self.last = time.perf_counter()

    def update(self, n: int) -> None:
        self.pos += n
        now = time.perf_counter()
        if now - self.last >= INTERVAL_S and self.pos < self.length:
            self.last = now
            self._line(now)

    def _line(self, now: float) -> None:
        share = self.pos / self.length if self.length else 1.0
        print(
            f"{self.label}: {self.pos}/{self.length} {self.unit} ({share:.0%}), {now - self.t0:.0f} s",
            file=self.file,
            flush=True,
        )

    def finish(self) -> None:
        now = time.perf_counter()
        if self.pos and now - self.t0 >= INTERVAL_S:  # work shorter than an interval needs no line
            self._line(now)


class _Silent:
    """``update(n)`` that reports nothing (``--json``)."""

    def update(self, n: int) -> None:
        pass


@contextmanager
def progress(length: int, label: str, *, hidden: bool = False, file=None, unit: str = "done", bar=None):
    """A progress reporter with ``update(n)``: a bar on a terminal, lines otherwise, or nothing.

    Args:
        length: the total of the work.
        label: what is being done (``training CACLA``).
        hidden: report nothing (``--json``).
        file: where to report (default stderr).
        unit: the name of the counted things in lines (``episodes``, ``trials``).
        bar: the bar to draw on a terminal, a context manager factory called with ``length``,
            ``label``, ``file`` and ``show_pos`` (the command line passes ``click.progressbar``);
            without one, a terminal gets the lines too.
    """
    file = sys.stderr if file is None else file
    if hidden:
        yield _Silent()
        return
    if bar is not None and file.isatty():
        with bar(length=length, label=label, file=file, show_pos=True) as drawn:
            yield drawn
        return
    lines = _Lines(length, label, file, unit)
    yield lines
    lines.finish()
