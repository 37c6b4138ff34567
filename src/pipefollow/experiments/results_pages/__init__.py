"""Results pages of the documentation site, generated from the stored outputs under docs/.

Each page is a module with ``TITLE``, ``SOURCES`` (paths under docs/) and ``render(docs) -> str``,
which reads only those stored outputs (and, for tables of settings, the code that defines them):
tables are rendered from the CSV/JSON files and every number in the prose is a field of a template
filled from them. :func:`write_pages` writes them (``pipefollow docs results``); :func:`stale_pages`
names the committed pages that differ from what their stored outputs give. Output is deterministic:
no clock, no machine, only what the stored outputs carry.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable, Sequence
from pathlib import Path

from pipefollow.experiments.results_pages.markdown import PageError

# page name → module under this package; the order is the site's
PAGES = {
    "reproduction": "reproduction",
    "readings": "readings",
    "reference-learners": "reference_learners",
    "generalization": "generalization",
    "deep-vs-paper": "deep_vs_paper",
    "robustness": "robustness",
    "sample-efficiency": "sample_efficiency",
    "perception": "perception",
    "speed": "speed",
}
DEFAULT_OUT = "docs/results"  # the committed pages: the one default output path inside docs/


def module(name: str):
    """The module that renders page ``name``."""
    if name not in PAGES:
        raise PageError(f"results page {name!r}: unknown (choose from {', '.join(PAGES)})")
    return importlib.import_module(f"{__name__}.{PAGES[name]}")


def render(name: str, docs: str | Path) -> str:
    """Page ``name`` rendered from the stored outputs under ``docs``."""
    return module(name).render(Path(docs))


def write_pages(docs: str | Path, out: str | Path, names: Iterable[str] | None = None) -> list[Path]:
    """Render the pages (all, or ``names``) from ``docs`` and write ``out/<name>.md`` atomically."""
    from pipefollow.files.atomic import write_text_atomic

    out = Path(out)
    texts = {n: render(n, docs) for n in (list(names) if names else list(PAGES))}  # all first: no half update
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for n, text in texts.items():
        path = out / f"{n}.md"
        write_text_atomic(path, text)
        written.append(path)
    return written


def stale_pages(docs: str | Path, out: str | Path, names: Sequence[str] | None = None) -> list[str]:
    """The pages whose file under ``out`` is missing or differs from what ``docs`` renders."""
    stale = []
    for n in names or list(PAGES):
        path = Path(out) / f"{n}.md"
        if not path.is_file() or path.read_text(encoding="utf-8") != render(n, docs):
            stale.append(n)
    return stale


__all__ = ["PAGES", "DEFAULT_OUT", "PageError", "module", "render", "write_pages", "stale_pages"]
