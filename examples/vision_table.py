"""What imperfect detection does to the controllers: the held-out suite with the vision camera.

    python examples/vision_table.py --policies runs/vision --csv docs/vision/closed_loop.csv

Every controller runs one deterministic 60-s episode per held-out pipe with the vision camera in
clear, moderate and turbid water (`pipefollow.evaluation.vision.closed_loop`), and is compared
with the heuristic on the ideal camera on the same pipes (paired differences, bootstrap CIs).
The row "ideal" is each controller on the ideal camera. With ``--policies FOLDER`` it also trains,
if missing, CACLA and supervised CACLA on random pipes (the README's recipe: 5,000 episodes of 90 s
on random:mixed) without camera faults, and CACLA under the camera model calibrated for ``--calibrated`` water
(``docs/vision/calibration.json``), and PPO (the README's recipe: 100,000 steps on random:mixed,
the extra ``deep``), and judges them.
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
from pathlib import Path

from pipefollow.evaluation.benchmark import benchmark, load_controller
from pipefollow.evaluation.vision import closed_loop
from pipefollow.perception.water import WATER_PRESETS
from pipefollow.sim.suites import get_suite

COLUMNS = (
    "water", "controller", "mean_return", "ci95_low", "ci95_high", "success_rate", "pipe_in_view",
    "mean_diff", "ci95_diff_low", "ci95_diff_high",
)  # fmt: skip


def trained(folder: Path, seed: int, *options: str) -> str:
    """The policy file in ``folder``, trained if missing (``pipefollow train``, 90 s on random:mixed)."""
    policy = folder / "policy.npz"
    if not policy.exists():
        cmd = [
            sys.executable, "-m", "pipefollow.cli", "train", "--pipeline", "random:mixed", "--seconds", "90",
            "--seed", str(seed), "--out", str(folder), *options,
        ]  # fmt: skip
        subprocess.run(cmd, check=True)
    return str(policy)


def train(folder: Path, seed: int, noise: float, miss: float, supervised: bool = False) -> str:
    """CACLA's policy file in ``folder`` (the README's recipe: 5,000 episodes), trained if missing."""
    faults = ["--camera-noise", str(noise), "--miss-prob", str(miss)]
    options = [*faults, "--supervised"] if supervised else faults
    return trained(folder, seed, "--algorithm", "cacla", "--episodes", "5000", *options)


def train_ppo(folder: Path, seed: int) -> str:
    """PPO's policy file in ``folder`` (the README's recipe: 100,000 steps), trained if missing."""
    return trained(folder, seed, "--algorithm", "ppo", "--steps", "100000")


def main() -> None:
    """Print the table's rows and write the CSV."""
    parser = argparse.ArgumentParser()
    parser.add_argument("--csv", default=None)
    parser.add_argument("--pipes", type=int, default=100)
    parser.add_argument("--policies", default=None, help="Folder of the CACLA policies (trained if missing).")
    parser.add_argument("--calibrated", default="moderate", help="Water of the calibrated camera model.")
    parser.add_argument("--seed", type=int, default=2010)
    parser.add_argument("--ppo-seed", type=int, default=0, help="Seed of the PPO policy (deep extra).")
    args = parser.parse_args()
    controllers = [("heuristic", "heuristic"), ("LOS (Δ = 1.5 m)", "los")]
    if args.policies:
        table = json.loads(Path("docs/vision/calibration.json").read_text())
        cal = {round(r["turbidity"], 6): r for r in table}
        c = cal[round(WATER_PRESETS[args.calibrated].turbidity, 6)]
        base = Path(args.policies)
        controllers.append(("CACLA, random pipes", train(base / "plain", args.seed, 0.0, 0.0)))
        supervised = train(base / "supervised", args.seed, 0.0, 0.0, supervised=True)
        controllers.append(("supervised CACLA, random pipes", supervised))
        label = f"CACLA, random pipes, calibrated ({args.calibrated})"
        controllers.append((label, train(base / "calibrated", args.seed, c["camera_noise"], c["miss_prob"])))
        controllers.append(("PPO, random pipes", train_ppo(base / "ppo", args.ppo_seed)))
    suite = get_suite("heldout")
    rows = []
    for label, spec in controllers:
        for water in ("ideal", "clear", "moderate", "turbid"):
            agent = load_controller(spec)
            if water == "ideal":
                s = benchmark(agent, suite, controller=label, n_pipes=args.pipes).summary
            else:
                s = closed_loop(agent, suite, WATER_PRESETS[water], label, n_pipes=args.pipes).summary
            d = s.get("vs_heuristic") or {"mean_diff": 0.0, "ci95_diff": [0.0, 0.0]}
            row = {
                "water": water, "controller": label, "mean_return": s["mean_return"],
                "ci95_low": s["ci95_mean"][0], "ci95_high": s["ci95_mean"][1],
                "success_rate": s["success_rate"], "pipe_in_view": s["mean_pipe_in_view"],
                "mean_diff": d["mean_diff"],
                "ci95_diff_low": d["ci95_diff"][0], "ci95_diff_high": d["ci95_diff"][1],
            }  # fmt: skip
            rows.append(row)
            print(
                f"| {water} | {label} | {row['mean_return']:.1f} "
                f"[{row['ci95_low']:.1f}, {row['ci95_high']:.1f}] "
                f"| {row['success_rate']:.0%} | {row['pipe_in_view']:.1%} | {row['mean_diff']:+.1f} "
                f"[{row['ci95_diff_low']:+.1f}, {row['ci95_diff_high']:+.1f}] |",
                flush=True,
            )
    if args.csv:
        with open(args.csv, "w", newline="", encoding="utf-8") as f:
            w = csv.DictWriter(f, COLUMNS, lineterminator="\n")
            w.writeheader()
            for r in rows:
                w.writerow({k: round(v, 4) if isinstance(v, float) else v for k, v in r.items()})


if __name__ == "__main__":
    main()
