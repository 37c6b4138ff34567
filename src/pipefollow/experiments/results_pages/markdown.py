"""The pieces every results page is made of: numbers in words, tables, filled templates, provenance.

A results page is text computed from stored outputs only: a number in its prose is a named field of
a template (:func:`fill`), filled from the data, never typed into the text. Formatting is fixed
(the minus sign is U+2212, as in the guides) so that the same data always give the same bytes.
"""

from __future__ import annotations

import csv
import json
import math
import re
import string
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

MINUS = "\N{MINUS SIGN}"


class PageError(ValueError):
    """A stored output a page needs is missing or not what the page expects; names the file."""


# ---------------------------------------------------------------------------------------------
# Numbers


def num(x: float | None, digits: int = 1, sign: bool = False) -> str:
    """``x`` with ``digits`` decimals, the minus sign U+2212, ``+`` in front when ``sign``; ``—`` for NaN."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "—"
    text = f"{x:+.{digits}f}" if sign else f"{x:.{digits}f}"
    if float(text) == 0.0:  # no "−0.0"
        text = text.replace("-", "+" if sign else "")
    return text.replace("-", MINUS)


def pct(x: float | None, digits: int = 0) -> str:
    """A share as a percentage: ``0.82`` → ``82%``."""
    return "—" if x is None else f"{100 * x:.{digits}f}%"


def count(n: float) -> str:
    """A whole number with thousands separators: ``9990`` → ``9,990``."""
    return f"{int(n):,}"


def ci(lo: float, hi: float, digits: int = 1, sign: bool = False) -> str:
    """A 95 % interval as ``[lo, hi]``."""
    return f"[{num(lo, digits, sign)}, {num(hi, digits, sign)}]"


def value(text: str) -> float:
    """A number as a report prints it (``−9.3``, ``-9.3``, ``82%``, ``9,990``) → float."""
    t = text.strip().replace(MINUS, "-").replace(",", "").rstrip("%")
    try:
        return float(t)
    except ValueError:
        raise PageError(f"not a number: {text!r}") from None


def minus(text: str) -> str:
    """``text`` with the minus of every negative number as U+2212 (hyphens in words stay)."""
    return re.sub(r"(?<![\w\-])-(?=\d)", MINUS, text)


def mean_sd_cell(text: str) -> tuple[float, float]:
    """``"-11.00 ± 2.53"`` → (−11.0, 2.53)."""
    m, _, s = text.partition("±")
    return value(m), value(s)


def fraction_cell(text: str) -> tuple[int, int]:
    """``"5/5"`` → (5, 5)."""
    a, _, b = text.partition("/")
    return int(value(a)), int(value(b))


# ---------------------------------------------------------------------------------------------
# Templates


class _Strict(string.Formatter):
    def __init__(self, fields: Mapping[str, object]):
        self.unused = set(fields)

    def get_value(self, key, args, kwargs):
        self.unused.discard(key)
        return kwargs[key]


def fill(template: str, **fields: object) -> str:
    """``template`` with its ``{name}`` fields filled; a missing or an unused field is an error.

    Both directions are checked so that a number computed for the prose is in it and the prose
    cites no field the data did not give.
    """
    f = _Strict(fields)
    try:
        out = f.format(template, **fields)
    except KeyError as e:
        raise PageError(f"template field {e} has no value") from None
    if f.unused:
        raise PageError(f"computed field(s) {sorted(f.unused)} not used by the template")
    return out


# ---------------------------------------------------------------------------------------------
# Tables


def around_markers(text: str, where: Path | str, begin: str, end: str) -> tuple[str, str]:
    """What lies before the marker line ``begin`` and after ``end`` in ``text`` (a page at ``where``).

    A generated block sits between the two, and both must stand once, in order.
    """
    if text.count(begin) != 1 or text.count(end) != 1 or text.index(begin) > text.index(end):
        raise PageError(f"{where}: needs the two marker lines {begin!r} and {end!r}, once each, in order")
    return text[: text.index(begin)], text[text.index(end) + len(end) :]


def table(headers: Sequence[str], rows: Iterable[Sequence[object]]) -> str:
    """A Markdown table."""
    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def read_csv(path: Path) -> list[dict[str, str]]:
    """The rows of a stored CSV file."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            return list(csv.DictReader(f))
    except OSError as e:
        raise PageError(f"{path}: cannot be read ({e.strerror or e})") from None


def read_json(path: Path):
    """A stored JSON file."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise PageError(f"{path}: cannot be read ({e.strerror or e})") from None
    except json.JSONDecodeError as e:
        raise PageError(f"{path}: not JSON ({e})") from None


def read_text(path: Path) -> str:
    """A stored text file."""
    try:
        return path.read_text(encoding="utf-8")
    except OSError as e:
        raise PageError(f"{path}: cannot be read ({e.strerror or e})") from None


def markdown_tables(text: str) -> dict[str, list[list[dict[str, str]]]]:
    """The tables of a generated Markdown report, by the heading they stand under.

    Each table is a list of rows, each a mapping from the column's header to the cell's text.
    """
    out: dict[str, list[list[dict[str, str]]]] = {}
    heading = ""
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("#"):
            heading = line.lstrip("#").strip()
        elif line.startswith("|") and i + 1 < len(lines) and re.match(r"^\|(\s*:?-+:?\s*\|)+$", lines[i + 1]):
            header = _cells(line)
            rows = []
            i += 2
            while i < len(lines) and lines[i].startswith("|"):
                rows.append(dict(zip(header, _cells(lines[i]), strict=False)))
                i += 1
            out.setdefault(heading, []).append(rows)
            continue
        i += 1
    return out


def _cells(line: str) -> list[str]:
    return [c.strip() for c in line.strip().strip("|").split("|")]


def report_table(path: Path, heading: str, index: int = 0) -> list[dict[str, str]]:
    """Table ``index`` under ``heading`` of a stored generated report."""
    tables = markdown_tables(read_text(path)).get(heading)
    if not tables or len(tables) <= index:
        raise PageError(f"{path}: no table {index + 1} under the heading {heading!r}")
    return tables[index]


def row_by(rows: Sequence[Mapping[str, str]], column: str, key: str) -> Mapping[str, str]:
    """The first row whose ``column`` is ``key``."""
    for r in rows:
        if r.get(column) == key:
            return r
    raise PageError(f"no row with {column} = {key!r}")


# ---------------------------------------------------------------------------------------------
# Provenance and the page's frame

NOT_RECORDED = "not recorded"

REGENERATE = (
    "This page is generated: `pipefollow docs results` writes it from the stored outputs named "
    "below (tables rendered from them, every number in the text filled from them); edit the "
    "generator (`{module}`), not the page."
)


def stored_provenance(output: Path, folder: bool = True) -> str:
    """Where a stored output (a file or a folder) was computed, from its provenance record, if any.

    The record is the file's own ``X.provenance.json``, else (unless ``folder`` is false: a file
    another command wrote into the folder) its folder's ``provenance.json``
    (:func:`pipefollow.files.machine.provenance_record_path`); :data:`NOT_RECORDED` without one.
    """
    from pipefollow.files.machine import describe_provenance, provenance_path, provenance_record_path

    path = provenance_record_path(output)
    if not folder and path != provenance_path(output):
        path = None
    return NOT_RECORDED if path is None else describe_provenance(read_json(path))


def report_provenance(path: Path) -> str:
    """Where a run of ``pipefollow reproduce`` was computed, from its report's "Started on" line."""
    m = re.search(r"^Started on (.+?)\.?$", read_text(path), flags=re.MULTILINE)
    return m.group(1) if m else NOT_RECORDED


def page(
    title: str, module: str, sources: Sequence[str], provenance: Sequence[tuple[str, str]], body: str
) -> str:
    """A whole results page: title, how it is made, the sources and their provenance, the body."""
    lines = [f"# {title}", "", REGENERATE.format(module=module), ""]
    lines.append("Stored outputs: " + ", ".join(f"`docs/{s}`" for s in sources) + ".")
    lines.append("")
    lines.append("| stored output | where and with what it was computed |")
    lines.append("|---|---|")
    lines += [f"| `docs/{what}` | {where} |" for what, where in provenance]
    lines.append("")
    lines.append(
        f'"{NOT_RECORDED}": the stored output carries no code stamp, date, numba CPU target or machine; '
        "the generated reports of `pipefollow reproduce` record the machine, numba's CPU target and the "
        "package versions, but no code stamp or date."
    )
    lines += ["", body.strip(), ""]
    return "\n".join(lines)
