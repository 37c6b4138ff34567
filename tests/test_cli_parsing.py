"""The option values of the command line, parsed (``pipefollow.cli.parsing``)."""

from __future__ import annotations

import pytest

from pipefollow.cli.parsing import parse_camera_noise, parse_current, parse_miss_prob, parse_randomization
from pipefollow.sim import randomization as rz
from pipefollow.sim.disturbance import DisturbanceError


@pytest.mark.parametrize(
    ("text", "expected"), [("0.1,45", (0.1, 45.0)), (" 0.2 , -90 ", (0.2, -90.0)), ("0,0", (0.0, 0.0))]
)
def test_parse_current(text, expected):
    assert parse_current(text) == expected


@pytest.mark.parametrize("text", ["0.1", "0.1,45,3", "a,b", "-0.1,0", "inf,0", "0.1,nan", ""])
def test_parse_current_rejects(text):
    with pytest.raises(DisturbanceError):
        parse_current(text)


def test_camera_noise_and_miss_probability_are_checked_with_their_names():
    assert parse_camera_noise(0.05) == 0.05 and parse_miss_prob(1.0) == 1.0
    with pytest.raises(DisturbanceError, match="^camera noise must be ≥ 0, got -0.01$"):
        parse_camera_noise(-0.01)
    with pytest.raises(DisturbanceError, match=r"^miss probability must be a probability in \[0, 1\], got 2"):
        parse_miss_prob(2.0)


def test_randomization_from_a_preset_or_a_toml_file(tmp_path):
    assert parse_randomization("mild") == rz.PRESETS["mild"]
    table = tmp_path / "r.toml"
    table.write_text('[randomization]\npreset = "mild"\nmiss_prob = [0.0, 0.5]\n', encoding="utf-8")
    assert parse_randomization(str(table)).miss_prob == (0.0, 0.5)
    table.write_text("miss_prob = [", encoding="utf-8")
    with pytest.raises(DisturbanceError, match=f"--randomization {table}: not valid TOML"):
        parse_randomization(str(table))
    with pytest.raises(DisturbanceError, match="--randomization"):
        parse_randomization("stormy")
