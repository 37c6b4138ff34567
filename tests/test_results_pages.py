"""The generated results pages (docs/results/): stale pages fail, the numbers come from the data.

Each committed page must equal what ``pipefollow docs results`` renders from the stored outputs
under docs/; a number changed in a copy of the stored outputs must show up in the page; the water
presets' table on the perception page must say what the code's presets set.
"""

from __future__ import annotations

import csv
import json
import re
import shutil
import statistics
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.experiments import results_pages
from pipefollow.experiments.results_pages.markdown import (
    MINUS,
    PageError,
    fill,
    markdown_tables,
    minus,
    num,
)

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
RESULTS = DOCS / "results"


@pytest.mark.parametrize("name", list(results_pages.PAGES))
def test_the_committed_page_is_what_its_stored_outputs_give(name):
    committed = (RESULTS / f"{name}.md").read_text(encoding="utf-8")
    assert committed == results_pages.render(name, DOCS), (
        f"docs/results/{name}.md is stale: run `pipefollow docs results`"
    )


def test_every_page_is_in_the_site_nav_and_says_how_to_regenerate_it():
    nav = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    for name in results_pages.PAGES:
        assert f"results/{name}.md" in nav
        text = (RESULTS / f"{name}.md").read_text(encoding="utf-8")
        assert "`pipefollow docs results`" in text and "where and with what it was computed" in text


def _result_rows(text: str) -> list[str]:
    """The table rows of ``text`` with at least two measured numbers (decimals) in their cells."""
    number = re.compile(r"^[+\N{MINUS SIGN}-]?\d+\.\d+")
    rows = []
    for line in text.splitlines():
        if line.lstrip().startswith("|"):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if sum(bool(number.match(c)) for c in cells) >= 2:
                rows.append(line)
    return rows


def test_the_guides_hold_no_table_of_results():
    guides = sorted((DOCS / "guides").glob("*.md"))
    found = [f"{p.name}: {r}" for p in guides for r in _result_rows(p.read_text(encoding="utf-8"))]
    assert found == []
    # a results row as the guides had them is found; a table of options is not
    m = "\N{MINUS SIGN}"
    assert _result_rows(f"| calm | heuristic | {m}41.3 | [{m}49.8, {m}32.8] | +2.4 |")
    assert not _result_rows("| `--seconds` | 20 | episode length (s) |\n| `turbidity` | 1/m | [0, 3] |")


def test_rendering_twice_gives_the_same_bytes():
    for name in results_pages.PAGES:
        assert results_pages.render(name, DOCS) == results_pages.render(name, DOCS)


# ---------------------------------------------------------------------------------------------
# The filling: a changed stored number shows up in the page


@pytest.fixture
def docs_copy(tmp_path) -> Path:
    """A copy of the stored outputs (docs/ without the pages and images)."""
    out = tmp_path / "docs"
    for sub in ("reproduction", "repeats", "readings", "skew-centred", "reference-learners", "generalize",
                "deep-vs-paper", "robustness", "sample-efficiency", "vision", "speed"):  # fmt: skip
        shutil.copytree(DOCS / sub, out / sub, ignore=shutil.ignore_patterns("*.png"))
    return out


def _rewrite_csv(path: Path, change) -> None:
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    fields = list(rows[0])
    for r in rows:
        change(r)
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fields)
        w.writeheader()
        w.writerows(rows)


def test_a_changed_heuristic_return_moves_the_generalization_table(docs_copy):
    def change(r):
        if r["scenario"] == "calm" and r["controller"] == "heuristic":
            r["mean_return"] = "-12.3456"

    _rewrite_csv(docs_copy / "generalize" / "heldout.csv", change)
    page = results_pages.render("generalization", docs_copy)
    row = next(line for line in page.splitlines() if line.startswith("| calm | heuristic |"))
    assert f"| {MINUS}12.3 |" in row
    assert f"{MINUS}41.3" not in row


def test_a_changed_validation_return_moves_table_1_and_its_prose(docs_copy):
    # one repeat's learned return on the validation pipe beats the heuristic: mean, sd, wins change
    path = docs_copy / "reproduction" / "evaluation.csv"
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    learned = [r for r in rows if r["trial"] == "validation" and r["controller"] == "learned"]
    heuristic = next(
        float(r["return"]) for r in rows if r["trial"] == "validation" and r["controller"] == "heuristic"
    )
    values = [float(r["return"]) for r in learned]
    values[0] = -50.0

    def change(r):
        if (r["trial"], r["controller"], r["seed"]) == ("validation", "learned", learned[0]["seed"]):
            r["return"] = "-50.0"

    _rewrite_csv(path, change)
    page = results_pages.render("reproduction", docs_copy)
    mean, sd = statistics.fmean(values), statistics.stdev(values)
    assert f"{num(mean, 2)} ± {num(sd, 2)}" in page
    assert f"beats the heuristic in {sum(v > heuristic for v in values)} of {len(values)} repeats" in page
    assert f"{num((mean - heuristic) / abs(heuristic) * 100, 1, sign=True)} %" in page


def test_a_changed_verdict_moves_the_readings_page(docs_copy):
    def change(r):
        if (r["reading"], r["claim"]) == ("default", "4a"):
            r["passed"], r["verdict"] = "10", "confirmed"

    _rewrite_csv(docs_copy / "readings" / "readings.csv", change)
    page = results_pages.render("readings", docs_copy)
    row = (
        "| `default` | 6/10 ✗ | 10/10 ✓ | 10/10 ✓ | 30/40 ✗ | 27/30 ✓ | 18/20 ✗ | 2/10 ✗ | 10/10 ✓ | 2/10 ✗ |"  # noqa: E501
    )
    assert row in page.splitlines()
    assert "**Claims that fail under every reading**: none." in page  # 4a no longer fails everywhere
    assert "4 of 9 parts hold (1b, 1c, 2b, 4a)" in page


def test_a_changed_run_file_moves_the_deep_vs_paper_page(docs_copy):
    path = docs_copy / "deep-vs-paper" / "heuristic.json"
    run = json.loads(path.read_text())
    run["calm"]["success_rate"] = 0.37
    path.write_text(json.dumps(run))
    page = results_pages.render("deep-vs-paper", docs_copy)
    row = next(line for line in page.splitlines() if line.startswith("| heuristic |"))
    assert row.split(" | ")[4] == "37%"


def test_a_changed_summary_moves_the_sample_efficiency_prose(docs_copy):
    path = docs_copy / "sample-efficiency" / "summary.json"
    rows = json.loads(path.read_text())
    for r in rows:
        if (r["variant"], r["budget"], r["condition"]) == ("cacla-sigma0.3", 100000, "calm"):
            r["mean_return"] = -77.77
    path.write_text(json.dumps(rows))
    page = results_pages.render("sample-efficiency", docs_copy)
    assert f"CACLA {MINUS}77.8 against" in page


def test_a_changed_closed_loop_row_moves_the_perception_prose(docs_copy):
    def change(r):
        if (r["water"], r["camera"], r["controller"]) == ("clear", "vision", "heuristic"):
            r["mean_return"] = "-99.5"

    _rewrite_csv(docs_copy / "vision" / "closed_loop.csv", change)
    page = results_pages.render("perception", docs_copy)
    assert re.search(f"alone\\s+\\([^)]*\\) and {MINUS}99.5 with the tracker", page)


def test_a_missing_stored_output_is_a_one_line_error_naming_it(docs_copy):
    (docs_copy / "robustness" / "curve.csv").unlink()
    with pytest.raises(PageError, match=r"robustness/curve\.csv: cannot be read"):
        results_pages.render("robustness", docs_copy)


# ---------------------------------------------------------------------------------------------
# The pieces


def test_fill_refuses_a_missing_and_an_unused_field():
    assert fill("{a} and {b}", a=1, b="x") == "1 and x"
    with pytest.raises(PageError, match="'b' has no value"):
        fill("{a} and {b}", a=1)
    with pytest.raises(PageError, match=r"\['c'\] not used"):
        fill("{a}", a=1, c=2)


def test_numbers_are_written_with_the_minus_sign_and_no_negative_zero():
    assert num(-41.31569) == f"{MINUS}41.3"
    assert num(2.25, 1, sign=True) == "+2.2"  # round half to even, as Python formats
    assert num(-0.04) == "0.0" and num(-0.04, 1, sign=True) == "+0.0"
    assert num(float("nan")) == "—"
    assert minus("last-50 return -9.3, [-1.2, 3]") == f"last-50 return {MINUS}9.3, [{MINUS}1.2, 3]"


def test_markdown_tables_are_read_by_their_heading():
    text = "# A\n\n| x | y |\n|---|---|\n| 1 | 2 |\n| 3 | 4 |\n\n## B\n\n| z |\n|---|\n| 5 |\n"
    assert markdown_tables(text) == {"A": [[{"x": "1", "y": "2"}, {"x": "3", "y": "4"}]], "B": [[{"z": "5"}]]}


# ---------------------------------------------------------------------------------------------
# The water presets: the table, the --water help and the one-line description


def test_the_presets_table_says_what_the_code_sets():
    from pipefollow.perception.water import WATER_PRESETS, Water

    page = (RESULTS / "perception.md").read_text(encoding="utf-8")
    (rows,) = markdown_tables(page)["The water presets"]
    assert [r["field"].strip("`") for r in rows] == list(Water._fields)
    for r in rows:
        for name, preset in WATER_PRESETS.items():
            assert float(r[f"`{name}`"].strip("*")) == getattr(preset, r["field"].strip("`"))
        assert float(r["default"]) == getattr(Water(), r["field"].strip("`"))


def test_the_presets_change_blur_noise_and_snow_with_the_turbidity():
    from pipefollow.perception.water import PRESET_FIELDS, WATER_PRESETS

    assert set(PRESET_FIELDS) == {"turbidity", "blur", "noise", "snow"}
    order = sorted(WATER_PRESETS.values(), key=lambda w: w.turbidity)
    for field in PRESET_FIELDS:
        values = [getattr(w, field) for w in order]
        assert values == sorted(values) and values[0] < values[-1]


def test_the_water_help_names_every_preset_and_every_field_a_preset_sets():
    from pipefollow.perception.water import PRESET_FIELDS, WATER_PRESETS

    for command in ("benchmark", "evaluate"):
        res = CliRunner().invoke(main, [command, "--help"], terminal_width=400)
        assert res.exit_code == 0
        line = " ".join(res.output.split())
        water = line[line.index("--water PRESET") : line.index("--turbidity C")]
        for word in (*WATER_PRESETS, *PRESET_FIELDS):
            assert word in water, (command, word)


def test_describe_names_the_preset_and_its_settings():
    from pipefollow.perception.water import describe, water_from

    assert describe(water_from("moderate")) == (
        "water moderate: turbidity 0.2/m, blur 0.9 px, noise 5 grey levels, 12 snow particles/frame"
    )
    buried = describe(water_from({"preset": "turbid", "burial": 0.25}))
    assert buried.startswith("water turbid: turbidity 0.25/m,")
    assert buried.endswith(", 0.25 of the width buried")
    murky = describe(water_from({"preset": "clear", "turbidity": 0.3}))
    assert murky == "water custom: turbidity 0.3/m, blur 0.6 px, noise 3 grey levels, 4 snow particles/frame"


def test_evaluate_prints_the_camera_and_water_in_one_line_under_its_head():
    pytest.importorskip("cv2")
    args = ["evaluate", "--controller", "heuristic", "--pipeline", "paper-left", "--seconds", "3",
            "--camera", "vision", "--water", "turbid"]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    lines = res.output.splitlines()
    assert lines[1] == (
        "camera vision, water turbid: turbidity 0.25/m, blur 1.2 px, noise 7 grey levels, "
        "25 snow particles/frame"
    )


def test_benchmark_prints_the_camera_and_water_in_one_line_under_its_head():
    pytest.importorskip("cv2")
    args = ["benchmark", "--controller", "heuristic", "--pipes", "2", "--seconds", "3",
            "--camera", "vision", "--water", "moderate", "--burial", "0.2"]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    lines = res.output.splitlines()
    assert lines[0].startswith("heuristic on 'heldout': 2 pipes")
    assert lines[1] == (
        "  camera vision, water moderate: turbidity 0.2/m, blur 0.9 px, noise 5 grey levels, "
        "12 snow particles/frame, 0.2 of the width buried"
    )
    assert lines[2].startswith("  mean return")


# ---------------------------------------------------------------------------------------------
# The command


def test_the_command_writes_the_committed_pages_and_checks_them(tmp_path):
    out = tmp_path / "results"
    readme_copy = tmp_path / "README.md"
    readme_copy.write_bytes((DOCS.parent / "README.md").read_bytes())
    args = ["--docs", str(DOCS), "--readme", str(readme_copy)]
    res = CliRunner().invoke(main, ["docs", "results", *args, "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in out.iterdir()) == sorted(f"{n}.md" for n in results_pages.PAGES)
    for p in out.iterdir():
        assert p.read_bytes() == (RESULTS / p.name).read_bytes()
    assert readme_copy.read_bytes() == (DOCS.parent / "README.md").read_bytes()  # the README was current
    ok = CliRunner().invoke(main, ["docs", "results", *args, "--out", str(out), "--check"])
    assert ok.exit_code == 0 and f"up to date: {len(results_pages.PAGES)} page(s)" in ok.output
    (out / "robustness.md").write_text("old\n")
    stale = CliRunner().invoke(main, ["docs", "results", *args, "--out", str(out), "--check"])
    assert stale.exit_code == 1 and stale.output.strip() == f"stale: {out / 'robustness.md'}"
    assert (out / "robustness.md").read_text() == "old\n"  # --check writes nothing


def test_the_command_refuses_an_unknown_page_and_a_missing_folder(tmp_path):
    res = CliRunner().invoke(main, ["docs", "results", "--page", "nope", "--out", str(tmp_path)])
    assert res.exit_code == 2 and "unknown page 'nope'" in res.output
    missing = str(tmp_path / "none")
    res = CliRunner().invoke(main, ["docs", "results", "--docs", missing, "--out", str(tmp_path)])
    assert res.exit_code == 2 and "no such folder" in res.output
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------------------------------
# From scratch: the reproduction's stored outputs and page


@pytest.mark.slow
def test_the_reproduction_regenerates_to_the_committed_outputs_and_page(tmp_path):
    run = tmp_path / "run"
    cmd = [sys.executable, "-m", "pipefollow.cli"]
    subprocess.run([*cmd, "reproduce", "--out", str(run), "--no-figures"], check=True, capture_output=True)
    assert (run / "evaluation.csv").read_bytes() == (DOCS / "reproduction" / "evaluation.csv").read_bytes()
    subprocess.run([*cmd, "plot", str(run)], check=True, capture_output=True)
    docs = tmp_path / "docs"
    (docs / "reproduction").mkdir(parents=True)
    for name in ("REPORT.md", "evaluation.csv"):
        shutil.copy(run / name, docs / "reproduction" / name)
    shutil.copytree(DOCS / "repeats", docs / "repeats", ignore=shutil.ignore_patterns("*.png", "*.csv"))

    def body(text: str) -> list[str]:  # the provenance names the machine of the run: not compared
        machine = "| `docs/reproduction/REPORT.md` |"
        return [line for line in text.splitlines() if not line.startswith(machine)]

    fresh = results_pages.render("reproduction", docs)
    assert body(fresh) == body((RESULTS / "reproduction.md").read_text(encoding="utf-8"))


# ---------------------------------------------------------------------------------------------
# The README's claims table


def test_the_readme_claims_table_is_what_the_stored_reports_give():
    from pipefollow.experiments.results_pages import readme

    assert not readme.stale(DOCS.parent / "README.md", DOCS)


def test_a_changed_verdict_makes_the_readme_stale_and_the_command_rewrites_it(tmp_path):
    from pipefollow.experiments.results_pages import readme

    docs = tmp_path / "docs"
    for name in ("reproduction", "repeats"):
        (docs / name).mkdir(parents=True)
        (docs / name / "REPORT.md").write_bytes((DOCS / name / "REPORT.md").read_bytes())
    shutil.copytree(DOCS / "speed", docs / "speed")  # the README's compile time
    copy = tmp_path / "README.md"
    copy.write_bytes((DOCS.parent / "README.md").read_bytes())
    report = docs / "repeats" / "REPORT.md"
    text = report.read_text(encoding="utf-8")
    assert "SARSA: 12/30 repeats converged." in text
    old, new = "SARSA: 12/30 repeats converged.", "SARSA: 13/30 repeats converged."
    report.write_text(text.replace(old, new), "utf-8")
    assert readme.stale(copy, docs)
    args = ["--docs", str(docs), "--readme", str(copy), "--page", "reproduction", "--out", str(tmp_path)]
    check = CliRunner().invoke(main, ["docs", "results", *args, "--check"])
    assert (
        check.exit_code == 1
        and f"stale: the generated blocks (claims table, compile time) of {copy}" in check.output
    )
    assert readme.update(copy, docs) and new in copy.read_text(encoding="utf-8")
    assert not readme.stale(copy, docs)
    copy.write_text("no markers\n")
    with pytest.raises(results_pages.PageError, match="marker lines"):
        readme.render(copy, docs)


# ---------------------------------------------------------------------------------------------
# Provenance of the stored outputs


def test_a_stored_provenance_file_is_cited_on_the_page(tmp_path):
    import json

    from pipefollow.files.machine import PROVENANCE_FILE, provenance
    from pipefollow.files.sources import package_modules, source_hash

    record = provenance("python examples/generalize_table.py runs/generalize --csv out/heldout.csv")
    sources = record["code"]["sources"]
    assert sources == source_hash(package_modules()) and len(sources) == 16
    assert record["date"].endswith(" UTC") and record["machine"]["numba_cpu_target"]
    docs = tmp_path / "docs"
    (docs / "generalize").mkdir(parents=True)
    (docs / "generalize" / "heldout.csv").write_bytes((DOCS / "generalize" / "heldout.csv").read_bytes())
    before = results_pages.render("generalization", docs)
    assert "| `docs/generalize/heldout.csv` | not recorded |" in before
    (docs / "generalize" / PROVENANCE_FILE).write_text(json.dumps(record))
    after = results_pages.render("generalization", docs)
    assert "not recorded |" not in after.split("\n\n")[3]  # the provenance table
    assert "`python examples/generalize_table.py runs/generalize --csv out/heldout.csv`" in after
    assert record["code"]["sources"] in after and record["machine"]["numba_cpu_target"] in after


# ---------------------------------------------------------------------------------------------
# The closed-loop table of every sensor (examples/closed_loop_table.py's CSV)


def _sensor_row(sensor, water, controller, label, mean, success, lost, same=None, ideal=None, clear=None):
    """One row of ``heldout`` as examples/closed_loop_table.py writes it; differences (mean, low, high)."""
    from pipefollow.experiments.results_pages.closed_loop_sensors import NEED

    r = dict.fromkeys(NEED, "")
    r |= {"suite": "heldout", "sensor": sensor, "water": water, "controller": controller, "label": label,
          "n_pipes": "100", "mean_return": mean, "ci95_low": "-1", "ci95_high": "1",
          "success_rate": success, "pipe_in_view": "0.9", "turned_back": "0", "lost_pipes": lost}  # fmt: skip
    for key, v in (("vs_same", same), ("vs_ideal", ideal), ("vs_clear", clear)):
        if v is not None:
            r[key], r[key + "_low"], r[key + "_high"] = v
    return r


def _sensor_rows() -> list[dict]:
    """A small table as examples/closed_loop_table.py writes it: one suite, two sensors, one water."""
    row = _sensor_row
    return [
        row("ideal", "any", "heuristic", "heuristic", "-41.25", "0.82", "0"),
        row(
            "ideal",
            "any",
            "ppo",
            "PPO",
            "6.5",
            "1.0",
            "0",
            ("47.8", "41.1", "54.4"),
            ("47.8", "41.1", "54.4"),
        ),
        row("sonar", "clear", "heuristic", "heuristic", "-90.0", "0.5", "7", None, ("-48.75", "-55", "-40")),
        row(
            "sonar",
            "clear",
            "ppo",
            "PPO",
            "-88.0",
            "0.6",
            "3",
            ("2.0", "-3.5", "7.5"),
            ("-46.75", "-50", "-40"),
        ),
    ]


def _buried_rows() -> list[dict]:
    """:func:`_sensor_rows` and the sonar's cells with the pipe half buried (``vs_clear`` filled)."""

    def row(controller, label, mean, same, ideal, clear):
        return _sensor_row("sonar", "half-buried", controller, label, mean, "0.5", "1", same, ideal, clear)

    return _sensor_rows() + [
        row("heuristic", "heuristic", "-95.0", None, ("-53.75", "-60", "-45"), ("-5.0", "-9.0", "-1.5")),
        row("ppo", "PPO", "-86.0", ("9.0", "4", "14"), ("-44.75", "-50", "-40"), ("2.0", "-1.0", "5.0")),
    ]


def _write_rows(path: Path, rows: list[dict]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, list(rows[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def test_the_sensor_section_tables_a_synthetic_csv(tmp_path):
    from pipefollow.experiments.results_pages.closed_loop_sensors import SOURCE, section

    _write_rows(tmp_path / SOURCE, _sensor_rows())
    text = section(tmp_path)
    tables = markdown_tables(text)
    returns = tables["`heldout`: mean return (success, pipes lost)"][0]
    diffs = tables["`heldout`: against the heuristic through the same sensor"][0]
    assert [(r["water"], r["controller"]) for r in returns] == [("clear", "heuristic"), ("clear", "PPO")]
    # the ideal camera's one row (water "any") stands in every water's rows
    assert returns[0]["ideal camera"] == f"{MINUS}41.2 (82%, 0 lost)"  # −41.25 to one decimal: even
    assert returns[1]["sonar"] == f"{MINUS}88.0 (60%, 3 lost)"
    # PPO against the heuristic through the same sensor; the heuristic against the ideal camera's
    assert diffs[1]["sonar"] == f"+2.0 [{MINUS}3.5, +7.5]"  # the interval holds 0: not bold
    assert diffs[1]["ideal camera"] == "**+47.8 [+41.1, +54.4]**"
    assert diffs[0]["controller"] == "heuristic (vs the ideal camera)"
    assert (
        diffs[0]["sonar"] == f"**{MINUS}48.8 [{MINUS}55.0, {MINUS}40.0]**" and diffs[0]["ideal camera"] == "—"
    )
    # the prose counts the cells beside the heuristic: PPO better on the ideal camera, undecided on sonar
    assert "of 2 learned or LOS cells:\n  1 better (interval above 0), 0 worse" in text
    assert f"`heldout`: sonar {MINUS}48.8" in text
    assert "ideal camera: PPO (6.5); sonar: PPO (" + MINUS + "88.0)" in text


def test_the_sensor_section_sets_each_water_against_the_same_controller_in_clear_water(tmp_path):
    from pipefollow.experiments.results_pages.closed_loop_sensors import SOURCE, section

    _write_rows(tmp_path / SOURCE, _buried_rows())
    text = section(tmp_path)
    costs = markdown_tables(text)["`heldout`: against the same controller in clear water"][0]
    # one row per controller in each water but clear; no column for the ideal camera (any water)
    rows = [(r["water"], r["controller"]) for r in costs]
    assert rows == [("half buried", "heuristic"), ("half buried", "PPO")]
    assert list(costs[0]) == ["water", "controller", "sonar"]
    assert costs[0]["sonar"] == f"**{MINUS}5.0 [{MINUS}9.0, {MINUS}1.5]**"  # below 0: worse half buried
    assert costs[1]["sonar"] == f"+2.0 [{MINUS}1.0, +5.0]"  # undecided
    assert "of 2 cells: 1 worse half buried (interval below 0),\n  0 better, the rest undecided" in text
    # without a fused cell the fused count says so
    assert "through the camera fused with the multibeam sonar\n  —." in text
    fused = _sensor_row(
        "fused", "half-buried", "ppo", "PPO", "-80.0", "0.6", "2", None, None, ("-3.0", "-6.0", "-0.5")
    )
    _write_rows(tmp_path / SOURCE, [*_buried_rows(), fused])
    text = section(tmp_path)
    assert (
        "of 3 cells: 2 worse half buried" in text
        and "through the camera fused with the multibeam sonar\n  `heldout` 1 of 1 worse." in text
    )


def test_a_clear_water_table_has_no_third_table(tmp_path):
    from pipefollow.experiments.results_pages.closed_loop_sensors import SOURCE, section

    _write_rows(tmp_path / SOURCE, _sensor_rows())
    assert "against the same controller in clear water" not in section(tmp_path)


def test_the_sensor_section_refuses_a_table_of_another_script(tmp_path):
    from pipefollow.experiments.results_pages.closed_loop_sensors import SOURCE, section

    rows = [{k: v for k, v in r.items() if k != "vs_same"} for r in _sensor_rows()]
    _write_rows(tmp_path / SOURCE, rows)
    with pytest.raises(
        PageError, match=r"closed_loop_sensors/table\.csv: not a table of examples/closed_loop_table"
    ):
        section(tmp_path)


def test_a_changed_sensor_row_moves_the_perception_page(docs_copy):
    def change(r):
        if (r["suite"], r["sensor"], r["water"], r["controller"]) == ("heldout", "sonar", "turbid", "ppo"):
            r["mean_return"] = "-77.77"

    _rewrite_csv(docs_copy / "vision" / "closed_loop_sensors" / "table.csv", change)
    page = results_pages.render("perception", docs_copy)
    rows = markdown_tables(page)["`heldout`: mean return (success, pipes lost)"][0]
    row = next(r for r in rows if (r["water"], r["controller"]) == ("turbid", "PPO"))
    assert row["sonar"].startswith(f"{MINUS}77.8 (")
