"""Generated blocks in hand-written pages (``results_pages.blocks``): current, checked, rewritten."""

import json
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.evaluation.compare import format_summary
from pipefollow.experiments.results_pages import blocks
from pipefollow.experiments.results_pages.markdown import PageError, value

DOCS = Path(__file__).resolve().parent.parent / "docs"


def test_every_generated_block_is_current():
    assert blocks.stale(DOCS) == []


def test_the_compare_sample_is_what_the_command_prints():
    # the command's text is format_summary of its --json, whatever the policies: held here on two
    # controllers and three pipes, then the stored example's block shows format_summary of its JSON
    args = ["compare", "heuristic", "los", "--pipes", "3", "--reps", "200"]
    text = CliRunner().invoke(main, args)
    as_json = CliRunner().invoke(main, [*args, "--json"])
    assert text.exit_code == 0 and as_json.exit_code == 0
    assert text.output.rstrip("\n") == format_summary(json.loads(as_json.output))
    stored = json.loads((DOCS / blocks.COMPARE).read_text())
    page = (DOCS / "guides/training-and-comparing.md").read_text()
    assert f"$ {blocks.COMPARE_COMMAND}\n{format_summary(stored)}\n```" in page
    assert stored["pipes"] == 100 and stored["suite"] == "heldout"
    assert {r["runs"] for r in stored["learners"].values()} == {5}  # five seeds each, as the guide says


def test_the_measured_state_table_has_the_heuristics_benchmark_return():
    from pipefollow.evaluation.benchmark import benchmark
    from pipefollow.learners.heuristic import Heuristic
    from pipefollow.sim.suites import get_suite

    page = (DOCS / "sample-efficiency/measured-state.md").read_text()
    row = next(line for line in page.splitlines() if line.startswith("| heuristic |"))
    calm = value(row.split("|")[4])
    # calm: no disturbance, and the heuristic reads neither sensor: heldout's 100 pipes × 60 s
    run = benchmark(Heuristic(), get_suite("heldout"), controller="heuristic", seconds=60.0)
    assert calm == pytest.approx(run.summary["mean_return"], abs=0.05)


def test_a_stale_block_is_found_and_rewritten_and_markers_are_required(tmp_path):
    docs = tmp_path / "docs"
    for b in blocks.BLOCKS:
        for rel in (b.page, *b.sources, *(s.replace(".json", ".provenance.json") for s in b.sources)):
            (docs / rel).parent.mkdir(parents=True, exist_ok=True)
            if (DOCS / rel).is_file():
                shutil.copy(DOCS / rel, docs / rel)
    shutil.copytree(DOCS / "speed", docs / "speed")  # the one results page --check is asked for
    page = docs / "sample-efficiency/measured-state.md"
    good = page.read_text()
    page.write_text(good.replace("| heuristic |", "| heuristic (typed) |"))
    assert blocks.stale(docs) == [page]
    check = CliRunner().invoke(main, ["docs", "results", "--docs", str(docs), "--out", str(tmp_path / "r"),
                                      "--page", "speed", "--check"])  # fmt: skip
    assert check.exit_code == 1
    assert f"stale: the generated blocks (sample outputs, tables) of {page}" in check.output
    assert blocks.update(docs) == [page]
    assert page.read_text() == good
    page.write_text(good.replace(blocks.BLOCKS[1].end, ""))
    with pytest.raises(PageError, match="needs the two marker lines"):
        blocks.render(docs, "sample-efficiency/measured-state.md")
    page.unlink()  # a documentation folder without the page has none of its blocks
    assert blocks.pages(docs) == ["guides/training-and-comparing.md"] and blocks.stale(docs) == []
