"""A multilayer perceptron policy evaluated without torch: the actor of a deep-RL learner.

An :class:`MLPPolicy` holds dense layers ``h ← act(W h + b)`` with ``W`` of shape (out, in),
an affine observation scaling applied first (``h₀ = (obs − obs_offset) · obs_scale``) and an
output transform applied last:

* ``clip``: the action is the network's output clipped to ``[action_low, action_high]`` (a
  Gaussian policy's mean, as Stable-Baselines3's PPO acts deterministically);
* ``tanh``: the action is ``low + (tanh(y) + 1)/2 · (high − low)`` (a squashed Gaussian's mean, as
  SAC acts deterministically).

The forward pass is a compiled function of two packed arrays (:meth:`MLPPolicy.packed`):
``theta`` (float64: obs_offset, obs_scale, action_low, action_high, then W₀, b₀, W₁, b₁, …, each
weight matrix row-major) and ``layout`` (int64, one row per layer after a header row
``(n_obs, n_act, output, max_width)``: ``(n_in, n_out, activation, offset into theta)``). Sums run
in a fixed order (plain loops, no BLAS), so a policy gives the same numbers in every process.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numba import njit

ACTIVATIONS = {"identity": 0, "tanh": 1, "relu": 2}
OUTPUTS = {"clip": 0, "tanh": 1}
_IDENTITY, _TANH, _RELU = 0, 1, 2
_OUT_CLIP, _OUT_TANH = 0, 1


@njit(cache=True)
def forward(theta, layout, obs, h0, h1, out):
    """The policy's action for ``obs`` into ``out``; ``h0``, ``h1`` are scratch of ``layout[0, 3]`` floats."""
    n_obs, n_act, output = layout[0, 0], layout[0, 1], layout[0, 2]
    for i in range(n_obs):
        h0[i] = (obs[i] - theta[i]) * theta[n_obs + i]
    src, dst = h0, h1
    for k in range(1, layout.shape[0]):
        n_in, n_out, act, off = layout[k, 0], layout[k, 1], layout[k, 2], layout[k, 3]
        b = off + n_in * n_out
        for j in range(n_out):
            acc = theta[b + j]
            row = off + j * n_in
            for i in range(n_in):
                acc += theta[row + i] * src[i]
            if act == _TANH:
                acc = math.tanh(acc)
            elif act == _RELU:
                acc = max(acc, 0.0)
            dst[j] = acc
        src, dst = dst, src
    lo = 2 * n_obs
    for j in range(n_act):
        low, high = theta[lo + j], theta[lo + n_act + j]
        y = src[j]
        if output == _OUT_TANH:
            out[j] = low + (math.tanh(y) + 1.0) * 0.5 * (high - low)
        else:
            out[j] = min(max(y, low), high)


@njit(cache=True)
def action1(theta, layout, obs, h0, h1, out):
    """The first (for this environment: the only) action component for ``obs``."""
    forward(theta, layout, obs, h0, h1, out)
    return out[0]


class MLPPolicy:
    """A feed-forward policy network (module docstring) with the agent interface of the learners.

    Args:
        weights: weight matrices, layer by layer, each (out, in).
        biases: bias vectors, each (out,).
        activations: per layer, one of :data:`ACTIVATIONS` (the last is usually ``identity``).
        output: ``clip`` or ``tanh`` (module docstring).
        obs_offset, obs_scale: observation scaling (default: none).
        action_low, action_high: action bounds (default ±1).
        trained_by: label of the learner that produced it (``ppo``, ``sac``).
        n_obs, n_act: the sizes the network must take and give; shapes that do not chain or fit
            raise ``ValueError``.
    """

    algorithm = "mlp"

    def __init__(
        self,
        weights: Sequence[np.ndarray],
        biases: Sequence[np.ndarray],
        activations: Sequence[str],
        *,
        output: str = "clip",
        obs_offset: np.ndarray | None = None,
        obs_scale: np.ndarray | None = None,
        action_low: np.ndarray | float = -1.0,
        action_high: np.ndarray | float = 1.0,
        trained_by: str = "",
        n_obs: int = 4,
        n_act: int = 1,
    ) -> None:
        if not (len(weights) == len(biases) == len(activations) >= 1):
            raise ValueError(
                f"{len(weights)} weight matrices, {len(biases)} bias vectors and "
                f"{len(activations)} activations: need one of each per layer"
            )
        self.weights = [np.ascontiguousarray(w, dtype=np.float64) for w in weights]
        self.biases = [np.ascontiguousarray(b, dtype=np.float64).reshape(-1) for b in biases]
        width = n_obs
        for k, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            if w.ndim != 2 or w.shape[1] != width or b.shape != (w.shape[0],):
                what = "the observation" if k == 0 else f"layer {k - 1}"
                raise ValueError(
                    f"layer {k} has weights {w.shape} and bias {b.shape}; {what} gives {width} values"
                )
            width = w.shape[0]
        if width != n_act:
            raise ValueError(f"the network gives {width} outputs, the action space has {n_act}")
        unknown = [a for a in activations if a not in ACTIVATIONS]
        if unknown or output not in OUTPUTS:
            raise ValueError(
                f"unknown activation or output {unknown or output!r} "
                f"(activations: {', '.join(ACTIVATIONS)}; outputs: {', '.join(OUTPUTS)})"
            )
        self.activations = list(activations)
        self.output = output
        self.obs_offset = _vector(0.0 if obs_offset is None else obs_offset, n_obs)
        self.obs_scale = _vector(1.0 if obs_scale is None else obs_scale, n_obs)
        self.action_low = _vector(action_low, n_act)
        self.action_high = _vector(action_high, n_act)
        arrays = [self.obs_offset, self.obs_scale, self.action_low, self.action_high]
        for a in (*self.weights, *self.biases, *arrays):
            if not np.all(np.isfinite(a)):
                raise ValueError("weights, biases or scalings contain NaN or infinite values")
        if np.any(self.action_low > self.action_high):
            raise ValueError("action_low exceeds action_high")
        self.trained_by = trained_by
        self.readings = "default"
        self.n_obs, self.n_act = n_obs, n_act
        self.theta, self.layout = self._pack()
        max_width = int(self.layout[0, 3])
        self._h0, self._h1 = np.empty(max_width), np.empty(max_width)
        self._out = np.empty(n_act)

    def _pack(self) -> tuple[np.ndarray, np.ndarray]:
        parts = [self.obs_offset, self.obs_scale, self.action_low, self.action_high]
        offset = sum(p.size for p in parts)
        width = max(self.n_obs, *self.hidden_sizes, self.n_act)
        rows = [(self.n_obs, self.n_act, OUTPUTS[self.output], width)]
        for w, b, act in zip(self.weights, self.biases, self.activations, strict=True):
            rows.append((w.shape[1], w.shape[0], ACTIVATIONS[act], offset))
            parts += [w.ravel(), b]
            offset += w.size + b.size
        return np.concatenate(parts), np.array(rows, dtype=np.int64)

    @property
    def hidden_sizes(self) -> list[int]:
        """Widths of the hidden layers."""
        return [w.shape[0] for w in self.weights[:-1]]

    @property
    def name(self) -> str:
        """Short label, e.g. ``PPO, MLP 64×64``."""
        net = "MLP " + "×".join(str(h) for h in self.hidden_sizes) if self.hidden_sizes else "linear"
        return f"{self.trained_by.upper()}, {net}" if self.trained_by else net

    def begin_episode(self, sigma: float) -> None:
        """Nothing to prepare: the exported policy acts deterministically."""

    def act(self, obs, explore: bool = False) -> float:
        """The action for ``obs`` (deterministic; ``explore`` is ignored)."""
        obs = np.asarray(obs, dtype=np.float64)
        return float(action1(self.theta, self.layout, obs, self._h0, self._h1, self._out))

    def predict(self, observations: np.ndarray) -> np.ndarray:
        """Actions (n, n_act) for observations (n, n_obs), in numpy (float64)."""
        h = (np.asarray(observations, dtype=np.float64) - self.obs_offset) * self.obs_scale
        for w, b, act in zip(self.weights, self.biases, self.activations, strict=True):
            h = h @ w.T + b
            if act == "tanh":
                h = np.tanh(h)
            elif act == "relu":
                h = np.maximum(h, 0.0)
        if self.output == "tanh":
            return self.action_low + (np.tanh(h) + 1.0) * 0.5 * (self.action_high - self.action_low)
        return np.clip(h, self.action_low, self.action_high)

    def update(self, *args, **kwargs) -> None:
        """An exported policy does not learn."""
        raise TypeError("an exported MLP policy cannot be trained further by pipefollow")


def _vector(value, n: int) -> np.ndarray:
    v = np.asarray(value, dtype=np.float64).reshape(-1)
    if v.size == 1:
        v = np.full(n, float(v[0]))
    if v.shape != (n,):
        raise ValueError(f"a scaling vector has {v.size} entries, expected {n}")
    return np.ascontiguousarray(v)
