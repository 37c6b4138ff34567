"""docs/design.md's tables that the code defines: they must say what the code says."""

from __future__ import annotations

from pathlib import Path

from pipefollow import readings as rd

DESIGN = Path(__file__).resolve().parents[1] / "docs" / "design.md"


def test_the_readings_table_is_the_one_generated_from_the_open_points():
    text = DESIGN.read_text(encoding="utf-8")
    section = text[text.index("## Readings") :]
    section = section[: section.index("\n## ", 1)]
    table = "\n".join(line for line in section.splitlines() if line.startswith("|"))
    # to update the document, paste the output of pipefollow.readings.table_markdown()
    assert table == rd.table_markdown().strip()
    assert [line.split("`")[1] for line in table.splitlines()[2:]] == [p.key for p in rd.OPEN_POINTS]
