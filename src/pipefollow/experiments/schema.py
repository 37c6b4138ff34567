"""The experiment configuration's schema: frozen dataclasses, their field docs, range checks and plain form.

:class:`Phase`, :class:`TrialConfig` and :class:`ExperimentConfig` carry every field's unit and
source in ``metadata["help"]`` (:func:`field_help`; ``pipefollow reproduce --help`` and the report
use it) and the allowed values in ``metadata["choices"]``. :func:`validate` checks a record's
ranges; :func:`to_dict` and :func:`from_dict` give the plain-data form of a run folder's
``config.json``. Reading TOML files into these records is :mod:`pipefollow.experiments.config`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from pipefollow import readings as rd
from pipefollow.files.limits import MAX_EPISODE_SECONDS as MAX_SECONDS
from pipefollow.files.limits import MAX_EPISODES, MAX_REPEATS
from pipefollow.files.paper_training import EPISODE_SECONDS, TRAINING_EPISODES
from pipefollow.learners.options import LEARNER_OPTIONS, OPTION, PHASE_OPTIONS, check_schedule
from pipefollow.learners.registry import NAMES as ALGORITHMS
from pipefollow.learners.registry import agent_options, learner, takes, taking
from pipefollow.perception.camera import CAMERAS, SENSORS, SONAR_ALONE

# Figure and table keys of the report a trial can belong to (``figures = [...]`` in a trial).
FIGURE_KEYS = ("fig5", "fig6", "fig7", "table1")


class ConfigError(ValueError):
    """An experiment configuration that cannot be used."""


NAME_PATTERN = r"[A-Za-z0-9_.@=,+-]+"  # trial names are file names; '@' joins a name and a reading id


def _f(default, help: str, **kw):
    return field(default=default, metadata={"help": help, **kw})


@dataclass(frozen=True)
class Phase:
    """One stretch of training on one pipeline."""

    pipeline: str = _f(
        "paper-left",
        "pipeline to train on: built-in name, JSON file, or random:FAMILY (a new pipe every episode)",
    )
    episodes: int = _f(
        TRAINING_EPISODES, "episodes of this phase; σ runs from sigma_start to sigma_end over them"
    )
    learner: dict | None = _f(
        None,
        "learner options of this phase's episodes in place of the trial's: a table of "
        "pipefollow.learners.options.PHASE_OPTIONS (actor_repeats, critic_lambda, the step sizes); "
        "none by default",
    )


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
    # The learners' options, one field each, from their one table (pipefollow.learners.options):
    # skew_deg, supervised, actor_update, actor_repeats, critic_lambda, the step sizes, the σ
    # schedule and the observed state.
    for _o in LEARNER_OPTIONS:
        __annotations__[_o.name] = _o.kind.__name__
        vars()[_o.name] = _f(_o.default, _o.help, **({"choices": _o.choices} if _o.choices else {}))
    del _o
    phases: tuple[Phase, ...] = _f((Phase(),), "training phases in order (paper §4.2: left, then right)")
    episode_seconds: float = _f(EPISODE_SECONDS, "episode length (s); one decision per second (paper §4.1)")
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
        "(mild, moderate, vision, harsh) or a table of pipefollow.sim.randomization.KEYS; not with "
        "disturbance",
    )
    camera: str = _f(
        "ideal",
        "camera of the evaluation episode: ideal (the paper's), vision (rendered image, pipe detector and "
        "tracker; extra vision) or vision-raw (the detector alone, frame by frame); training stays on the "
        "ideal camera's compiled loops unless train_through_sensor",
        choices=CAMERAS,
    )
    water: dict | str | None = _f(
        None,
        "water and camera settings of the vision cameras and the sonar: a preset name (clear, moderate, "
        "turbid) or a table of pipefollow.perception.water.Water fields (preset key allowed); clear by "
        "default",
    )
    sensor: str = _f(
        "camera",
        "sensor of the evaluation episode: camera (the camera alone), sonar (the look-ahead multibeam "
        "alone, with camera ideal) or fused (the camera's detections, the sonar's where it finds none)",
        choices=SENSORS,
    )
    train_through_sensor: bool = _f(
        False,
        "train through the camera, sensor and water above too (in the environment, frame by frame), "
        "not in the ideal camera's compiled loops",
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


def check_readings(ids, where: str) -> None:
    """Refuse reading ids that do not parse; raises :class:`ConfigError` naming ``where``."""
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
        for key, value in (obj.learner or {}).items():
            if key not in PHASE_OPTIONS:
                raise ConfigError(f"{where}: key 'learner' may set {', '.join(PHASE_OPTIONS)}, not {key!r}")
            try:
                OPTION[key].check(value)
            except ValueError:
                raise bad(f"learner.{key}", OPTION[key].allowed(), value) from None
    elif isinstance(obj, TrialConfig):
        import re

        if not re.fullmatch(NAME_PATTERN, obj.name):
            raise bad("name", "letters, digits and any of - _ . @ = , +", obj.name)
        for o in LEARNER_OPTIONS:  # each value as its table allows, then the learner's own
            try:
                o.check(getattr(obj, o.name))
            except ValueError:
                raise bad(o.name, o.allowed(), getattr(obj, o.name)) from None
        try:
            agent_options(obj.algorithm, learner_values(obj), strict=False)
            check_schedule(obj.sigma_start, obj.sigma_end)
        except ValueError as e:
            raise ConfigError(f"{where}: {_keyed(e)}") from None
        for i, phase in enumerate(obj.phases):
            for key in phase.learner or {}:
                if not takes(learner(obj.algorithm), key):
                    raise ConfigError(f"{where}.phases[{i}]: key 'learner.{key}' applies to algorithm "
                                      f"{' and '.join(taking(key))} only")  # fmt: skip
        check_readings(obj.readings, f"{where}: key 'readings'")
        if obj.sensor in SONAR_ALONE and obj.camera != "ideal":
            raise bad(
                "camera", f"'ideal' with sensor = {obj.sensor!r} (the sonar observes alone)", obj.camera
            )
        if obj.train_through_sensor and obj.camera == "ideal" and obj.sensor == "camera":
            what = "false with the ideal camera alone (the compiled loops are that camera)"
            raise bad("train_through_sensor", what, obj.train_through_sensor)
        for key in ("episode_seconds", "evaluate_seconds"):
            if not 1.0 <= getattr(obj, key) <= MAX_SECONDS:
                raise bad(key, f"from 1 to {MAX_SECONDS:g} (s)", getattr(obj, key))
    elif isinstance(obj, ExperimentConfig):
        for rid in obj.compare_readings:
            check_readings((rid,), f"{where}: key 'compare_readings'")
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


def learner_values(trial: TrialConfig, phase: Phase | None = None) -> dict:
    """The values of ``trial``'s learner options (:data:`~pipefollow.learners.options.LEARNER_OPTIONS`).

    With a ``phase``, those it sets for its episodes (its ``learner`` table) in their place.
    """
    return {o.name: getattr(trial, o.name) for o in LEARNER_OPTIONS} | dict((phase and phase.learner) or {})


def _keyed(e: ValueError) -> str:
    """``sigma_start must be …`` as ``key 'sigma_start' must be …``; other messages as they are."""
    text = str(e)
    first, _, rest = text.partition(" must be ")
    return f"key '{first}' must be {rest}" if rest and " " not in first else text


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
