"""The vehicle's navigation between camera frames: a DVL's velocity and a gyro's heading, with their errors.

The pipe tracker (:mod:`pipefollow.perception.tracker`) moves its line by what the navigation
reports, not by the simulator's truth (docs/decisions.md "pipe tracker" cites the datasheet figures).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np


class NavParams(NamedTuple):
    """The navigation's sensors (docs/decisions.md "pipe tracker" cites the datasheet figures).

    A DVL measures the velocity over the seabed in the body frame; a gyro (or AHRS) the heading's
    change. Between two frames their integration gives the vehicle's motion with these errors.
    """

    dvl_sd: float = 0.01  # one ping's velocity noise per axis (m/s)
    dvl_rate: float = 5.0  # pings per second
    dvl_scale_sd: float = 0.002  # scale-factor error (share of the velocity), drawn once per episode
    gyro_arw: float = 0.05  # angle random walk (deg/√s; 3 °/√h)
    gyro_bias_sd: float = 10.0 / 3600.0  # the gyro's bias at the start (deg/s; 10 °/h), per episode
    gyro_bias_walk: float = 1.0 / 3600.0  # the bias's random walk (deg/s per √s)


NAV = NavParams()

NORMALS_BLOCK = 256  # steps of navigation noise drawn at a time


class Navigation:
    """Dead reckoning between frames: a DVL's velocity and a gyro's heading, with their errors.

    :meth:`motion` turns the vehicle's true poses at two frames into what its navigation reports:
    the displacement in the earlier frame's axes (the DVL's velocity integrated, off by the
    episode's scale error and the pings' noise) and the heading's change (the gyro's, off by its
    drifting bias and its angle random walk). The errors draw from the generator given to
    :meth:`reset`. :attr:`variances` are the motion's error variances as the filter assumes them
    for a step of ``dt`` seconds (the bias's share: its 1σ over the step).
    """

    def __init__(self, params: NavParams = NAV, dt: float = 1.0) -> None:
        self.params, self.dt = params, dt
        p = params
        disp_sd = p.dvl_sd * math.sqrt(dt / p.dvl_rate)  # the mean of dt·rate pings, times dt
        turn_var = math.radians(p.gyro_arw) ** 2 * dt + (math.radians(p.gyro_bias_sd) * dt) ** 2
        self.disp_sd = disp_sd
        self.variances = np.array([disp_sd**2, disp_sd**2, turn_var])
        self.rng = np.random.default_rng(0)
        self.scale, self.bias = 1.0, 0.0
        self._z = np.empty((0, 4))  # the steps' normals, drawn from the generator a block at a time
        self._k = 0
        self._out = np.zeros(3)

    def reset(self, rng: np.random.Generator) -> None:
        """A new episode: the scale error and the gyro's bias drawn from ``rng``, which later steps use."""
        p = self.params
        self.rng = rng
        self.scale = 1.0 + p.dvl_scale_sd * float(rng.standard_normal())
        self.bias = math.radians(p.gyro_bias_sd) * float(rng.standard_normal())
        self._z, self._k = np.empty((0, 4)), 0

    def motion(self, before: tuple[float, float, float], after: tuple[float, float, float]) -> np.ndarray:
        """The navigation's ``(Δl, Δf, Δψ)`` between two true poses (x north, y east, ψ).

        Returns an array the next call overwrites. The step's four normals come from blocks of
        :data:`NORMALS_BLOCK` rows drawn from the generator (a draw per step cost more than the filter).
        """
        p, dt = self.params, self.dt
        x0, y0, psi0 = before
        dx, dy = after[0] - x0, after[1] - y0
        cs, sn = math.cos(psi0), math.sin(psi0)
        if self._k >= len(self._z):
            self._z, self._k = self.rng.standard_normal((NORMALS_BLOCK, 4)), 0
        z = self._z[self._k]
        self._k += 1
        d_f = self.scale * (cs * dx + sn * dy) + self.disp_sd * z[0]
        d_l = self.scale * (-sn * dx + cs * dy) + self.disp_sd * z[1]
        d_psi = math.remainder(after[2] - psi0, 2.0 * math.pi)
        d_psi += self.bias * dt + math.radians(p.gyro_arw) * math.sqrt(dt) * z[2]
        self.bias += math.radians(p.gyro_bias_walk) * math.sqrt(dt) * z[3]
        out = self._out
        out[0], out[1], out[2] = d_l, d_f, d_psi
        return out
