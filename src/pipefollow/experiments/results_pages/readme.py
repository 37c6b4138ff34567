"""The README's table of the paper's claims, generated from the stored reproduction reports.

The README shows the headline result (each claim part of the paper with our measurement and its
verdict over 5 and over 30 repeats) between two marker lines; :func:`update` rewrites what lies
between them from ``docs/reproduction/REPORT.md`` and ``docs/repeats/REPORT.md`` and
:func:`stale` says whether the committed README differs, so that the README's numbers regenerate
like the results pages (``pipefollow docs results``; ``tests/test_results_pages.py``).
"""

from __future__ import annotations

from pathlib import Path

from pipefollow.experiments.results_pages.markdown import PageError, table
from pipefollow.experiments.results_pages.reproduction import claim_parts

BEGIN = "<!-- the claims table: written by `pipefollow docs results` (docs/reproduction, docs/repeats) -->"
END = "<!-- end of the generated claims table -->"
SOURCES = ("reproduction/REPORT.md", "repeats/REPORT.md")


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


def block(docs: Path) -> str:
    """The README's generated block, marker lines included."""
    return f"{BEGIN}\n\n{claims_table(docs)}\n\n{END}"


def _split(text: str, readme: Path) -> tuple[str, str]:
    if text.count(BEGIN) != 1 or text.count(END) != 1 or text.index(BEGIN) > text.index(END):
        raise PageError(f"{readme}: needs the claims table's two marker lines, once each, in order")
    return text[: text.index(BEGIN)], text[text.index(END) + len(END) :]


def render(readme: Path, docs: Path) -> str:
    """The README with its claims table regenerated from ``docs``."""
    text = Path(readme).read_text(encoding="utf-8")
    head, tail = _split(text, readme)
    return head + block(docs) + tail


def stale(readme: Path, docs: Path) -> bool:
    """Whether the README's claims table differs from what the stored reports give."""
    return Path(readme).read_text(encoding="utf-8") != render(readme, docs)


def update(readme: Path, docs: Path) -> bool:
    """Rewrite the README's claims table (atomically); True if it changed."""
    from pipefollow.files.atomic import write_text_atomic

    new = render(readme, docs)
    if new == Path(readme).read_text(encoding="utf-8"):
        return False
    write_text_atomic(Path(readme), new)
    return True
