"""Policy files: a learned agent in one ``.npz`` (loaded with ``allow_pickle=False``).

A file holds ``format`` (``pipefollow-policy``), ``format_version``, ``package_version``,
``algorithm`` (a learner of :mod:`pipefollow.learners.registry`: ``sarsa``, ``cacla``, ``ac``),
the learner's own fields (its ``policy_fields``: ``params``, JSON of the agent's parameter record,
``grid`` and, for SARSA, ``action_grid``, JSON feature specifications, and ``weights``) and
``readings``: the id of the readings the policy was trained under (docs/design.md), under which
it is evaluated unless told otherwise. The loaded agent carries it as ``agent.readings``.
``state`` names what the learner observes (:mod:`pipefollow.sim.observation`; ``paper`` when
absent), the loaded agent's ``agent.state``; ``options`` (JSON, when written by a training run) holds
the values of the learner options of :data:`pipefollow.learners.options.LEARNER_OPTIONS` it was
trained with, its σ schedule too (:func:`policy_options`; the loaded agent's ``agent.learner_options``).

Format versions read: 3 (``readings`` and CACLA's reading fields) and 4, which adds
``algorithm`` ``mlp``: a feed-forward network exported from a deep-RL learner
(:class:`~pipefollow.learners.mlp.MLPPolicy`), stored as ``n_layers``, ``layer{k}_weight`` (out × in) and
``layer{k}_bias`` (float64), ``activations`` (JSON list: ``identity``, ``tanh`` or ``relu`` per
layer), ``output`` (``clip`` or ``tanh``), ``obs_offset``, ``obs_scale``, ``action_low``,
``action_high``, ``trained_by`` (``ppo``, ``sac``) and ``params`` (JSON: the training's
hyper-parameters, for the record). Loading it needs neither torch nor Stable-Baselines3.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

import pipefollow
from pipefollow.files.atomic import atomic_file, read_npz_file
from pipefollow.learners.mlp import MLPPolicy
from pipefollow.learners.registry import LEARNERS, NAMES, learner_of

FORMAT = "pipefollow-policy"
FORMAT_VERSION = 4  # 3: readings; 4: mlp
OLDEST_FORMAT_VERSION = 3  # the first with readings; older files are refused


class PolicyError(ValueError):
    """A policy file that cannot be used; the message names the file and the problem."""


def save_policy(
    agent, path: str | os.PathLike, *, compress: bool = True, options: dict | None = None, **metadata
) -> Path:
    """Write ``agent`` (a learner of the registry, or an MLP) to ``path`` (``.npz``) atomically.

    The file holds the agent's readings' id (``agent.readings``) and its named state
    (``agent.state``), and ``options``, the learner options it trained with (option → value), if
    given; extra string ``metadata`` is stored too.
    ``compress=False`` stores the arrays uncompressed (a run folder's many policies: zlib cost more
    time than the files' size is worth); either kind loads the same way.
    """
    path = Path(path)
    if isinstance(agent, MLPPolicy):
        return _save_mlp(agent, path, metadata)
    kind = learner_of(agent)
    if kind is None:
        raise TypeError(f"cannot save a policy of type {type(agent).__name__}")
    arrays = {
        **_header(kind.name, metadata),
        **kind.policy_fields(agent),
        "readings": np.array(getattr(agent, "readings", "default")),
        "state": np.array(getattr(agent, "state", "paper")),
    }
    if options is not None:
        arrays["options"] = np.array(json.dumps(options))
    with atomic_file(path) as f:
        (np.savez_compressed if compress else np.savez)(f, **arrays)
    return path


def trained_through(camera: dict) -> str:
    """The camera, sensor and water a run trained through, as the JSON its policy file records.

    :func:`~pipefollow.perception.camera.camera_record`, with the sensor named also when it is the
    camera alone.
    """
    from pipefollow.perception.camera import camera_record

    record = {"sensor": camera.get("sensor", "camera"), **camera_record(camera)}
    return json.dumps(record, sort_keys=True)


def _header(algorithm: str, metadata: dict) -> dict[str, np.ndarray]:
    return {
        "format": np.array(FORMAT),
        "format_version": np.array(FORMAT_VERSION),
        "package_version": np.array(pipefollow.__version__),
        "algorithm": np.array(algorithm),
        "metadata": np.array(json.dumps({k: str(v) for k, v in metadata.items()})),
    }


def _save_mlp(agent: MLPPolicy, path: Path, metadata: dict) -> Path:
    hyper = metadata.pop("hyperparameters", {})
    arrays = {
        **_header("mlp", metadata),
        "params": np.array(json.dumps(hyper)),
        "n_layers": np.array(len(agent.weights)),
        "activations": np.array(json.dumps(agent.activations)),
        "output": np.array(agent.output),
        "obs_offset": agent.obs_offset,
        "obs_scale": agent.obs_scale,
        "action_low": agent.action_low,
        "action_high": agent.action_high,
        "trained_by": np.array(agent.trained_by),
        "readings": np.array(agent.readings),
    }
    for k, (w, b) in enumerate(zip(agent.weights, agent.biases, strict=True)):
        arrays[f"layer{k}_weight"], arrays[f"layer{k}_bias"] = w, b
    with atomic_file(path) as f:
        np.savez_compressed(f, **arrays)
    return path


def _load_mlp(data: dict, src: str) -> MLPPolicy:
    try:
        n = int(data["n_layers"])
        weights = [np.asarray(data[f"layer{k}_weight"], dtype=np.float64) for k in range(n)]
        biases = [np.asarray(data[f"layer{k}_bias"], dtype=np.float64) for k in range(n)]
        activations = json.loads(str(data["activations"]))
        fields = {k: np.asarray(data[k], dtype=np.float64) for k in ("obs_offset", "obs_scale")}
        fields |= {k: np.asarray(data[k], dtype=np.float64) for k in ("action_low", "action_high")}
        output, trained_by = str(data["output"]), str(data["trained_by"])
    except (KeyError, ValueError, TypeError) as e:
        raise PolicyError(f"{src}: missing or malformed entry ({e})") from None
    if not isinstance(activations, list) or len(activations) != n:
        raise PolicyError(f"{src}: 'activations' must list one activation per layer ({n})")
    try:
        agent = MLPPolicy(weights, biases, activations, output=output, trained_by=trained_by, **fields)
    except ValueError as e:
        raise PolicyError(f"{src}: network does not fit the environment ({e})") from None
    agent.readings = str(data.get("readings", "default"))
    agent.hyperparameters = json.loads(str(data.get("params", "{}")))
    return agent


def load_policy(path: str | os.PathLike, seed: int | None = None):
    """Read a policy file written by :func:`save_policy`; problems raise :class:`PolicyError`."""
    path = Path(path)
    src = f"policy file '{path}'"
    data = read_npz_file(path, src, PolicyError, FORMAT, "policy")
    if str(data.get("algorithm", "")) == "mlp":
        version = int(data.get("format_version", 0))
        if version > FORMAT_VERSION:
            raise PolicyError(f"{src}: format version {version} is newer than this pipefollow reads")
        return _load_mlp(data, src)
    try:
        version = int(data["format_version"])
        algorithm = str(data["algorithm"])
    except (KeyError, ValueError, TypeError) as e:
        raise PolicyError(f"{src}: missing or malformed entry ({e})") from None
    if version > FORMAT_VERSION:
        raise PolicyError(f"{src}: format version {version} is newer than this pipefollow reads")
    if version < OLDEST_FORMAT_VERSION:
        raise PolicyError(f"{src}: format version {version} is older than this pipefollow reads")
    if algorithm not in LEARNERS:
        expected = ", ".join(NAMES)
        raise PolicyError(f"{src}: unknown algorithm '{algorithm}' (expected {expected} or mlp)")
    missing = [k for k in ("params", "grid", "weights") if k not in data]
    if missing:
        raise PolicyError(f"{src}: missing or malformed entry ({missing[0]!r})")
    try:
        agent, weights = LEARNERS[algorithm].from_policy(data, seed)
    except (TypeError, KeyError, ValueError) as e:
        raise PolicyError(f"{src}: parameters do not fit algorithm '{algorithm}' ({e})") from None
    if weights.shape != agent.weights.shape:
        raise PolicyError(f"{src}: weights have shape {weights.shape}, expected {agent.weights.shape}")
    if not np.all(np.isfinite(weights)):
        raise PolicyError(f"{src}: weights contain NaN or infinite values")
    agent.weights[...] = weights
    _read_state_and_options(agent, data, src)
    return agent


def _read_state_and_options(agent, data: dict, src: str) -> None:
    """``agent.state`` and ``agent.learner_options`` from the file; a state must fit the grid."""
    from pipefollow.sim.observation import components

    state = str(data.get("state", "paper"))
    try:
        entries = len(components(state))
    except ValueError as e:
        raise PolicyError(f"{src}: {e}") from None
    if entries != agent.grid.ndim:
        raise PolicyError(f"{src}: state {state!r} has {entries} entries, its RBF grid {agent.grid.ndim}")
    agent.state = state
    try:
        options = json.loads(str(data["options"])) if "options" in data else {}
    except ValueError as e:
        raise PolicyError(f"{src}: malformed entry 'options' ({e})") from None
    agent.learner_options = options if isinstance(options, dict) else {}


def policy_options(agent) -> dict:
    """The learner options a loaded policy trained with (none for files that do not say), and its state."""
    return {**getattr(agent, "learner_options", {}), "state": getattr(agent, "state", "paper")}
