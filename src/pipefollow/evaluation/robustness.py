"""Robustness to currents and an imperfect camera: fixed scenario sets and curves against current speed.

A *scenario* is one held-out pipe under one :class:`~pipefollow.sim.disturbance.Disturbance`, with
the seed of its random disturbances. Every scenario is a pure function of the set's name and the
pipe's index: pipe ``k`` of set ``S`` draws its disturbance with :func:`pipefollow.sim.randomization.draw`
from ``numpy.random.default_rng(SeedSequence([SCENARIO_ROOT, id(S), k]))``, and then the seed of its
camera noise from the same generator. So the sets are fixed, every controller meets the same
scenarios (common random numbers), and changing one set does not move another.

Scenario sets (:data:`SCENARIO_SETS`):

==========  ==========================================================================================
``calm``    no disturbance (the suite as ``benchmark`` runs it)
``current`` a constant current of 0.05 – 0.25 m/s towards any direction
``noise``   camera noise of s.d. 0.02 – 0.1 m on the detected end points
``misses``  missed detections, 2 – 10 % of the camera readings
``buried``  two cells of 5 – 25 m and 25 – 45 m, each with a buried stretch of 0.5 – 2 m
``sea``     all at once: a wandering current of 0.05 – 0.25 m/s, noise 0 – 0.05 m, misses 0 – 5 %,
            and a buried stretch in a cell with probability 0.5
==========  ==========================================================================================

The *robustness curve* holds the pipes and the current's direction fixed and raises its speed:
pipe ``k`` gets the direction drawn from ``SeedSequence([SCENARIO_ROOT, 0, k])``, uniform on
[0°, 360°) (the held-out pipes start heading north, so the direction is relative to the first leg),
at every speed of the curve.

Each controller is a label with one or more policies (training seeds): per scenario its return is
the mean over its policies, the confidence interval a bootstrap over the pipes of those means
(:mod:`pipefollow.evaluation.stats`), and its success rate the share of (policy, pipe) episodes with
the pipe in view at ≥ 95 % of the decisions and followed forward (:mod:`pipefollow.evaluation.success`),
beside the share with the pipe in view alone (``in_view_rate``), the mean progress share and the
count of episodes that turned back. The heuristic is always run, for the paired difference.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from pipefollow.evaluation import success as sc
from pipefollow.evaluation.benchmark import heuristic_camera, run_episodes
from pipefollow.evaluation.stats import bootstrap_ci, iqm, paired_difference
from pipefollow.files.paper_training import TEST_EPISODE_SECONDS
from pipefollow.learners.heuristic import Heuristic
from pipefollow.sim import decision as sim
from pipefollow.sim import randomization as rz
from pipefollow.sim.disturbance import NO_DISTURBANCE, Disturbance, DisturbanceError
from pipefollow.sim.episode import STAT_IN_VIEW, STAT_NAMES, STAT_RETURN
from pipefollow.sim.pipeline import Pipeline
from pipefollow.sim.suites import Suite, min_length_for

SCENARIO_ROOT = 2010_0017  # first entropy word of every scenario seed
SPEEDS = (0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3)  # m/s, the curve's default
MAX_SPEED = 2.0  # m/s; four times the AUV's cruise speed, a sanity bound on the curve's speeds
HEURISTIC_LABEL = "heuristic"


@dataclass(frozen=True)
class ScenarioSet:
    """A named distribution of disturbances, drawn once per pipe from fixed seeds."""

    name: str
    id: int  # entropy word of its seeds
    randomization: rz.Randomization
    description: str


SCENARIO_SETS = {
    s.name: s
    for s in (
        ScenarioSet("calm", 1, rz.NONE, "no disturbance"),
        ScenarioSet(
            "current", 2, rz.Randomization(current_speed=(0.05, 0.25)), "current 0.05–0.25 m/s, any direction"
        ),
        ScenarioSet("noise", 3, rz.Randomization(camera_noise=(0.02, 0.1)), "camera noise s.d. 0.02–0.1 m"),
        ScenarioSet("misses", 4, rz.Randomization(miss_prob=(0.02, 0.1)), "missed detections 2–10 %"),
        ScenarioSet(
            "buried",
            5,
            rz.Randomization(
                buried_prob=1.0, buried_count=2, buried_length_m=(0.5, 2.0), buried_region_m=(5.0, 45.0)
            ),
            "two buried stretches of 0.5–2 m",
        ),
        ScenarioSet(
            "sea",
            6,
            rz.Randomization(
                current_speed=(0.05, 0.25),
                current_time_constant=30.0,
                current_speed_sd=0.02,
                current_direction_sd_deg=10.0,
                camera_noise=(0.0, 0.05),
                miss_prob=(0.0, 0.05),
                buried_prob=0.5,
                buried_count=2,
                buried_length_m=(0.5, 2.0),
                buried_region_m=(5.0, 45.0),
            ),
            "all at once: wandering current 0.05–0.25 m/s, noise, misses, burial",
        ),
    )
}


@dataclass(frozen=True)
class Scenario:
    """One pipe under one disturbance, with the seed of its random disturbances."""

    pipe: Pipeline
    disturbance: Disturbance
    noise_seed: int


def get_scenario_set(name: str) -> ScenarioSet:
    """The set called ``name``; raises :class:`DisturbanceError` listing the sets otherwise."""
    try:
        return SCENARIO_SETS[name]
    except (KeyError, TypeError):
        raise DisturbanceError(
            f"scenario set '{name}': unknown (choose from {', '.join(SCENARIO_SETS)})"
        ) from None


def _rng(set_id: int, k: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence([SCENARIO_ROOT, set_id, k]))


def _pipes(suite: Suite, n: int | None, seconds: float) -> list[Pipeline]:
    n = n if n is not None else (suite.count or 100)
    return suite.pipes(n, min_length_for(seconds))


def scenarios(
    name: str, suite: Suite, n: int | None = None, seconds: float = TEST_EPISODE_SECONDS
) -> list[Scenario]:
    """The scenarios of set ``name`` on the first ``n`` pipes of ``suite`` (all of a held-out suite)."""
    s = get_scenario_set(name)
    out = []
    for k, pipe in enumerate(_pipes(suite, n, seconds)):
        rng = _rng(s.id, k)
        out.append(Scenario(pipe, rz.draw(s.randomization, rng), int(rng.integers(2**63))))
    return out


def curve_directions(n: int) -> np.ndarray:
    """The current's direction (degrees towards) on pipe ``k`` of the curve, for ``k < n``."""
    return np.array([_rng(0, k).random() * 360.0 for k in range(n)])


def curve_scenarios(
    speed: float, suite: Suite, n: int | None = None, seconds: float = TEST_EPISODE_SECONDS
) -> list[Scenario]:
    """The curve's scenarios at ``speed`` (m/s): a constant current, pipe ``k`` towards its direction."""
    if not (isinstance(speed, int | float) and math.isfinite(speed) and 0.0 <= speed <= MAX_SPEED):
        raise DisturbanceError(f"current speed must be a number from 0 to {MAX_SPEED:g} m/s, got {speed!r}")
    pipes = _pipes(suite, n, seconds)
    directions = curve_directions(len(pipes))

    def current(b: float) -> Disturbance:
        return (
            Disturbance(current_speed=float(speed), current_direction=math.radians(b))
            if speed
            else NO_DISTURBANCE
        )

    return [Scenario(pipe, current(b), k) for k, (pipe, b) in enumerate(zip(pipes, directions, strict=True))]


# ---------------------------------------------------------------------------------------------
# Running


def run_scenarios(
    agent, cases: Sequence[Scenario], seconds: float, params: sim.SimParams = sim.PAPER_SIM,
    camera: dict | None = None,
):  # fmt: skip
    """One deterministic episode of ``agent`` per scenario: rows of :func:`benchmark.run_episodes`.

    ``camera``: the environment's camera arguments (:func:`benchmark.run_episodes`); None for the
    ideal camera.
    """
    out = np.empty((len(cases), len(STAT_NAMES)))
    for i, c in enumerate(cases):
        p = params._replace(disturbance=c.disturbance)
        out[i] = run_episodes(agent, [c.pipe], seconds, p, c.noise_seed, camera)[0][0]
    return out


def params_for(agent) -> sim.SimParams:
    """The simulation under the readings ``agent`` was trained with (the project's for built-ins)."""
    from pipefollow.readings import parse, sim_params

    return sim_params(parse(getattr(agent, "readings", "default"), source="policy readings"))


def summarize(label: str, results: Sequence[np.ndarray], heuristic: np.ndarray | None, seed: int = 0,
              lengths=None) -> dict:  # fmt: skip
    """One row: ``results`` has a statistics array (pipes, columns) per policy of ``label``.

    ``heuristic``: the heuristic's array, the reference of the paired difference (None for itself).

    ``lengths``: the pipes' lengths (m), for the success (:mod:`pipefollow.evaluation.success`);
    None: pipes longer than any episode reaches.
    """
    stacked = np.stack(results)  # (policies, pipes, columns)
    lengths = np.full(stacked.shape[1], np.inf) if lengths is None else np.asarray(lengths, dtype=np.float64)
    judged = sc.summary(stacked.reshape(-1, stacked.shape[2]), np.tile(lengths, stacked.shape[0]))
    per_pipe = stacked[:, :, STAT_RETURN].mean(axis=0)
    lo, hi = bootstrap_ci(per_pipe, seed)
    row = {
        "controller": label,
        "policies": len(results),
        "episodes": int(stacked.shape[0] * stacked.shape[1]),
        "mean_return": float(per_pipe.mean()),
        "ci95_low": lo,
        "ci95_high": hi,
        "iqm_return": iqm(per_pipe),
        "success_rate": judged["success_rate"],
        "in_view_rate": judged["in_view_rate"],
        "mean_progress_share": judged["mean_progress_share"],
        "turned_back": judged["turned_back"],
        "mean_pipe_in_view": float(stacked[:, :, STAT_IN_VIEW].mean()),
        "seed_returns": [float(r[:, STAT_RETURN].mean()) for r in results],
    }
    if heuristic is not None:
        d = paired_difference(per_pipe, heuristic[:, STAT_RETURN], seed)
        row |= {"vs_heuristic": d["mean_diff"], "vs_heuristic_low": d["ci95_diff"][0],
                "vs_heuristic_high": d["ci95_diff"][1]}  # fmt: skip
    return row


def evaluate(
    controllers: Mapping[str, Sequence[object]],
    cases: Sequence[Scenario],
    seconds: float,
    seed: int = 0,
    progress=None,
    camera: dict | None = None,
) -> list[dict]:
    """Rows of :func:`summarize` for the heuristic and each labelled controller on ``cases``.

    ``camera``: what every controller observes through (:func:`benchmark.run_episodes`), the
    heuristic beside them too (:func:`benchmark.heuristic_camera`); None for the ideal camera.
    """
    h = run_scenarios(Heuristic(), cases, seconds, camera=heuristic_camera(camera))
    lengths = [c.pipe.length for c in cases]
    rows = [summarize(HEURISTIC_LABEL, [h], None, seed, lengths)]
    for label, agents in controllers.items():
        if label == HEURISTIC_LABEL:
            continue
        results = []
        for agent in agents:
            results.append(run_scenarios(agent, cases, seconds, params_for(agent), camera))
            if progress:
                progress()
        rows.append(summarize(label, results, h, seed, lengths))
    return rows


def robustness_curve(
    controllers: Mapping[str, Sequence[object]],
    suite: Suite,
    *,
    speeds: Sequence[float] = SPEEDS,
    n_pipes: int | None = None,
    seconds: float = TEST_EPISODE_SECONDS,
    seed: int = 0,
    progress=None,
    camera: dict | None = None,
) -> list[dict]:
    """Rows (label, speed): success rate, mean return with CI, vs the heuristic (module docstring).

    ``camera``: what the controllers observe through (:func:`evaluate`); None for the ideal camera.
    """
    cases = {v: curve_scenarios(v, suite, n_pipes, seconds) for v in speeds}  # checks every speed first
    rows = []
    for v, cs in cases.items():
        rows += [
            {"current_speed": float(v), **r}
            for r in evaluate(controllers, cs, seconds, seed, progress, camera)
        ]
    return rows


def scenario_table(
    controllers: Mapping[str, Sequence[object]],
    suite: Suite,
    *,
    sets: Sequence[str] = tuple(SCENARIO_SETS),
    n_pipes: int | None = None,
    seconds: float = TEST_EPISODE_SECONDS,
    seed: int = 0,
    progress=None,
    camera: dict | None = None,
) -> list[dict]:
    """Rows (label, scenario set) of :func:`evaluate` on each set's fixed scenarios (``camera``: as there)."""
    cases = {name: scenarios(name, suite, n_pipes, seconds) for name in sets}  # checks every name first
    rows = []
    for name, cs in cases.items():
        rows += [{"scenarios": name, **r} for r in evaluate(controllers, cs, seconds, seed, progress, camera)]
    return rows


# ---------------------------------------------------------------------------------------------
# Output: tables, figure

COLUMNS = (
    "controller",
    "policies",
    "episodes",
    "success_rate",
    "in_view_rate",
    "mean_progress_share",
    "turned_back",
    "mean_return",
    "ci95_low",
    "ci95_high",
    "iqm_return",
    "mean_pipe_in_view",
    "vs_heuristic",
    "vs_heuristic_low",
    "vs_heuristic_high",
)


def to_csv(rows: Sequence[dict], first: str) -> str:
    """``rows`` as CSV text, column ``first`` (``current_speed`` or ``scenarios``) then :data:`COLUMNS`."""
    import csv
    import io

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow((first, *COLUMNS))
    for r in rows:
        w.writerow([r[first], *(_cell(r.get(c)) for c in COLUMNS)])
    return buf.getvalue()


def _cell(v):
    return "" if v is None else (f"{v:.6g}" if isinstance(v, float) else v)


def markdown(rows: Sequence[dict], first: str, header: str) -> str:
    """A Markdown table: one row per ``first`` value, one column per controller (mean return, success).

    A cell names the episodes that turned back, where any did.
    """
    labels = list(dict.fromkeys(r["controller"] for r in rows))
    keys = list(dict.fromkeys(r[first] for r in rows))
    cell = {(r[first], r["controller"]): r for r in rows}
    lines = [f"| {header} | " + " | ".join(labels) + " |", "|---" * (len(labels) + 1) + "|"]
    for k in keys:
        cells = []
        for lab in labels:
            r = cell[(k, lab)]
            back = r.get("turned_back", 0)
            cells.append(
                f"{r['mean_return']:.1f} [{r['ci95_low']:.1f}, {r['ci95_high']:.1f}], {r['success_rate']:.0%}"
                + (f", {back} turned back" if back else "")
            )
        lines.append(f"| {k:g} | " if isinstance(k, float) else f"| {k} | ")
        lines[-1] += " | ".join(cells) + " |"
    return "\n".join(lines)


def plot_curve(rows: Sequence[dict], path, title: str = "") -> None:
    """Success rate and mean return (95 % CI band) against current speed, one line per controller."""
    from pipefollow.envs.render import new_figure, save_figure

    fig = new_figure((11.0, 4.2))
    ax_s, ax_r = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    for label in dict.fromkeys(r["controller"] for r in rows):
        rs = sorted((r for r in rows if r["controller"] == label), key=lambda r: r["current_speed"])
        v = [r["current_speed"] for r in rs]
        n = rs[0]["policies"]
        name = label if n == 1 else f"{label} ({n} seeds)"
        (line,) = ax_s.plot(v, [100.0 * r["success_rate"] for r in rs], marker="o", ms=3, label=name)
        ax_r.plot(v, [r["mean_return"] for r in rs], marker="o", ms=3, color=line.get_color(), label=name)
        ax_r.fill_between(v, [r["ci95_low"] for r in rs], [r["ci95_high"] for r in rs],
                          color=line.get_color(), alpha=0.18, lw=0)  # fmt: skip
    ax_s.set_ylabel("success rate (%): pipe in view ≥ 95 %, followed forward")
    ax_r.set_ylabel("mean return per 60-s episode (95 % CI)")
    for ax in (ax_s, ax_r):
        ax.set_xlabel("current speed (m/s); the AUV cruises at 0.48 m/s")
        ax.grid(alpha=0.3)
    ax_s.set_ylim(-3, 103)
    ax_s.legend(fontsize=8, loc="lower left")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    save_figure(fig, path)
