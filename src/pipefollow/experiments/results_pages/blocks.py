"""Generated blocks inside hand-written pages of docs/: a command's sample output, a table of results.

A guide may show what a command prints, or a table of a stored result, next to the text that
explains it. Such a block sits between two marker lines that name it and the stored outputs it is
rendered from; :func:`update` rewrites what lies between them (``pipefollow docs results``) and
:func:`stale` names the pages whose blocks differ from what the stored outputs give (``pipefollow
docs results --check``), as the README's claims table (:mod:`.readme`). So no number of a sample
output or of a results table is typed into a guide.

The blocks (:data:`BLOCKS`):

* ``guides/training-and-comparing.md``, the sample of ``pipefollow compare``: its text rendered by
  :func:`pipefollow.evaluation.compare.format_summary` (what the command prints) from its stored
  ``--json`` (``docs/compare/example.json``), and the sentence on what it shows;
* ``sample-efficiency/measured-state.md``, the table of the measured states: every variant, budget
  and condition of ``docs/sample-efficiency/measured-state.json`` with the heuristic's row, in the
  layout of the sample-efficiency page's table (:func:`.sample_efficiency.full_rows`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from pipefollow.experiments.results_pages import sample_efficiency as se
from pipefollow.experiments.results_pages.markdown import (
    PageError,
    around_markers,
    fill,
    num,
    pct,
    read_json,
    stored_provenance,
    table,
)


@dataclass(frozen=True)
class Block:
    """A generated block: its page and name, the stored outputs it reads and how it is made."""

    page: str  # the page, a path under docs/
    name: str  # what the block holds, named in its marker lines
    sources: tuple[str, ...]  # the stored outputs (paths under docs/) it is rendered from
    make: Callable[[Path], str]  # docs/ → the block's text between the marker lines

    @property
    def begin(self) -> str:
        """The marker line before the block."""
        sources = ", ".join(f"docs/{s}" for s in self.sources)
        return f"<!-- {self.name}: written by `pipefollow docs results` ({sources}) -->"

    @property
    def end(self) -> str:
        """The marker line after the block."""
        return f"<!-- end of the generated {self.name} -->"


COMPARE = "compare/example.json"
COMPARE_COMMAND = (
    "pipefollow compare runs/c?/policy.npz runs/s?/policy.npz runs/q?/policy.npz --plot compare.png"
)
COMPARE_TEXT = (
    "The learner with the best IQM is {best} ({best_iqm}, success {best_success}); "
    "P({best} > {other}) = {best_poi} on average over the pipes. By the IQM the order is {iqm_order}, "
    "by the mean {mean_order}{disagree}."
)


def compare_example(docs: Path) -> str:
    """``pipefollow compare``'s text on the stored example, and what it shows."""
    from pipefollow.evaluation.compare import format_summary

    s = read_json(Path(docs) / COMPARE)
    learners = s.get("learners")
    if not learners or len(learners) < 2:
        raise PageError(f"docs/{COMPARE}: needs two learners or more")
    by_iqm = sorted(learners, key=lambda k: -learners[k]["iqm"])
    by_mean = sorted(learners, key=lambda k: -learners[k]["mean"])
    best, other = by_iqm[0], by_iqm[1]
    poi = {(p["x"], p["y"]): p["probability"] for p in s["probability_of_improvement"]}
    text = fill(
        COMPARE_TEXT,
        best=best,
        best_iqm=num(learners[best]["iqm"], 2),
        best_success=pct(learners[best]["success_rate"]),
        other=other,
        best_poi=f"{poi[best, other]:.2f}",
        iqm_order=" > ".join(by_iqm),
        mean_order=" > ".join(by_mean),
        disagree=(
            ": the two disagree, which is what the IQM is for (it leaves out the best and the worst quarter "
            "of the runs × pipes, where a few pipes lost for good weigh on the mean)"
            if by_iqm != by_mean
            else ""
        ),
    )
    where = stored_provenance(Path(docs) / COMPARE, folder=False)
    return f"```text\n$ {COMPARE_COMMAND}\n{format_summary(s)}\n```\n\n{text} Computed: {where}."


MEASURED = "sample-efficiency/measured-state.json"


def measured_state_table(docs: Path) -> str:
    """The measured states' table: the heuristic's row, then every variant and budget."""
    rows = read_json(Path(docs) / MEASURED)
    heuristic = {c: se.heuristic_of(next(r for r in rows if r["condition"] == c)) for c in se.CONDITIONS}
    h_calm, h_disturbed = num(heuristic["calm"]), num(heuristic["disturbed"])
    first = ("heuristic", "—", "—", h_calm, "—", "—", h_disturbed, "—", "—", "—")
    return table(se.FULL_HEADERS, [first, *se.full_rows(rows)])


BLOCKS = (
    Block("guides/training-and-comparing.md", "sample of compare", (COMPARE,), compare_example),
    Block(
        "sample-efficiency/measured-state.md",
        "table of the measured states",
        (MEASURED,),
        measured_state_table,
    ),
)


def render(docs: Path, page: str) -> str:
    """Page ``page`` (a path under ``docs``) with its generated blocks regenerated from ``docs``."""
    path = Path(docs) / page
    text = path.read_text(encoding="utf-8")
    for block in (b for b in BLOCKS if b.page == page):
        head, tail = around_markers(text, path, block.begin, block.end)
        text = f"{head}{block.begin}\n{block.make(Path(docs))}\n{block.end}{tail}"
    return text


def pages(docs: Path | None = None) -> list[str]:
    """The pages that hold generated blocks, in :data:`BLOCKS`' order; those ``docs`` holds if given.

    A documentation folder without a page (a folder of some stored outputs alone) has none of its
    blocks to regenerate.
    """
    names = dict.fromkeys(b.page for b in BLOCKS)
    return [p for p in names if docs is None or (Path(docs) / p).is_file()]


def stale(docs: Path) -> list[Path]:
    """The pages of ``docs`` whose generated blocks differ from what the stored outputs give."""
    return [
        Path(docs) / p for p in pages(docs) if (Path(docs) / p).read_text(encoding="utf-8") != render(docs, p)
    ]


def update(docs: Path) -> list[Path]:
    """Rewrite the generated blocks (atomically, every page rendered first); the pages that changed."""
    from pipefollow.files.atomic import write_text_atomic

    new = {p: render(docs, p) for p in pages(docs)}
    changed = []
    for p, text in new.items():
        path = Path(docs) / p
        if text != path.read_text(encoding="utf-8"):
            write_text_atomic(path, text)
            changed.append(path)
    return changed
