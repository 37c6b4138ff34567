import json

import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.cli import tables as listings
from pipefollow.sim.pipeline import Pipeline


def test_builtin_pipelines_with_their_segments_and_lengths():
    rows = {e.name: e for e in listings.pipelines() if e.group == "built-in"}
    assert list(rows) == ["paper-left", "paper-right", "paper-validation"]
    assert (rows["paper-left"].segments, rows["paper-left"].length_m) == (3, 12.5)  # 2 + 2.5 + 8
    assert (rows["paper-right"].segments, rows["paper-right"].length_m) == (3, 12.5)
    # 4 + 5 + 3.5 + 6 + 4.5 + 5 m and an 8-m run-out
    assert (rows["paper-validation"].segments, rows["paper-validation"].length_m) == (7, 36.0)
    assert all(e.group == "built-in" and e.description for e in rows.values())


def test_a_source_of_more_pipelines_is_listed_after_the_builtins(monkeypatch):
    monkeypatch.setattr(listings, "_SOURCES", list(listings._SOURCES))
    square = Pipeline([[0, 0], [3, 0], [3, 4]], name="suite-a")

    def suite():
        return [listings.entry(square, "suite", "two legs")]

    listings.add_pipeline_source(suite)
    listings.add_pipeline_source(suite)  # once only
    names = [e.name for e in listings.pipelines()]
    assert names[:3] == ["paper-left", "paper-right", "paper-validation"] and names[-1] == "suite-a"
    assert listings.pipelines()[-1].length_m == 7.0


def test_cli_pipelines_table_and_json():
    runner = CliRunner()
    res = runner.invoke(main, ["pipelines", "--json"])
    assert res.exit_code == 0, res.output
    rows = json.loads(res.stdout)
    assert [r["name"] for r in rows] == ["paper-left", "paper-right", "paper-validation"] + [
        f"random:{f}" for f in ("easy", "medium", "hard", "mixed")
    ]
    assert rows[2]["segments"] == 7 and rows[2]["length_m"] == 36.0
    res = runner.invoke(main, ["pipelines"])
    lines = res.stdout.splitlines()
    assert lines[0].split()[:4] == ["name", "group", "segments", "length"]
    assert lines[3].split()[:4] == ["paper-validation", "built-in", "7", "36.00"]


def test_cli_trials_of_the_paper_and_of_a_file(tmp_path):
    runner = CliRunner()
    res = runner.invoke(main, ["trials", "--json"])
    assert res.exit_code == 0, res.output
    rows = json.loads(res.stdout)
    assert len(rows) == 8 and rows[0]["name"] == "sarsa" and rows[0]["algorithm"] == "sarsa"
    validation = rows[-1]
    assert validation["episodes"] == 1000 and validation["options"] == "skew 22.5°, supervised"
    assert [p["pipeline"] for p in validation["phases"]] == ["paper-left", "paper-right"]
    path = tmp_path / "exp.toml"
    path.write_text('[experiment]\nname = "mine"\nrepeats = 3\n[[trial]]\nname = "only"\nlabel = "Only one"')
    res = runner.invoke(main, ["trials", "--experiment", str(path)])
    assert res.exit_code == 0, res.output
    lines = res.stdout.splitlines()
    assert lines[0] == "mine: 1 trials, 3 repeats each (seeds from 2010)"
    assert lines[2].split()[:4] == ["only", "Only", "one", "cacla"]


@pytest.mark.parametrize("content", [None, b"\xff\xfe\x00garbage", b"[experiment\n"])
def test_cli_trials_of_a_bad_file_is_a_one_line_error(tmp_path, content):
    path = tmp_path / "exp.toml"
    if content is not None:
        path.write_bytes(content)
    res = CliRunner().invoke(main, ["trials", "--experiment", str(path)])
    assert res.exit_code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and str(path) in lines[0]


def test_the_random_families_are_listed_by_the_name_train_accepts():
    from pipefollow.sim.pipe_names import resolve_training

    rows = [e for e in listings.pipelines() if e.group == "random family"]
    assert [e.name for e in rows] == ["random:easy", "random:medium", "random:hard", "random:mixed"]
    for e in rows:
        family = resolve_training(e.name)
        assert family.pipe(0).length == pytest.approx(e.length_m)


def test_cli_trials_name_the_camera_sensor_and_water_of_the_evaluation(tmp_path):
    path = tmp_path / "exp.toml"
    path.write_text(
        '[experiment]\nname = "seeing"\n[[trial]]\nname = "plain"\n'
        '[[trial]]\nname = "fused"\ncamera = "vision"\nsensor = "fused"\nwater = "turbid"\n'
        '[[trial]]\nname = "raw"\ncamera = "vision-raw"\nwater = { preset = "clear", burial = 0.5 }\n'
    )
    res = CliRunner().invoke(main, ["trials", "--experiment", str(path), "--json"])
    assert res.exit_code == 0, res.output
    rows = {r["name"]: r for r in json.loads(res.stdout)}
    assert rows["plain"]["options"] == ""  # the paper's camera says nothing
    assert rows["fused"]["options"] == "camera vision, sensor fused, water turbid"
    assert rows["raw"]["options"] == "camera vision-raw, water preset=clear burial=0.5"
    fused = rows["fused"]
    assert (fused["camera"], fused["sensor"], fused["water"]) == ("vision", "fused", "turbid")
    res = CliRunner().invoke(main, ["trials", "--experiment", str(path)], terminal_width=200)
    assert "camera vision, sensor fused, water turbid" in res.stdout
