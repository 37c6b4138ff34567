"""Option values as the command line writes them, parsed into what the library takes.

Each parser raises :class:`~pipefollow.sim.disturbance.DisturbanceError` with one line; the option
decorators of :mod:`pipefollow.cli.options` turn it into a usage error naming the option. The
library is imported when a value is parsed, so that building the options imports nothing heavy.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any


def parse_current(text: str) -> tuple[float, float]:
    """``--current SPEED,DIR_DEG`` → ``(V_c m/s, β_c degrees)``; raises :class:`DisturbanceError`."""
    from pipefollow.sim.disturbance import DisturbanceError

    parts = str(text).split(",")
    if len(parts) != 2:
        raise DisturbanceError(f"expected SPEED,DIR_DEG (m/s, degrees towards, from north), got {text!r}")
    try:
        speed, direction = float(parts[0]), float(parts[1])
    except ValueError:
        raise DisturbanceError(f"expected two numbers SPEED,DIR_DEG, got {text!r}") from None
    if not (math.isfinite(speed) and math.isfinite(direction)):
        raise DisturbanceError(f"SPEED and DIR_DEG must be finite, got {text!r}")
    if speed < 0.0:
        raise DisturbanceError(f"SPEED must be ≥ 0 m/s, got {speed:g}")
    return speed, direction


def parse_camera_noise(value: Any) -> float:
    """``--camera-noise M``: a camera-noise s.d. (m), a finite number ≥ 0."""
    from pipefollow.sim.disturbance import non_negative

    return non_negative(value, "camera noise")


def parse_sensor_noise(name: str):
    """A parser of ``--dvl-noise M/S`` or ``--gyro-noise DEG/S``: a noise s.d., a finite number ≥ 0."""

    def parse(value: Any) -> float:
        from pipefollow.sim.disturbance import non_negative

        return non_negative(value, name)

    return parse


def parse_miss_prob(value: Any) -> float:
    """``--miss-prob P``: a miss probability, a number in [0, 1]."""
    from pipefollow.sim.disturbance import probability

    return probability(value, "miss probability")


def parse_randomization(spec: str):
    """``--randomization PRESET|FILE.toml`` → a checked :class:`~pipefollow.sim.randomization.Randomization`.

    A preset name, or a TOML file holding the table or a ``[randomization]`` table.

    Raises:
        DisturbanceError: an unreadable file, bad TOML, an unknown preset or a bad table.
    """
    from pipefollow.sim.disturbance import DisturbanceError
    from pipefollow.sim.randomization import from_dict, resolve

    if not str(spec).endswith(".toml"):
        return resolve(spec, "--randomization")
    import tomllib

    from pipefollow.files.atomic import read_text_file

    source = f"--randomization {spec}"
    try:
        table = tomllib.loads(read_text_file(spec, source, DisturbanceError))
    except tomllib.TOMLDecodeError as e:
        raise DisturbanceError(f"{source}: not valid TOML ({e})") from None
    if isinstance(table.get("randomization"), Mapping):
        table = table["randomization"]
    return from_dict(table, source)
