"""The speed results page and the README's compile time, from stored benchmark runs.

``benchmarks/stored.py`` writes a run's record (figures, clock, load, cores) and its provenance
beside it; ``pipefollow docs results`` renders the records into ``docs/results/speed.md`` and the
README's compile-time sentence, and reruns nothing. Small hand-made records with hand-computed cells.
"""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import pytest

from pipefollow.experiments.results_pages import readme, speed
from pipefollow.experiments.results_pages.markdown import PageError

ROOT = Path(__file__).resolve().parents[1]


def _stored():
    spec = importlib.util.spec_from_file_location("stored", ROOT / "benchmarks" / "stored.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize(
    ("seconds", "text"),
    [
        (6.25e-6, "6.25 µs"),
        (14.4e-6, "14.4 µs"),
        (285e-6, "285 µs"),
        (0.0966, "96.6 ms"),
        (0.9996, "1000 ms"),  # below one second stays in ms
        (8.78, "8.78 s"),
        (91.53, "91.5 s"),
        (1234.0, "1234 s"),
        (None, "—"),
        (math.nan, "—"),
    ],
)
def test_a_duration_is_written_in_the_unit_that_suits_it(seconds, text):
    assert speed.duration(seconds) == text


def _rows(source: str) -> list[tuple]:
    """Every row the summary cites for ``source``, with round medians (the row's index + 1 ms)."""
    keys = [
        k
        for k in vars(speed).values()
        if isinstance(k, tuple) and len(k) == 2 and k[0] == source and isinstance(k[1], str)
    ]
    return [(name, (i + 1) * 1e-3, None, None) for i, (_, name) in enumerate(keys)]


def _docs(tmp_path) -> Path:
    stored = _stored()
    docs = tmp_path / "docs"
    for source in speed.SOURCES:
        rows = _rows(source)
        if source == speed.ENV_STEP[0]:
            rows += [("RK4 substep (closed loop)", 0.34e-6, None, 0.09e-6), ("x, target", 0.2, 0.1, 0.05)]
        stored.write(
            docs / source, source.split("/")[1][:-5], "wall", 7, [0.5, 0.25, 0.125], rows, ["a note"]
        )
    return docs


def test_a_stored_record_holds_the_run_its_load_and_its_provenance(tmp_path):
    docs = _docs(tmp_path)
    record = json.loads((docs / "speed" / "run.json").read_text(encoding="utf-8"))
    assert record["format"] == speed.FORMAT and record["repeats"] == 7 and record["clock"] == "wall"
    assert (
        record["load_average"]["before"] == [0.5, 0.25, 0.125] and len(record["load_average"]["after"]) == 3
    )
    assert record["rows"][-1] == {"name": "x, target", "median_s": 0.2, "target_s": 0.1, "floor_s": 0.05}
    own = json.loads((docs / "speed" / "run.provenance.json").read_text(encoding="utf-8"))
    assert set(own) == {"command", "date", "code", "machine"} and own["command"].startswith("python ")


def test_the_page_tables_each_run_and_cites_its_rows(tmp_path):
    docs = _docs(tmp_path)
    text = speed.render(docs)
    # the floor and its ratio: 0.34 / 0.09 = 3.8; a target missed: 0.2 s > 0.1 s; 0.2 / 0.05 = 4.0
    assert "| RK4 substep (closed loop) | 0.34 µs | — | — | 0.09 µs | 3.8 |" in text
    assert "| x, target | 200 ms | 100 ms | no | 50.0 ms | 4.0 |" in text
    assert "| env.step (1-s decision) | 1.00 ms | — | — | — | — |" in text
    # the summary's fields: the cited rows' medians (the order of speed's keys: 1 ms, 2 ms, ...)
    run_rows = dict((name, t) for name, t, _, _ in _rows("speed/run.json"))
    assert "with a warm compile cache" in text
    assert f"{speed.duration(run_rows[speed.COLD[1]])} with an empty one" in text
    assert "7 repeats, wall time, " in text and "load average 0.50 / 0.25 / 0.12 before" in text
    assert "* a note" in text
    assert text.count("| `docs/speed/") == len(speed.SOURCES)  # each record's provenance cited
    assert "not recorded |" not in text.split("## In brief")[0]


def test_a_missing_cited_row_and_a_foreign_file_are_errors_naming_them(tmp_path):
    docs = _docs(tmp_path)
    path = docs / "speed" / "sonar.json"
    record = json.loads(path.read_text(encoding="utf-8"))
    record["rows"] = []
    path.write_text(json.dumps(record), encoding="utf-8")
    with pytest.raises(PageError, match="speed/sonar.json: no row 'SonarSensor.step"):
        speed.render(docs)
    path.write_text(json.dumps({"rows": []}), encoding="utf-8")
    with pytest.raises(PageError, match="not a benchmark record"):
        speed.render(docs)


def test_the_readme_compile_time_comes_from_the_stored_run(tmp_path):
    docs = _docs(tmp_path)
    run_rows = dict((name, t) for name, t, _, _ in _rows("speed/run.json"))
    sentence = readme.compile_time(docs)
    assert f"took {speed.duration(run_rows[speed.COLD[1]])} with an empty compile cache" in sentence
    assert f"and {speed.duration(run_rows[speed.WARM[1]])} with a warm" in sentence
    block = readme.speed_block(docs)
    assert block.startswith(readme.SPEED_BEGIN + "\n") and block.endswith("\n" + readme.SPEED_END)
