"""CACLA+Var and TD(λ) paired against the learner without them: the pairing and the page's sections.

``examples/sample_efficiency_options.py`` pairs the run files of ``examples/sample_efficiency.py``;
the sample-efficiency page renders its ``options.json``. Small hand-made runs and records with
hand-computed cells.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

from pipefollow.experiments.results_pages import sample_efficiency_options as section
from pipefollow.experiments.results_pages.markdown import MINUS, PageError

ROOT = Path(__file__).resolve().parents[1]


def _script():
    spec = importlib.util.spec_from_file_location(
        "sample_efficiency_options", ROOT / "examples" / "sample_efficiency_options.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _run(variant, seed, calm, disturbed, sqrt_var=None):
    r = {"variant": variant, "budget": 10000, "seed": seed, "steps": 9990, "wall_s": 0.1,
         "calm": {"returns": calm, "in_view": [1.0] * len(calm)},
         "disturbed": {"returns": disturbed, "in_view": [1.0] * len(disturbed)}}  # fmt: skip
    if sqrt_var is not None:
        r["sqrt_td_var"] = sqrt_var
    return r


def test_the_pairing_averages_the_seeds_per_pipe_then_differences():
    runs = [
        _run("cacla", 0, [0.0, 1.0], [0.0, 0.0], 1.0),
        _run("cacla", 1, [1.0, 1.0], [0.0, 0.0], 1.0),
        _run("cacla-var", 0, [1.0, 3.0], [-1.0, 0.0], 2.5),
        _run("cacla-var", 1, [2.0, 6.0], [1.0, -2.0], 3.5),
        _run("cacla-td0.9", 0, [0.0, 1.0], [0.0, 0.0]),  # its seed 1 is missing: seed 0 only
    ]
    rows = _script().compare(runs)
    by = {(r["option"], r["condition"]): r for r in rows}
    assert set(by) == {(o, c) for o in ("cacla-var", "cacla-td0.9") for c in ("calm", "disturbed")}
    calm = by["cacla-var", "calm"]
    # per pipe over the seeds: option (1.5, 4.5), base (0.5, 1.0): differences 1.0 and 3.5
    assert calm["mean_diff"] == pytest.approx(2.25)
    assert calm["ci95_diff"][0] >= 1.0 - 1e-12 and calm["ci95_diff"][1] <= 3.5 + 1e-12
    assert calm["seeds_higher"] == 2 and calm["seeds"] == [0, 1] and calm["pipes"] == 2
    assert calm["sqrt_td_var"] == [2.5, 3.5] and calm["family"] == "var" and calm["lambda"] is None
    dist = by["cacla-var", "disturbed"]
    # seed 0: −0.5 against 0 (lower); seed 1: −0.5 against 0 (lower); per pipe (0, −1) − (0, 0)
    assert dist["mean_diff"] == pytest.approx(-0.5) and dist["seeds_higher"] == 0
    td = by["cacla-td0.9", "calm"]
    assert td["seeds"] == [0] and td["mean_diff"] == 0.0 and td["lambda"] == 0.9 and "sqrt_td_var" not in td


def _row(option, learner, family, lam, budget, condition, diff, lo, hi, higher, roots=None):
    r = {"option": option, "base": "", "learner": learner, "family": family, "lambda": lam, "budget": budget,
         "steps": budget - 10, "condition": condition, "seeds": [0, 1, 2], "pipes": 100, "mean_diff": diff,
         "ci95_diff": [lo, hi], "seeds_higher": higher}  # fmt: skip
    if roots is not None:
        r["sqrt_td_var"] = roots
    return r


def _docs(tmp_path, rows, trained=None) -> Path:
    folder = tmp_path / "docs" / "sample-efficiency"
    folder.mkdir(parents=True)
    (folder / "options.json").write_text(json.dumps({"rows": rows, "trained_by": trained}), encoding="utf-8")
    return tmp_path / "docs"


def test_the_var_section_tables_the_cells_and_the_range_of_the_variance(tmp_path):
    rows = [
        _row("cacla-var", "CACLA", "var", None, 10000, "calm", -3.94, -9.04, 1.46, 1, [7.21, 6.77]),
        _row("cacla-var", "CACLA", "var", None, 10000, "disturbed", 3.1, -0.7, 6.9, 2, [7.21, 6.77]),
        _row("cacla-var", "CACLA", "var", None, 100000, "calm", 4.2, -0.8, 8.1, 3, [2.13, 1.51]),
        _row("cacla-var", "CACLA", "var", None, 100000, "disturbed", 0.04, -5.1, 5.4, 2, [2.13, 1.51]),
    ]
    text = section.var_section(_docs(tmp_path, rows))
    assert (
        f"| CACLA | 9,990 | {MINUS}3.9 [{MINUS}9.0, +1.5] | +3.1 [{MINUS}0.7, +6.9] | 1/3, 2/3 | 6.8–7.2 |"
        in text
    )
    assert (
        f"| CACLA | 99,990 | +4.2 [{MINUS}0.8, +8.1] | +0.0 [{MINUS}5.1, +5.4] | 3/3, 2/3 | 1.5–2.1 |" in text
    )
    assert "between 1.5 and 7.2" in text and f"({MINUS}10 per decision" in text
    assert "change sign from budget to budget" in text  # −3.9 calm at 9,990, +4.2 at 99,990
    assert "the seeds (0, 1, 2)" in text and "the 100 pipes" in text
    assert "baselines: not recorded." in text


def test_the_var_section_says_so_when_no_difference_changes_sign(tmp_path):
    rows = [
        _row("cacla-var", "CACLA", "var", None, 10000, c, 1.0, 0.5, 1.5, 3, [2.0, 2.0])
        for c in ("calm", "disturbed")
    ]
    assert "change sign" not in section.var_section(_docs(tmp_path, rows))


def test_the_td_section_has_a_column_per_budget_and_condition_and_counts_the_seeds(tmp_path):
    rows = [
        _row("cacla-td0.9", "CACLA", "td", 0.9, b, c, d, d - 1, d + 1, h)
        for b, c, d, h in (
            (10000, "calm", 8.1, 2),
            (10000, "disturbed", 13.6, 3),
            (30000, "calm", 24.0, 3),
            (30000, "disturbed", -0.25, 1),
        )
    ]
    text = section.td_section(_docs(tmp_path, rows))
    assert (
        "| learner | λ | calm 9,990 | disturbed 9,990 | calm 29,990 | disturbed 29,990 | seeds higher |"
        in text
    )
    assert (
        f"| CACLA | 0.9 | +8.1 [+7.1, +9.1] | +13.6 [+12.6, +14.6] | +24.0 [+23.0, +25.0] | "
        f"{MINUS}0.2 [{MINUS}1.2, +0.8] | 9/12 |"
    ) in text


def test_a_record_without_the_family_is_an_error_naming_the_file(tmp_path):
    docs = _docs(tmp_path, [_row("cacla-td1", "CACLA", "td", 1.0, 10000, "calm", 1.0, 0.0, 2.0, 3)])
    with pytest.raises(PageError, match="options.json: no rows of the option family 'var'"):
        section.var_section(docs)


def test_the_page_cites_where_the_runs_were_trained(tmp_path):
    trained = {"command": "python examples/sample_efficiency.py --out R --variants cacla cacla-var",
               "date": "2026-12-03 07:19 UTC", "code": {"version": "0.1.0", "sources": "0123456789abcdef"},
               "machine": {"host_cpu": "CPU X"}}  # fmt: skip
    rows = [
        _row("cacla-var", "CACLA", "var", None, 10000, c, 1.0, 0.5, 1.5, 3, [2.0])
        for c in ("calm", "disturbed")
    ]
    text = section.var_section(_docs(tmp_path, rows, trained))
    assert (
        "`python examples/sample_efficiency.py --out R --variants cacla cacla-var` on 2026-12-03 07:19 UTC"
        in text
    )
    assert "0123456789abcdef" in text
