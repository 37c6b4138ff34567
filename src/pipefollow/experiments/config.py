"""Experiment files: TOML read into the schema's records (the paper's grid: ``paper.toml``), and overrides.

The records, their field docs and range checks are :mod:`pipefollow.experiments.schema` (whose
names this module also gives, as before). An unknown key or an invalid value raises
:class:`ConfigError` naming the file, the key and what is allowed.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

from pipefollow.experiments.schema import (
    FIGURE_KEYS,
    MAX_EPISODES,
    MAX_REPEATS,
    MAX_SECONDS,
    NAME_PATTERN,
    ConfigError,
    ExperimentConfig,
    Phase,
    TrialConfig,
    check_readings,
    field_help,
    from_dict,
    to_dict,
    validate,
)
from pipefollow.files.atomic import read_text_file

__all__ = [
    "FIGURE_KEYS",
    "MAX_EPISODES",
    "MAX_REPEATS",
    "MAX_SECONDS",
    "NAME_PATTERN",
    "ConfigError",
    "ExperimentConfig",
    "Phase",
    "TrialConfig",
    "field_help",
    "from_dict",
    "load_experiment",
    "parse_experiment",
    "shipped_experiments",
    "to_dict",
    "validate",
    "with_overrides",
]


def _check_keys(data: dict, cls, where: str, extra: tuple[str, ...] = ()) -> None:
    allowed = [f.name for f in dataclasses.fields(cls)] + list(extra)
    for key in data:
        if key not in allowed:
            raise ConfigError(f"{where}: unknown key '{key}'; allowed: {', '.join(allowed)}")


def _coerce(cls, data: dict, where: str):
    """Build ``cls`` from a TOML table, checking each value's type and range."""
    _check_keys(data, cls, where)
    kwargs: dict[str, Any] = {}
    for f in dataclasses.fields(cls):
        if f.name not in data:
            continue
        value = data[f.name]
        key = f"{where}: key '{f.name}'"
        default = f.default
        if f.name == "phases":
            if not isinstance(value, list) or not value or not all(isinstance(v, dict) for v in value):
                raise ConfigError(f"{key} must be a non-empty list of tables {{pipeline, episodes}}")
            kwargs[f.name] = tuple(_coerce(Phase, v, f"{where}.phases[{i}]") for i, v in enumerate(value))
            continue
        if f.name == "trials":
            kwargs[f.name] = value
            continue
        if f.name == "disturbance":
            _check_disturbance(value, key)
            kwargs[f.name] = dict(value)
            continue
        if f.name == "learner":  # a phase's options: a table, checked by validate
            if not isinstance(value, dict):
                raise ConfigError(f"{key} must be a table of learner options, got {value!r}")
            kwargs[f.name] = dict(value)
            continue
        if f.name == "water":
            camera, sensor = data.get("camera", "ideal"), data.get("sensor", "camera")
            kwargs[f.name] = _check_water(value, key, camera, sensor)
            continue
        if f.name == "randomization":
            kwargs[f.name] = _check_randomization(value, key, data.get("disturbance"))
            continue
        if f.name in ("figures", "readings", "compare_readings"):
            if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
                raise ConfigError(f"{key} must be a list of strings")
            unknown = [v for v in value if v not in FIGURE_KEYS] if f.name == "figures" else []
            if unknown:
                raise ConfigError(f"{key}: unknown figure {unknown[0]!r}; allowed: {', '.join(FIGURE_KEYS)}")
            kwargs[f.name] = tuple(value)
            continue
        if isinstance(default, bool):
            if not isinstance(value, bool):
                raise ConfigError(f"{key} must be true or false, got {value!r}")
        elif isinstance(default, int):
            if not isinstance(value, int) or isinstance(value, bool):
                raise ConfigError(f"{key} must be an integer, got {value!r}")
        elif isinstance(default, float):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ConfigError(f"{key} must be a finite number, got {value!r}")
            value = float(value)
        elif isinstance(default, str):
            if not isinstance(value, str):
                raise ConfigError(f"{key} must be a string, got {value!r}")
        choices = f.metadata.get("choices")
        if choices and value not in choices:
            raise ConfigError(f"{key} must be one of {', '.join(choices)}, got {value!r}")
        kwargs[f.name] = value
    obj = cls(**kwargs)
    validate(obj, where)
    return obj


def _check_randomization(value, where: str, disturbance) -> dict:
    """A preset name or a table → the table (``{"preset": name}`` for a name); one-line errors."""
    from pipefollow.sim.disturbance import DisturbanceError
    from pipefollow.sim.randomization import both_given, resolve

    table = {"preset": value} if isinstance(value, str) else value
    if not isinstance(table, dict):
        raise ConfigError(f"{where} must be a preset name or a table, got {value!r}")
    if both_given(disturbance or None, table):
        raise ConfigError(f"{where}: give a disturbance or a randomization, not both")
    try:
        resolve(table, where)
    except DisturbanceError as e:
        raise ConfigError(str(e)) from None
    return dict(table)


def _check_water(value, where: str, camera, sensor="camera") -> dict | str:
    """A water preset name or table, checked (one-line errors); only with a vision camera or the sonar."""
    from pipefollow.perception.camera import VISION_CAMERAS
    from pipefollow.perception.water import WaterError, water_from

    if camera not in VISION_CAMERAS and sensor == "camera":
        raise ConfigError(
            f"{where}: water settings need camera = 'vision' or 'vision-raw' or sensor = 'sonar', 'fused', "
            "'fls' or 'fused-fls', "
            f"got camera = {camera!r}"
        )
    if not isinstance(value, (str, dict)):
        raise ConfigError(f"{where} must be a preset name or a table, got {value!r}")
    try:
        water_from(value)
    except WaterError as e:
        raise ConfigError(f"{where}: {e}") from None
    return dict(value) if isinstance(value, dict) else value


def _check_disturbance(table, where: str) -> None:
    from pipefollow.sim.disturbance import DisturbanceError, disturbance_from_dict

    try:
        disturbance_from_dict(table, where)
    except DisturbanceError as e:
        raise ConfigError(str(e)) from None


def parse_experiment(data: dict, source: str) -> ExperimentConfig:
    """An :class:`ExperimentConfig` from parsed TOML (``[experiment]``, ``[defaults]``, ``[[trial]]``)."""
    _check_keys(data, ExperimentConfig, source, extra=("experiment", "defaults", "trial"))
    for key in ("name", "repeats", "seed", "trials"):
        if key in data:
            raise ConfigError(f"{source}: key '{key}' belongs in the [experiment] table")
    head = data.get("experiment", {})
    defaults = data.get("defaults", {})
    if not isinstance(head, dict) or not isinstance(defaults, dict):
        raise ConfigError(f"{source}: [experiment] and [defaults] must be tables")
    _check_keys(head, ExperimentConfig, f"{source} [experiment]")
    if "trials" in head:
        raise ConfigError(f"{source} [experiment]: give trials as [[trial]] tables")
    _check_keys(defaults, TrialConfig, f"{source} [defaults]")
    tables = data.get("trial", [])
    if not isinstance(tables, list):
        raise ConfigError(f"{source}: 'trial' must be an array of tables [[trial]]")
    if "trials_from" in head:
        base = head["trials_from"]
        if not isinstance(base, str) or tables or defaults:
            raise ConfigError(
                f"{source} [experiment]: 'trials_from' must name an experiment, with no [defaults] "
                "or [[trial]] tables beside it"
            )
        if base == head.get("name") or base == source:
            raise ConfigError(f"{source} [experiment]: 'trials_from' names this experiment itself")
        head = {**head, "trials": load_experiment(base).trials}
        return _coerce(ExperimentConfig, head, f"{source} [experiment]")
    trials = []
    for i, table in enumerate(tables):
        if not isinstance(table, dict):
            raise ConfigError(f"{source}: [[trial]] #{i + 1} must be a table, got {table!r}")
        where = f"{source} [[trial]] #{i + 1}" + (f" '{table['name']}'" if "name" in table else "")
        trials.append(_coerce(TrialConfig, {**defaults, **table}, where))
    return _coerce(ExperimentConfig, {**head, "trials": tuple(trials)}, f"{source} [experiment]")


def shipped_experiments() -> list[str]:
    """Names of the experiments shipped with the package (``paper``, ``repeats``, ``readings`` …)."""
    folder = resources.files("pipefollow.experiments")
    return sorted(p.name[: -len(".toml")] for p in folder.iterdir() if p.name.endswith(".toml"))


def load_experiment(spec: str | Path = "paper") -> ExperimentConfig:
    """Read an experiment: a shipped one by name (``paper``, ``readings``) or a path to a TOML file.

    Pipeline file names in the file that are relative paths are taken relative to the file's folder.
    """
    if str(spec) in shipped_experiments():
        folder_res = resources.files("pipefollow.experiments")
        text = folder_res.joinpath(f"{spec}.toml").read_text(encoding="utf-8")
        source = f"{spec}.toml"
        folder = None
    else:
        path = Path(spec)
        source = f"experiment file '{path}'"
        text = read_text_file(path, source, ConfigError)
        folder = path.parent
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ConfigError(f"{source}: not valid TOML ({e})") from None
    exp = parse_experiment(data, source)
    return exp if folder is None else _relative_to(exp, folder)


def _relative_to(exp: ExperimentConfig, folder: Path) -> ExperimentConfig:
    """``exp`` with relative pipeline file paths joined to ``folder`` (built-in names stay)."""
    import os

    from pipefollow.sim.pipeline import BUILTIN_NAMES

    def rebase(name: str) -> str:
        if not name or name in BUILTIN_NAMES or Path(name).is_absolute():
            return name
        joined = folder / name
        # Only file names: a name that is neither a .json path nor an existing file stays as
        # given, so that the pipeline resolver reports it (or knows it by another name).
        if Path(name).suffix.lower() == ".json" or joined.exists():
            return os.path.normpath(joined)
        return name

    trials = tuple(
        dataclasses.replace(
            t,
            phases=tuple(dataclasses.replace(p, pipeline=rebase(p.pipeline)) for p in t.phases),
            evaluate_on=rebase(t.evaluate_on),
        )
        for t in exp.trials
    )
    return dataclasses.replace(exp, trials=trials)


def with_overrides(
    exp: ExperimentConfig,
    *,
    repeats: int | None = None,
    episodes: int | None = None,
    seed: int | None = None,
    trials: list[str] | None = None,
    readings: list[str] | None = None,
) -> ExperimentConfig:
    """A copy with command-line overrides.

    Overrides are: repeats, episodes of every phase, seed, a subset of trials, and readings applied
    to every trial (after the trials' own).
    """
    out = exp
    if readings:
        check_readings(readings, "--reading")
        extra = tuple(readings)
        out = dataclasses.replace(
            out, trials=tuple(dataclasses.replace(t, readings=t.readings + extra) for t in out.trials)
        )
    if trials:
        known = [t.name for t in exp.trials]
        for name in trials:
            if name not in known:
                raise ConfigError(f"--trial: unknown trial '{name}'; allowed: {', '.join(known)}")
        out = dataclasses.replace(out, trials=tuple(t for t in out.trials if t.name in trials))
    if repeats is not None:
        out = dataclasses.replace(out, repeats=repeats)
    if seed is not None:
        out = dataclasses.replace(out, seed=seed)
    if episodes is not None:
        out = dataclasses.replace(
            out,
            trials=tuple(
                dataclasses.replace(
                    t, phases=tuple(dataclasses.replace(p, episodes=episodes) for p in t.phases)
                )
                for t in out.trials
            ),
        )
    validate(out, "overrides")
    for t in out.trials:
        for p in t.phases:
            validate(p, f"trial '{t.name}'")
    return out
