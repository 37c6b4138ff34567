"""The run folder: everything a reproduction produced, written so that an interruption loses nothing.

Layout of a run folder ``RUN``::

    RUN/config.json                      the resolved ExperimentConfig (written first), the code stamp
                                         and the machine it was started on (numba's CPU target, versions)
    RUN/trials/<trial>/seed-<seed>.npz   one finished trial (TrialResult), the unit of resumption
    RUN/policies/<trial>-seed<seed>.npz  its learned policy, a policy file for ``pipefollow evaluate``
    RUN/results.csv                      tidy learning curves: trial × seed × training episode
    RUN/evaluation.csv                   tidy evaluation: trial × seed × evaluated controller

Every file is written through a temporary file in the same folder and ``os.replace``, so a file
with its final name is always complete. A trial file is written last for its trial: its presence
is what "finished" means, and a run started again in the same folder computes only the trials
without one. The tables are regenerated from the trial files (:mod:`pipefollow.experiments.tables`).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from pipefollow.experiments.schema import ConfigError, ExperimentConfig, TrialConfig, from_dict, to_dict
from pipefollow.experiments.trial import TrialResult, build_agent
from pipefollow.files.atomic import TMP_SUFFIX, atomic_file, read_npz_file, write_text_atomic
from pipefollow.files.machine import machine_stamp
from pipefollow.files.sources import imported_modules, source_hash

FORMAT = "pipefollow-trial"
FORMAT_VERSION = 1
CONFIG_FILE = "config.json"


class StoreError(ValueError):
    """A run folder or trial file that cannot be used; the message names it."""


def trial_path(run_dir: str | os.PathLike, trial: str, seed: int) -> Path:
    """Where the result of ``trial`` with ``seed`` is stored."""
    return Path(run_dir) / "trials" / trial / f"seed-{seed}.npz"


def policy_path(run_dir: str | os.PathLike, trial: str, seed: int) -> Path:
    """Where the learned policy of ``trial`` with ``seed`` is stored."""
    return Path(run_dir) / "policies" / f"{trial}-seed{seed}.npz"


def _write_npz_atomic(path: Path, arrays: dict[str, np.ndarray]) -> None:
    with atomic_file(path) as f:
        np.savez(f, **arrays)


# ---------------------------------------------------------------------------------------------
# The folder and its configuration


# The code stamp covers the modules whose code decides a trial's numbers: every module that a
# trial imports (found by walking the imports), so edits elsewhere (the command line, the report,
# figures, this store) do not keep a run from resuming.
TRIAL_MODULE = "pipefollow.experiments.trial"


def result_modules() -> tuple[str, ...]:
    """The modules whose code decides a trial's numbers."""
    return imported_modules(TRIAL_MODULE)


def _code_stamp() -> dict[str, str]:
    """Which code computes this run: package version, a hash of the result modules, numerics libraries."""
    import numba

    import pipefollow

    return {
        "version": pipefollow.__version__,
        "sources": source_hash(result_modules()),
        "numpy": np.__version__,
        "numba": numba.__version__,
    }


def _describe_difference(stored: dict, wanted: dict) -> str:
    """A short account of how two resolved configurations differ."""
    for key in ("name", "repeats", "seed"):
        if stored.get(key) != wanted.get(key):
            return f"{key} {stored.get(key)!r} there, {wanted.get(key)!r} now"
    old = {t["name"]: t for t in stored.get("trials", [])}
    new = {t["name"]: t for t in wanted.get("trials", [])}
    if list(old) != list(new):
        return f"trials {', '.join(old) or 'none'} there; {', '.join(new) or 'none'} now"
    for name, t in new.items():
        for key in t:
            if old[name].get(key) != t[key]:
                return f"trial '{name}': {key} {old[name].get(key)!r} there, {t[key]!r} now"
    return "different content"


def read_config(run_dir: str | os.PathLike) -> ExperimentConfig:
    """The experiment stored in a run folder; :class:`StoreError` if it is not a run folder."""
    run_dir = Path(run_dir)
    path = run_dir / CONFIG_FILE
    if not run_dir.is_dir():
        raise StoreError(f"run folder '{run_dir}': no such folder")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        return from_dict(data)
    except FileNotFoundError:
        msg = f"'{run_dir}' is not a run folder (no {CONFIG_FILE}; 'pipefollow reproduce' writes one)"
        raise StoreError(msg) from None
    except (OSError, ValueError, KeyError, TypeError) as e:
        msg = f"run folder '{run_dir}': unreadable {CONFIG_FILE} ({type(e).__name__}: {e})"
        raise StoreError(msg) from None


def prepare(run_dir: str | os.PathLike, exp: ExperimentConfig) -> Path:
    """Create ``run_dir`` for ``exp``, or check that it holds the same resolved configuration.

    A different configuration raises :class:`ConfigError`; temporary files left by an interrupted
    run are removed. Call it with the folder locked (:func:`pipefollow.experiments.folder.locked`).
    """
    run_dir = Path(run_dir)
    if run_dir.exists() and not run_dir.is_dir():
        raise ConfigError(f"--out '{run_dir}': exists and is not a folder")
    wanted = {**json.loads(json.dumps(to_dict(exp))), "code": _code_stamp()}
    path = run_dir / CONFIG_FILE
    if path.exists():
        try:
            stored = json.loads(path.read_text(encoding="utf-8"))
            same = from_dict(stored) == exp
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise StoreError(f"run folder '{run_dir}': unreadable {CONFIG_FILE} ({e})") from None
        if not same:
            diff = _describe_difference(stored, wanted)
            raise ConfigError(
                f"run folder '{run_dir}' holds a different configuration ({diff}); "
                "use another --out or the same options"
            )
        if stored.get("code") != wanted["code"]:
            then, now = stored.get("code") or {}, wanted["code"]
            differ = ", ".join(
                f"{k} {then.get(k, '?')} there, {now[k]} now" for k in now if then.get(k) != now[k]
            )
            raise ConfigError(
                f"run folder '{run_dir}' was computed by other code ({differ}): "
                "its results would mix with this version's; use another --out"
            )
    else:
        # the machine is a record, not part of what must match on resumption: results do not
        # depend on the CPU (learners.sums), so a run may be resumed on another machine
        record = {**wanted, "machine": machine_stamp()}
        write_text_atomic(path, json.dumps(record, indent=2, ensure_ascii=False) + "\n")
    for tmp in run_dir.rglob(f".*{TMP_SUFFIX}"):
        tmp.unlink(missing_ok=True)
    return run_dir


# ---------------------------------------------------------------------------------------------
# Trial files


def save_trial(run_dir: str | os.PathLike, result: TrialResult, config: TrialConfig | None = None) -> Path:
    """Store ``result`` atomically; with its ``config``, first also write its policy file.

    The trial file comes last: once it exists, the trial counts as finished.
    """
    if config is not None:
        save_policy_file(run_dir, config, result)
    names = list(result.evaluation)
    arrays = {
        "format": np.array(FORMAT),
        "format_version": np.array(FORMAT_VERSION),
        "trial": np.array(result.trial),
        "seed": np.array(str(result.seed)),  # text: seeds may exceed 64 bits (SeedSequence takes any)
        "stats": np.asarray(result.stats, dtype=np.float64),
        "phase": np.asarray(result.phase, dtype=np.int64),
        "sigma": np.asarray(result.sigma, dtype=np.float64),
        "weights": np.asarray(result.weights, dtype=np.float64),
        "evaluation_controllers": np.array(names, dtype=str).reshape(len(names)),
        "evaluation_values": np.array([result.evaluation[n] for n in names], dtype=np.float64).reshape(-1, 4),
        "evaluation_pipeline": np.array(result.evaluation_pipeline),
        "wall_seconds": np.array(float(result.wall_seconds)),
    }
    for name, poses in result.poses.items():
        arrays[f"poses/{name}"] = np.asarray(poses, dtype=np.float64)
    path = trial_path(run_dir, result.trial, result.seed)
    _write_npz_atomic(path, arrays)
    return path


def load_trial(run_dir: str | os.PathLike, trial: str, seed: int) -> TrialResult:
    """Read a stored trial; any problem raises :class:`StoreError` naming the file."""
    path = trial_path(run_dir, trial, seed)
    src = f"trial file '{path}'"
    data = read_npz_file(path, src, StoreError, FORMAT, "trial file")
    try:
        if int(data["format_version"]) > FORMAT_VERSION:
            raise StoreError(f"{src}: format version {int(data['format_version'])} is newer than this reads")
        stored_seed = int(str(data["seed"]))  # int64 in files written before seeds were text
        if str(data["trial"]) != trial or stored_seed != seed:
            raise StoreError(f"{src}: holds trial '{data['trial']}' seed {stored_seed}")
        names = [str(n) for n in data["evaluation_controllers"]]
        values = data["evaluation_values"]
        stats = data["stats"]
        if (
            stats.ndim != 2
            or stats.shape[1] != 4
            or len(data["phase"]) != len(stats)
            or len(data["sigma"]) != len(stats)
            or values.shape != (len(names), 4)
        ):
            raise StoreError(f"{src}: arrays of inconsistent shapes")
        return TrialResult(
            trial=trial,
            seed=seed,
            stats=stats,
            phase=data["phase"],
            sigma=data["sigma"],
            weights=data["weights"],
            evaluation={n: tuple(float(v) for v in row) for n, row in zip(names, values, strict=True)},
            poses={k.split("/", 1)[1]: v for k, v in data.items() if k.startswith("poses/")},
            evaluation_pipeline=str(data["evaluation_pipeline"]),
            wall_seconds=float(data["wall_seconds"]),
        )
    except StoreError:
        raise
    except KeyError as e:
        raise StoreError(f"{src}: missing entry {e}") from None
    except (ValueError, TypeError) as e:
        raise StoreError(f"{src}: malformed entry ({e})") from None


def finished(
    run_dir: str | os.PathLike,
    exp: ExperimentConfig,
    loaded: dict[tuple[str, int], TrialResult] | None = None,
) -> set[tuple[str, int]]:
    """The (trial, seed) pairs of ``exp`` with a complete trial file in ``run_dir``.

    A trial file that does not load or does not fit its trial's configuration is removed: its
    trial counts as unfinished and will be computed again. ``loaded``, if given, receives the
    results read (for :func:`stored_results`, which then need not read them again).
    """
    done = set()
    shapes: dict[str, tuple[int, ...]] = {}
    for t in exp.trials:
        for seed in exp.seeds():
            path = trial_path(run_dir, t.name, seed)
            if not path.exists():
                continue
            try:
                result = load_trial(run_dir, t.name, seed)
            except StoreError:
                path.unlink(missing_ok=True)
                continue
            if t.name not in shapes:
                shapes[t.name] = build_agent(t).weights.shape
            if len(result.stats) != t.episodes or result.weights.shape != shapes[t.name]:
                path.unlink(missing_ok=True)
                continue
            done.add((t.name, seed))
            if loaded is not None:
                loaded[t.name, seed] = result
    return done


def save_policy_file(run_dir: str | os.PathLike, config: TrialConfig, result: TrialResult) -> Path:
    """Write the learned policy of ``result`` as a policy file (``pipefollow evaluate --controller``)."""
    from pipefollow.training.policy_files import save_policy

    agent = build_agent(config)
    agent.weights[...] = result.weights
    pipelines = " then ".join(p.pipeline for p in config.phases)
    return save_policy(
        agent,
        policy_path(run_dir, result.trial, result.seed),
        trial=config.name,
        label=config.title,
        seed=result.seed,
        pipeline=pipelines,
        episodes=config.episodes,
        compress=False,
    )


def ensure_policies(run_dir: str | os.PathLike, exp: ExperimentConfig) -> int:
    """Write the policy files missing for finished trials; returns how many were written."""
    written = 0
    for t in exp.trials:
        for seed in exp.seeds():
            if trial_path(run_dir, t.name, seed).exists() and not policy_path(run_dir, t.name, seed).exists():
                save_policy_file(run_dir, t, load_trial(run_dir, t.name, seed))
                written += 1
    return written


def stored_results(
    run_dir: str | os.PathLike,
    exp: ExperimentConfig,
    known: Mapping[tuple[str, int], TrialResult] | None = None,
) -> dict[tuple[str, int], TrialResult]:
    """Every stored trial of ``exp`` by (trial, seed), in the experiment's order.

    ``known`` holds results already in memory (those a run just saved); the others are read from
    their trial files. Trials without a trial file are left out.
    """
    known = known or {}
    out = {}
    for t in exp.trials:
        for seed in exp.seeds():
            if (t.name, seed) in known:
                out[t.name, seed] = known[t.name, seed]
            elif trial_path(run_dir, t.name, seed).exists():
                out[t.name, seed] = load_trial(run_dir, t.name, seed)
    return out
