"""The speed results page: the benchmarks' stored runs, each with its clock, load and machine.

Sources: ``docs/speed/run.json`` (``benchmarks/run.py --json``: the simulator, the learners, the
benchmark, training, rendering, the vector environment, the reproduction), ``vision.json``
(``benchmarks/vision.py``), ``sonar.json`` (``benchmarks/sonar.py``) and ``compare.json``
(``benchmarks/compare.py``), each written by ``benchmarks/stored.py`` with its
``X.provenance.json`` beside it. The page renders what they hold and reruns nothing; the guides
cite its rows instead of typing a time.
"""

from __future__ import annotations

import math
from pathlib import Path

from pipefollow.experiments.results_pages.markdown import (
    PageError,
    fill,
    page,
    read_json,
    stored_provenance,
    table,
)

TITLE = "Results: speed"
FORMAT = "pipefollow-benchmark-1"  # benchmarks/stored.py's FORMAT
# stored file → the script that writes it
SCRIPTS = {
    "speed/run.json": "benchmarks/run.py",
    "speed/vision.json": "benchmarks/vision.py",
    "speed/sonar.json": "benchmarks/sonar.py",
    "speed/compare.json": "benchmarks/compare.py",
}
SOURCES = tuple(SCRIPTS)

# the rows the summary cites: (stored file, row name)
ENV_STEP = ("speed/run.json", "env.step (1-s decision)")
CACLA_TRIAL = ("speed/run.json", "CACLA trial, 500 episodes")
SARSA_TRIAL = ("speed/run.json", "SARSA trial, 500 episodes")
RANDOM_TRAINING = ("speed/run.json", "random-pipe CACLA, 100k dec.")
RENDER = ("speed/run.json", "render one frame (rgb_array)")
WARM = ("speed/run.json", "pipefollow reproduce (warm)")
COLD = ("speed/run.json", "pipefollow reproduce (cold)")
VISION_STEP = ("speed/vision.json", "env.step, vision camera (detector + tracker)")
IDEAL_STEP = ("speed/vision.json", "env.step, ideal camera")
SONAR_DECISION = ("speed/sonar.json", "SonarSensor.step: render + detect + track, one decision")
COMPARE_CPU = ("speed/compare.json", "pipefollow compare, 15 × 100, CPU")

TEXT = """\
Regenerate the stored runs with the commands of [docs/speed/README.md](../speed/README.md) (a few
minutes on two cores); `pipefollow docs results` only renders what they stored. The machine is
shared: each run records its load average before and after, and times from runs at different
loads differ by tens of percent (`benchmarks/README.md` has earlier runs side by side). Compare
rows within one run.

## In brief

* One 1-s decision of the environment (`env.step`, ideal camera, wrappers included): {env_step}.
* A 500-episode trial on `paper-left` (the paper's training): CACLA {cacla_trial}, SARSA
  {sarsa_trial}; CACLA on a new random pipe every episode, 100,000 decisions: {random_training}.
* `pipefollow reproduce --no-figures` (40 trials, tables and report) as a fresh process:
  {warm} with a warm compile cache, {cold} with an empty one (compiling the simulator and learners).
* One rendered frame of the Fig. 2 view (`env.render()`): {render}.
* With the rendered camera, detector and tracker, one `env.step` takes {vision_step} ({ideal_step}
  with the ideal camera in the same run); one decision of the multibeam sonar (render, detect,
  track) {sonar_decision}.
* `pipefollow compare` of 15 policies on 100 held-out pipes: {compare_cpu} of CPU time.

{runs}
"""

RUN_TEXT = """\
## {title}

`{script}`: {repeats} repeats, {clock} time, {cores} cores; load average {load_before} before and
{load_after} after (1, 5 and 15 minutes).

{table}
{notes}"""

TITLES = {
    "run": "The simulator, the learners and the reproduction",
    "vision": "The vision camera",
    "sonar": "The sonars: the multibeam profiler and the imaging sonar",
    "compare": "Comparing policies",
}


def duration(seconds: float | None) -> str:
    """A time in the unit that suits it, three significant figures: ``6.25 µs``, ``96.9 ms``, ``8.78 s``."""
    if seconds is None or (isinstance(seconds, float) and math.isnan(seconds)):
        return "—"
    for unit, scale in (("µs", 1e-6), ("ms", 1e-3), ("s", 1.0)):
        v = seconds / scale
        if v < 1000 or unit == "s":
            digits = 2 if v < 10 else 1 if v < 100 else 0
            return f"{v:.{digits}f} {unit}"
    raise AssertionError("unreachable")


def _load(values) -> str:
    return " / ".join(f"{x:.2f}" for x in values) if values else "not recorded"


def read_record(docs: Path, source: str) -> dict:
    """A stored benchmark run, checked to be one of ``benchmarks/stored.py``."""
    record = read_json(docs / source)
    if not isinstance(record, dict) or record.get("format") != FORMAT:
        raise PageError(f"{docs / source}: not a benchmark record of benchmarks/stored.py ({FORMAT})")
    return record


def row(records: dict, key: tuple[str, str]) -> dict:
    """The row ``key`` = (stored file, row name) of the stored runs ``records``."""
    source, name = key
    for r in records[source]["rows"]:
        if r["name"] == name:
            return r
    raise PageError(f"docs/{source}: no row {name!r}")


def run_table(record: dict) -> str:
    """One run's rows: the median, the target and whether it was met, the floor and the ratio to it."""

    def met(r):
        if r["target_s"] is None or r["median_s"] is None or math.isnan(r["median_s"]):
            return "—"
        return "yes" if r["median_s"] <= r["target_s"] else "no"

    def ratio(r):
        if r["floor_s"] is None or r["median_s"] is None or math.isnan(r["median_s"]):
            return "—"
        return f"{r['median_s'] / r['floor_s']:.1f}"

    return table(
        ("benchmark", "median", "target", "met", "floor", "× floor"),
        (
            (
                r["name"],
                duration(r["median_s"]),
                duration(r["target_s"]),
                met(r),
                duration(r["floor_s"]),
                ratio(r),
            )
            for r in record["rows"]
        ),
    )


def render(docs: Path) -> str:
    """The page's Markdown from the stored runs under ``docs/speed``."""
    records = {s: read_record(docs, s) for s in SOURCES}
    runs = []
    for source, record in records.items():
        notes = "".join(f"\n* {n}" for n in record["notes"])
        runs.append(
            RUN_TEXT.format(
                title=TITLES.get(record["suite"], record["suite"]),
                script=SCRIPTS[source],
                repeats=record["repeats"],
                clock=record["clock"],
                cores=record["cpu_count"],
                load_before=_load(record["load_average"]["before"]),
                load_after=_load(record["load_average"]["after"]),
                table=run_table(record),
                notes=("\nThe script's paired comparisons in the same run:\n" + notes) if notes else "",
            ).rstrip()
        )
    cite = {
        name: duration(row(records, key)["median_s"])
        for name, key in {
            "env_step": ENV_STEP,
            "cacla_trial": CACLA_TRIAL,
            "sarsa_trial": SARSA_TRIAL,
            "random_training": RANDOM_TRAINING,
            "render": RENDER,
            "warm": WARM,
            "cold": COLD,
            "vision_step": VISION_STEP,
            "ideal_step": IDEAL_STEP,
            "sonar_decision": SONAR_DECISION,
            "compare_cpu": COMPARE_CPU,
        }.items()
    }
    body = fill(TEXT, runs="\n\n".join(runs), **cite)
    provenance = [(s, stored_provenance(docs / s)) for s in SOURCES]
    return page(TITLE, __name__, SOURCES, provenance, body)
