"""The stored record of a benchmark run: its figures, the clock, the load and the machine.

``run.py``, ``vision.py`` and ``sonar.py`` write one with ``--json FILE`` (the committed ones are
``docs/speed/*.json``, made by the commands of ``docs/speed/README.md``); ``pipefollow docs results``
renders them into ``docs/results/speed.md`` and never reruns a benchmark. Beside the JSON,
``FILE.provenance.json`` (``pipefollow.files.machine``) records the command, the UTC date, the code
(package version and a hash of its sources) and the machine; the JSON itself records the load
average before and after the run, the number of cores and the clock, which a shared machine's
figures depend on.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from pipefollow.experiments.results_pages.speed import FORMAT  # the results page checks it


def load_average() -> list[float]:
    """The 1-, 5- and 15-minute load averages (empty where the system has none)."""
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except OSError:
        return []


def write(path, suite: str, clock: str, repeats: int, load_before: list[float], rows, notes=()) -> None:
    """Write the record of one run to ``path`` and its provenance beside it.

    ``rows``: (name, median in seconds, target in seconds or None, floor in seconds or None).
    """
    from pipefollow.files.atomic import write_text_atomic
    from pipefollow.files.machine import script_command, write_output_provenance

    record = {
        "format": FORMAT,
        "suite": suite,
        "clock": clock,
        "repeats": repeats,
        "cpu_count": os.cpu_count(),
        "load_average": {"before": load_before, "after": load_average()},
        "rows": [
            {"name": name, "median_s": median, "target_s": target, "floor_s": floor}
            for name, median, target, floor in rows
        ],
        "notes": list(notes),
    }
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(Path(path), json.dumps(record, indent=1) + "\n")
    write_output_provenance(Path(path), script_command())
