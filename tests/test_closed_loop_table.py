"""``examples/closed_loop_table.py``'s rows from stored cells: the paired comparisons they carry."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def table():
    path = ROOT / "examples" / "closed_loop_table.py"
    spec = importlib.util.spec_from_file_location("closed_loop_table", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _store(table, cells: Path, suite, sensor, water, returns: np.ndarray, code: str, c="heuristic") -> None:
    stats = np.zeros((len(returns), len(table.ep.STAT_NAMES)))
    stats[:, table.ep.STAT_RETURN] = returns
    stats[:, table.ep.STAT_IN_VIEW] = 1.0
    cell = {"stamp": table.stamp_of(c, code), "stats": stats.tolist()}
    path = table.cell_path(cells, suite, sensor, water, c)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(cell), encoding="utf-8")


def test_a_half_buried_row_is_paired_with_the_same_controller_in_clear_water(table, tmp_path):
    pipes = table.get_suite("heldout").pipes(20, table.min_length_for(table.SECONDS))
    rng = np.random.default_rng(3)
    clear = rng.normal(-40.0, 10.0, len(pipes))
    buried = clear - rng.uniform(2.0, 6.0, len(pipes))  # every pipe 2–6 worse half buried
    code, specs = "c0de", {"heuristic": "heuristic"}
    _store(table, tmp_path, "heldout", "ideal", "any", clear + 5.0, code)
    _store(table, tmp_path, "heldout", "fused", "clear", clear, code)
    _store(table, tmp_path, "heldout", "fused", "half-buried", buried, code)
    row = table.row_of(tmp_path, "heldout", "fused", "half-buried", "heuristic", specs, code, pipes)
    assert row["vs_clear"] == pytest.approx(np.mean(buried - clear))
    assert row["vs_clear_low"] <= row["vs_clear"] <= row["vs_clear_high"] < 0.0  # worse at every pipe
    assert row["vs_ideal"] == pytest.approx(np.mean(buried - clear - 5.0))
    # another controller is paired with its own clear-water cell, not the heuristic's
    los_clear = clear + rng.normal(0.0, 5.0, len(pipes))
    _store(table, tmp_path, "heldout", "fused", "clear", los_clear, code, "los")
    _store(table, tmp_path, "heldout", "fused", "half-buried", los_clear - 1.0, code, "los")
    los = table.row_of(
        tmp_path, "heldout", "fused", "half-buried", "los", specs | {"los": "los"}, code, pipes
    )
    assert los["vs_clear"] == pytest.approx(-1.0)
    assert los["vs_same"] == pytest.approx(np.mean(los_clear - 1.0 - buried))
    clear_row = table.row_of(tmp_path, "heldout", "fused", "clear", "heuristic", specs, code, pipes)
    assert clear_row["vs_clear"] is None and clear_row["vs_clear_low"] is None
    # a cell of other code is not read: the clear-water reference is missing, the row has none
    _store(table, tmp_path, "heldout", "fused", "clear", clear, "other")
    row = table.row_of(tmp_path, "heldout", "fused", "half-buried", "heuristic", specs, code, pipes)
    assert row is not None and row["vs_clear"] is None
