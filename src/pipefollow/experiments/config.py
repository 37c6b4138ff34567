"""Experiment configuration: frozen dataclasses read from TOML (the paper's grid: ``paper.toml``).

Every field carries its unit and source in ``metadata["help"]``; ``pipefollow reproduce --help``
and the report use it. An unknown key or an invalid value raises :class:`ConfigError` naming
the file, the key and what is allowed.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from pipefollow import readings as rd
from pipefollow.files.atomic import read_text_file
from pipefollow.learners.registry import NAMES as ALGORITHMS
from pipefollow.learners.registry import check_options

# Bounds that keep a run finite (a day of simulated time per episode is far beyond any use).
MAX_EPISODES = 10_000_000
MAX_SECONDS = 86_400.0
MAX_REPEATS = 100_000

# Figure and table keys of the report a trial can belong to (``figures = [...]`` in a trial).
FIGURE_KEYS = ("fig5", "fig6", "fig7", "table1")


class ConfigError(ValueError):
    """An experiment configuration that cannot be used."""


def _f(default, help: str, **kw):
    return field(default=default, metadata={"help": help, **kw})


@dataclass(frozen=True)
class Phase:
    """One stretch of training on one pipeline."""

    pipeline: str = _f(
        "paper-left",
        "pipeline to train on: built-in name, JSON file, or random:FAMILY (a new pipe every episode)",
    )
    episodes: int = _f(500, "episodes of this phase; σ runs from sigma_start to sigma_end over them")


@dataclass(frozen=True)
class TrialConfig:
    """One learner set-up; a trial is this set-up trained once with one seed."""

    name: str = _f("trial", "identifier, used in file names (letters, digits, '-', '_', '.')")
    label: str = _f("", "label in figures and the report (default: the name)")
    algorithm: str = _f(
        "cacla",
        "learner: sarsa (eq. 3), cacla (eqs. 5-7) or ac (the general actor-critic, eq. 9)",
        choices=ALGORITHMS,
    )
    skew_deg: float = _f(0.0, "CACLA skew step Δγ (deg, eq. 15); 0 = Gaussian exploration (paper §4.1)")
    supervised: bool = _f(
        False, "the heuristic as supervisor: supervised CACLA (eqs. 10-13) or actor-critic (eq. 11)"
    )
    actor_update: str = _f(
        "delta",
        "actor-critic: the actor's step factor on (a - A(s)): delta (eq. 9), positive (max(δ, 0): eq. 7's "
        "max term alone) or sign (sgn δ: eq. 7's sign term alone)",
        choices=("delta", "positive", "sign"),
    )
    phases: tuple[Phase, ...] = _f((Phase(),), "training phases in order (paper §4.2: left, then right)")
    episode_seconds: float = _f(20.0, "episode length (s); one decision per second (paper §4.1)")
    sigma_start: float = _f(1.0, "exploration σ of the first episode, normalized action units (paper §4)")
    sigma_end: float = _f(0.01, "exploration σ of the last episode of each phase (paper §4)")
    alpha_v: float = _f(0.4, "CACLA and actor-critic: critic step size α_V (paper §4)")
    alpha_pi: float = _f(0.2, "CACLA and actor-critic: actor step size α_π (paper §4)")
    alpha_q: float = _f(0.4, "SARSA step size α (paper §4)")
    discount: float = _f(0.8, "discount factor γ_d (paper §4)")
    delta_k: float = _f(0.05, "supervised learners: increment Δk of k(s) per visit (paper §4.1)")
    forgetting: float = _f(0.0, "supervised learners: per-update decay of k's weights; the paper uses none")
    readings: tuple[str, ...] = _f(
        (), "readings of the paper's open points, as key=value ids (docs/design.md); later ones win"
    )
    disturbance: dict | None = _f(
        None,
        "ocean current and camera faults in training and evaluation: a table of "
        "pipefollow.sim.disturbance.TOML_KEYS (m/s, degrees, m); none by default",
    )
    randomization: dict | None = _f(
        None,
        "domain randomization in training: each episode draws its disturbances from a preset name "
        "(mild, moderate, harsh) or a table of pipefollow.sim.randomization.KEYS; not with disturbance",
    )
    evaluate_on: str = _f("", "after training, evaluate deterministically on this pipeline ('' = none)")
    evaluate_seconds: float = _f(60.0, "length of the evaluation episode (s) (paper §4.2)")
    figures: tuple[str, ...] = _f(
        (), "figures/tables of the report that use this trial (fig5, fig6, fig7, table1)", choices=FIGURE_KEYS
    )

    @property
    def title(self) -> str:
        """The label, or the name."""
        return self.label or self.name

    @property
    def episodes(self) -> int:
        """Episodes over all phases."""
        return sum(p.episodes for p in self.phases)

    @property
    def reading(self) -> rd.Readings:
        """The trial's readings of the open points (the defaults, changed by ``readings``)."""
        return rd.parse(self.readings)


@dataclass(frozen=True)
class ExperimentConfig:
    """A set of trials, each repeated with seeds ``seed, seed + 1, …``."""

    name: str = _f("experiment", "identifier of the experiment")
    repeats: int = _f(5, "repeats of every trial (paper §4.1: 5)")
    seed: int = _f(2010, "seed of the first repeat; repeat k uses seed + k")
    trials_from: str = _f("", "take the trials (and their defaults) of this experiment: 'paper' or a file")
    compare_readings: tuple[str, ...] = _f(
        (), "sensitivity study: run every trial under each of these reading ids ('default' = none)"
    )
    trials: tuple[TrialConfig, ...] = _f((), "the trials")

    def seeds(self) -> list[int]:
        """Seeds of the repeats."""
        return [self.seed + k for k in range(self.repeats)]

    def trial(self, name: str) -> TrialConfig:
        """The trial called ``name``."""
        for t in self.trials:
            if t.name == name:
                return t
        raise KeyError(name)


def field_help(cls) -> dict[str, str]:
    """Field name → help text (unit and source) of a config dataclass."""
    return {f.name: f.metadata.get("help", "") for f in dataclasses.fields(cls)}


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


NAME_PATTERN = r"[A-Za-z0-9_.@=,+-]+"  # trial names are file names; '@' joins a name and a reading id


def _check_disturbance(table, where: str) -> None:
    from pipefollow.sim.disturbance import DisturbanceError, disturbance_from_dict

    try:
        disturbance_from_dict(table, where)
    except DisturbanceError as e:
        raise ConfigError(str(e)) from None


def _check_randomization(value, where: str, disturbance) -> dict:
    """A preset name or a table → the table (``{"preset": name}`` for a name); one-line errors."""
    from pipefollow.sim.disturbance import DisturbanceError
    from pipefollow.sim.randomization import resolve

    table = {"preset": value} if isinstance(value, str) else value
    if not isinstance(table, dict):
        raise ConfigError(f"{where} must be a preset name or a table, got {value!r}")
    if disturbance:
        raise ConfigError(f"{where}: give a disturbance or a randomization, not both")
    try:
        resolve(table, where)
    except DisturbanceError as e:
        raise ConfigError(str(e)) from None
    return dict(table)


def _check_readings(ids, where: str) -> None:
    try:
        rd.parse(ids)
    except rd.ReadingError as e:
        raise ConfigError(f"{where}: {e}") from None


def validate(obj, where: str) -> None:
    """Range checks of a config record; raises :class:`ConfigError`."""

    def bad(key: str, what: str, value) -> ConfigError:
        return ConfigError(f"{where}: key '{key}' must be {what}, got {value!r}")

    if isinstance(obj, Phase):
        if not 1 <= obj.episodes <= MAX_EPISODES:
            raise bad("episodes", f"from 1 to {MAX_EPISODES:,}", obj.episodes)
    elif isinstance(obj, TrialConfig):
        import re

        if not re.fullmatch(NAME_PATTERN, obj.name):
            raise bad("name", "letters, digits and any of - _ . @ = , +", obj.name)
        try:
            check_options(
                obj.algorithm, skew_deg=obj.skew_deg, supervised=obj.supervised, actor_update=obj.actor_update
            )
        except ValueError as e:
            raise ConfigError(f"{where}: {e}") from None
        _check_readings(obj.readings, f"{where}: key 'readings'")
        for key in ("alpha_v", "alpha_pi", "alpha_q", "discount"):
            v = getattr(obj, key)
            if not 0.0 < v <= 1.0:
                raise bad(key, "in (0, 1]", v)
        for key in ("skew_deg", "delta_k", "forgetting", "sigma_end"):
            if getattr(obj, key) < 0.0:
                raise bad(key, "≥ 0", getattr(obj, key))
        if obj.forgetting >= 1.0:
            raise bad("forgetting", "below 1", obj.forgetting)
        if obj.sigma_start < obj.sigma_end:
            raise bad("sigma_start", f"≥ sigma_end ({obj.sigma_end})", obj.sigma_start)
        for key in ("episode_seconds", "evaluate_seconds"):
            if not 1.0 <= getattr(obj, key) <= MAX_SECONDS:
                raise bad(key, f"from 1 to {MAX_SECONDS:g} (s)", getattr(obj, key))
        if obj.skew_deg > 180.0:
            raise bad("skew_deg", "at most 180 (deg)", obj.skew_deg)
    elif isinstance(obj, ExperimentConfig):
        for rid in obj.compare_readings:
            _check_readings((rid,), f"{where}: key 'compare_readings'")
        if not 1 <= obj.repeats <= MAX_REPEATS:
            raise bad("repeats", f"from 1 to {MAX_REPEATS:,}", obj.repeats)
        if obj.seed < 0:  # NumPy's SeedSequence takes non-negative integers only
            raise bad("seed", "an integer ≥ 0", obj.seed)
        names = [t.name for t in obj.trials]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ConfigError(f"{where}: trial names must be unique, repeated: {', '.join(sorted(dup))}")
        if not obj.trials:
            raise ConfigError(f"{where}: no [[trial]] tables")


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
    """Names of the experiments shipped with the package (``paper``, ``readings``, ``reference-learners``)."""
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
        _check_readings(readings, "--reading")
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


def to_dict(obj) -> dict:
    """Plain-data form (for the run folder's resolved config)."""
    return dataclasses.asdict(obj)


def from_dict(data: dict) -> ExperimentConfig:
    """Inverse of :func:`to_dict`."""
    trials = tuple(
        TrialConfig(
            **{
                **t,
                "phases": tuple(Phase(**p) for p in t["phases"]),
                "figures": tuple(t["figures"]),
                "readings": tuple(t.get("readings", ())),
            }
        )
        for t in data["trials"]
    )
    return ExperimentConfig(
        name=data["name"],
        repeats=data["repeats"],
        seed=data["seed"],
        trials_from=data.get("trials_from", ""),
        compare_readings=tuple(data.get("compare_readings", ())),
        trials=trials,
    )
