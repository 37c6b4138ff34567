"""The README's generated blocks: the table of the paper's claims and the line on compile time.

The README shows the headline result (each claim part of the paper with our measurement and its
verdict over 5 and over 30 repeats) between two marker lines, and what the first run's compiling
costs between two others; :func:`update` rewrites what lies between each pair, the claims from
``docs/reproduction/REPORT.md`` and ``docs/repeats/REPORT.md``, the compile time from the stored
benchmark run ``docs/speed/run.json``, and :func:`stale` says whether the committed README
differs, so that the README's numbers regenerate like the results pages (``pipefollow docs
results``; ``tests/test_results_pages.py``).
"""

from __future__ import annotations

from pathlib import Path

from pipefollow.experiments.results_pages import speed
from pipefollow.experiments.results_pages.markdown import PageError, around_markers, fill, table
from pipefollow.experiments.results_pages.reproduction import claim_parts

BEGIN = "<!-- the claims table: written by `pipefollow docs results` (docs/reproduction, docs/repeats) -->"
END = "<!-- end of the generated claims table -->"
SOURCES = ("reproduction/REPORT.md", "repeats/REPORT.md", speed.WARM[0])
SPEED_BEGIN = "<!-- the compile time: written by `pipefollow docs results` (docs/speed/run.json) -->"
SPEED_END = "<!-- end of the generated compile time -->"
SPEED_TEXT = (
    "The first run compiles the simulator and the learners: in the last stored benchmark run\n"
    "`pipefollow reproduce --no-figures` took {cold} with an empty compile cache and {warm} with a warm\n"
    "one ([docs/results/speed.md](docs/results/speed.md), with that run's load and machine)."
)


def claims_table(docs: Path) -> str:
    """Each claim part: the paper's statement, ours over 5 repeats with its verdict, the verdict over 30."""
    five = claim_parts(Path(docs) / SOURCES[0])
    thirty = claim_parts(Path(docs) / SOURCES[1])
    if set(five) != set(thirty):
        raise PageError(f"the claim parts of {SOURCES[0]} and {SOURCES[1]} differ")
    rows = [
        (
            f"{p['figure']} ({key}): {p['statement']}",
            p["ours"],
            p["verdict"],
            f"{thirty[key]['ours']} **{thirty[key]['verdict']}**",
        )
        for key, p in five.items()
    ]
    return table(("the paper's claim", "ours, 5 repeats", "verdict", "over 30 repeats"), rows)


def compile_time(docs: Path) -> str:
    """The sentence on the first run's compiling, its times from the stored benchmark run."""
    records = {speed.WARM[0]: speed.read_record(docs, speed.WARM[0])}
    cold, warm = (speed.duration(speed.row(records, key)["median_s"]) for key in (speed.COLD, speed.WARM))
    return fill(SPEED_TEXT, cold=cold, warm=warm)


def block(docs: Path) -> str:
    """The README's claims block, marker lines included."""
    return f"{BEGIN}\n\n{claims_table(docs)}\n\n{END}"


def speed_block(docs: Path) -> str:
    """The README's compile-time block, marker lines included."""
    return f"{SPEED_BEGIN}\n{compile_time(docs)}\n{SPEED_END}"


BLOCKS = ((BEGIN, END, block), (SPEED_BEGIN, SPEED_END, speed_block))


def render(readme: Path, docs: Path) -> str:
    """The README with its generated blocks regenerated from ``docs``."""
    text = Path(readme).read_text(encoding="utf-8")
    for begin, end, make in BLOCKS:
        head, tail = around_markers(text, readme, begin, end)
        text = head + make(docs) + tail
    return text


def stale(readme: Path, docs: Path) -> bool:
    """Whether the README's generated blocks differ from what the stored outputs give."""
    return Path(readme).read_text(encoding="utf-8") != render(readme, docs)


def update(readme: Path, docs: Path) -> bool:
    """Rewrite the README's generated blocks (atomically); True if it changed."""
    from pipefollow.files.atomic import write_text_atomic

    new = render(readme, docs)
    if new == Path(readme).read_text(encoding="utf-8"):
        return False
    write_text_atomic(Path(readme), new)
    return True
