"""Where a stored output was computed: one record per file or per folder, cited by the results pages.

A file beside outputs of other commands (``docs/vision/``) has its own ``X.provenance.json``; a
folder made by one command has ``provenance.json``; a page cites the file's own record first, then
its folder's, else "not recorded".
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.experiments import results_pages
from pipefollow.experiments.results_pages.markdown import NOT_RECORDED, stored_provenance
from pipefollow.files.machine import (
    PROVENANCE_FILE,
    provenance,
    provenance_path,
    provenance_record_path,
    script_command,
    write_output_provenance,
    write_provenance,
)

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_a_file_has_its_record_beside_it_under_its_own_stem():
    assert provenance_path(Path("docs/vision/closed_loop.csv")) == Path(
        "docs/vision/closed_loop.provenance.json"
    )
    assert provenance_path(Path("a/ppo_pixels_raw.json")) == Path("a/ppo_pixels_raw.provenance.json")


def test_the_files_own_record_comes_first_then_its_folders(tmp_path):
    out = tmp_path / "out.csv"
    out.write_text("a\n1\n")
    assert provenance_record_path(out) is None
    assert stored_provenance(out) == NOT_RECORDED
    write_provenance(tmp_path, "python folder.py")
    assert provenance_record_path(out) == tmp_path / PROVENANCE_FILE
    assert provenance_record_path(tmp_path) == tmp_path / PROVENANCE_FILE
    assert stored_provenance(out).startswith("`python folder.py` on ")
    assert write_output_provenance(out, "python own.py --x 1") == tmp_path / "out.provenance.json"
    assert provenance_record_path(out) == tmp_path / "out.provenance.json"
    assert stored_provenance(out).startswith("`python own.py --x 1` on ")
    # another file of the same folder keeps the folder's record
    other = tmp_path / "other.csv"
    other.write_text("b\n2\n")
    assert stored_provenance(other).startswith("`python folder.py` on ")


def test_a_record_holds_the_command_date_code_and_machine(tmp_path):
    path = write_output_provenance(tmp_path / "x.json", "python examples/x.py --json x.json")
    record = json.loads(path.read_text(encoding="utf-8"))
    assert set(record) == {"command", "date", "code", "machine"}
    assert record["command"] == "python examples/x.py --json x.json"
    assert record["date"].endswith(" UTC") and len(record["code"]["sources"]) == 16


def test_a_scripts_command_is_python_and_its_arguments_quoted():
    assert script_command(["examples/ppo_pixels.py", "--json", "a b.json"]) == (
        "python examples/ppo_pixels.py --json 'a b.json'"
    )


def test_vision_calibrate_writes_its_record_beside_the_json(tmp_path):
    out = tmp_path / "calibration.json"
    result = CliRunner().invoke(
        main, ["vision", "calibrate", "--report", str(DOCS / "vision" / "report.csv"), "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    record = json.loads((tmp_path / "calibration.provenance.json").read_text(encoding="utf-8"))
    assert record["command"].startswith("pipefollow vision calibrate --report ")
    assert record["command"].endswith(f"--out {out}")


def test_the_perception_page_cites_each_vision_files_own_record(tmp_path):
    docs = tmp_path / "docs"
    shutil.copytree(DOCS / "vision", docs / "vision", ignore=shutil.ignore_patterns("*.png"))
    for name in ("closed_loop", "ppo_pixels"):
        for p in (docs / "vision").glob(f"{name}.provenance.json"):
            p.unlink()
    before = results_pages.render("perception", docs)
    record = provenance("python examples/vision_table.py --csv docs/vision/closed_loop.csv")
    (docs / "vision" / "closed_loop.provenance.json").write_text(json.dumps(record), encoding="utf-8")
    after = results_pages.render("perception", docs)
    row = next(line for line in after.splitlines() if line.startswith("| `docs/vision/closed_loop.csv` |"))
    assert "`python examples/vision_table.py --csv docs/vision/closed_loop.csv`" in row
    assert record["code"]["sources"] in row and record["date"] in row
    # the other files of the folder do not borrow it
    assert "| `docs/vision/ppo_pixels.json` | " + NOT_RECORDED in after
    changed = [a for a, b in zip(after.splitlines(), before.splitlines(), strict=True) if a != b]
    assert changed == [row]


def test_the_deep_rl_page_cites_its_folders_record_and_reads_no_run_from_it(tmp_path):
    docs = tmp_path / "docs"
    shutil.copytree(DOCS / "deep-vs-paper", docs / "deep-vs-paper")
    before = results_pages.render("deep-vs-paper", docs)
    assert "| `docs/deep-vs-paper/*.json` | " + NOT_RECORDED in before
    write_provenance(docs / "deep-vs-paper", "python examples/deep-vs-paper.py --out R")
    after = results_pages.render("deep-vs-paper", docs)
    assert "| `docs/deep-vs-paper/*.json` | `python examples/deep-vs-paper.py --out R` on " in after
    # only the runs' provenance row changed: the record is not read as a run, and discount.jsonl,
    # which another command writes, does not borrow it
    changed = [a for a, b in zip(after.splitlines(), before.splitlines(), strict=True) if a != b]
    assert len(changed) == 1 and changed[0].startswith("| `docs/deep-vs-paper/*.json` |")
    assert "| `docs/deep-vs-paper/discount.jsonl` | " + NOT_RECORDED in after
