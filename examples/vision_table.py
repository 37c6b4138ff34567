"""What imperfect detection does to the controllers: held-out suites through the rendered camera.

    python examples/vision_table.py --policies runs/vision-policies --csv docs/vision/closed_loop.csv
    python examples/vision_table.py --policies runs/vision-policies --suites \
        --csv docs/vision/closed_loop_suites.csv

Every controller runs one deterministic 60-s episode per held-out pipe through the rendered camera
in clear, moderate and turbid water (`pipefollow.evaluation.vision.closed_loop`), once with the
detector alone (``camera="vision-raw"``) and once with the detector and the pipe tracker
(``camera="vision"``), and is compared with the heuristic on the ideal camera on the same pipes
(paired differences, bootstrap CIs). The row "ideal" is each controller on the ideal camera.
``--suites`` makes the second table instead: the heuristic, PPO and supervised CACLA on
``heldout-easy``, ``-medium``, ``-hard`` and ``heldout-sharp`` (100 pipes each) in clear water,
ideal camera against both rendered ones. Success is today's (``pipefollow.evaluation.success``: the
pipe in view at >= 95 % of the decisions and followed forward). With ``--policies FOLDER`` it also trains,
if missing, CACLA and supervised CACLA on random pipes (the README's recipe: 5,000 episodes of 90 s
on random:mixed) without camera faults, and CACLA under the camera model calibrated for ``--calibrated`` water
(``docs/vision/calibration.json``), and PPO (the README's recipe: 100,000 steps on random:mixed,
the extra ``deep``), and judges them.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import subprocess
import sys
from pathlib import Path

from pipefollow.evaluation.benchmark import benchmark, load_controller
from pipefollow.evaluation.vision import closed_loop
from pipefollow.files.atomic import write_text_atomic
from pipefollow.files.machine import script_command, write_output_provenance
from pipefollow.perception.water import WATER_PRESETS
from pipefollow.sim.suites import get_suite

COLUMNS = (
    "water", "camera", "controller", "mean_return", "ci95_low", "ci95_high", "success_rate", "pipe_in_view",
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


def train_ppo(folder: Path, seed: int, *options: str) -> str:
    """PPO's policy file in ``folder`` (the README's recipe: 100,000 steps), trained if missing.

    ``options``: more ``pipefollow train`` options, e.g. the sensor and water to train through.
    """
    return trained(folder, seed, "--algorithm", "ppo", "--steps", "100000", *options)


CAMERAS = ("vision-raw", "vision")  # the detector alone; the detector and the tracker
SUITES = ("heldout-easy", "heldout-medium", "heldout-hard", "heldout-sharp")
SUITE_COLUMNS = (
    "suite", "controller", "camera", "water", "mean_return", "ci95_low", "ci95_high", "success_rate",
    "pipe_in_view", "vs_heuristic_ideal", "ci95_diff_low", "ci95_diff_high",
)  # fmt: skip


def run(agent, suite, label: str, camera: str, water: str, n_pipes: int) -> dict:
    """The benchmark summary of one controller on one camera (``ideal``: the exact visible piece)."""
    if camera == "ideal":
        return benchmark(agent, suite, controller=label, n_pipes=n_pipes).summary
    return closed_loop(agent, suite, WATER_PRESETS[water], label, n_pipes=n_pipes, camera=camera).summary


def row_of(s: dict, is_reference: bool) -> dict:
    """The summary's numbers as the CSV keeps them (the reference row has no difference to itself)."""
    # the heuristic on the ideal camera: the second reference of a rendered camera, the only one of the ideal
    d = s.get("vs_heuristic_ideal") or s.get("vs_heuristic") or {"mean_diff": 0.0, "ci95_diff": [0.0, 0.0]}
    return {
        "mean_return": s["mean_return"], "ci95_low": s["ci95_mean"][0], "ci95_high": s["ci95_mean"][1],
        "success_rate": s["success_rate"], "pipe_in_view": s["mean_pipe_in_view"],
        "mean_diff": None if is_reference else d["mean_diff"],
        "ci95_diff_low": None if is_reference else d["ci95_diff"][0],
        "ci95_diff_high": None if is_reference else d["ci95_diff"][1],
    }  # fmt: skip


def fmt(v):
    """Four decimals in the CSV; an empty cell for no value."""
    if v is None:
        return ""
    return round(v, 4) if isinstance(v, float) else v


def write(path: str, columns, rows) -> None:
    """The rows as CSV, written atomically."""
    lines = io.StringIO()
    w = csv.DictWriter(lines, columns, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: fmt(r[k]) for k in columns})
    write_text_atomic(path, lines.getvalue())
    write_output_provenance(path, script_command())  # X.provenance.json: command, date, code, machine


def main() -> None:
    """Print the table's rows and write the CSV."""
    parser = argparse.ArgumentParser()
    parser.add_argument("--csv", default=None)
    parser.add_argument("--pipes", type=int, default=100)
    parser.add_argument("--policies", default=None, help="Folder of the CACLA policies (trained if missing).")
    parser.add_argument("--calibrated", default="moderate", help="Water of the calibrated camera model.")
    parser.add_argument("--seed", type=int, default=2010)
    parser.add_argument("--ppo-seed", type=int, default=0, help="Seed of the PPO policy (deep extra).")
    parser.add_argument("--suites", action="store_true", help="The heldout-easy/-medium/-hard/-sharp table.")
    args = parser.parse_args()
    if args.suites and not args.policies:
        parser.error("--suites needs --policies (PPO and supervised CACLA are in the table)")
    controllers = [("heuristic", "heuristic")]
    if not args.suites:
        controllers.append(("LOS (Δ = 1.5 m)", "los"))
    if args.policies:
        base = Path(args.policies)
        supervised = train(base / "supervised", args.seed, 0.0, 0.0, supervised=True)
        ppo = ("PPO, random pipes", train_ppo(base / "ppo", args.ppo_seed))
        if args.suites:
            controllers += [ppo, ("supervised CACLA, random pipes", supervised)]
        else:
            table = json.loads(Path("docs/vision/calibration.json").read_text())
            cal = {round(r["turbidity"], 6): r for r in table}
            c = cal[round(WATER_PRESETS[args.calibrated].turbidity, 6)]
            controllers.append(("CACLA, random pipes", train(base / "plain", args.seed, 0.0, 0.0)))
            controllers.append(("supervised CACLA, random pipes", supervised))
            label = f"CACLA, random pipes, calibrated ({args.calibrated})"
            calibrated = train(base / "calibrated", args.seed, c["camera_noise"], c["miss_prob"])
            controllers.append((label, calibrated))
            controllers.append(ppo)
    if args.suites:
        suites_table(controllers, args)
        return
    suite = get_suite("heldout")
    conditions = [("ideal", "ideal")] + [(c, w) for w in ("clear", "moderate", "turbid") for c in CAMERAS]
    rows = []
    for label, spec in controllers:
        for camera, water in conditions:
            s = run(load_controller(spec), suite, label, camera, water, args.pipes)
            row = {"water": water, "camera": camera, "controller": label}
            row.update(row_of(s, (label, camera) == ("heuristic", "ideal")))
            rows.append(row)
            d = row["mean_diff"] or 0.0
            print(
                f"| {water} | {camera} | {label} | {row['mean_return']:.1f} "
                f"[{row['ci95_low']:.1f}, {row['ci95_high']:.1f}] "
                f"| {row['success_rate']:.0%} | {row['pipe_in_view']:.1%} | {d:+.1f} |",
                flush=True,
            )
    if args.csv:
        write(args.csv, COLUMNS, rows)


def suites_table(controllers, args) -> None:
    """The table of :data:`SUITES` in clear water: each controller on the ideal and both rendered cameras."""
    rows = []
    for name in SUITES:
        suite = get_suite(name)
        for label, spec in controllers:
            for camera in ("ideal", *CAMERAS):
                s = run(load_controller(spec), suite, label, camera, "clear", args.pipes)
                r = row_of(s, (label, camera) == ("heuristic", "ideal"))
                row = {
                    "suite": name, "controller": label, "camera": camera,
                    "water": "" if camera == "ideal" else "clear", **r,
                    "vs_heuristic_ideal": r["mean_diff"],
                }  # fmt: skip
                rows.append(row)
                d = r["mean_diff"] or 0.0
                mean, success = r["mean_return"], r["success_rate"]
                print(f"| {name} | {label} | {camera} | {mean:.1f} | {success:.0%} | {d:+.1f} |", flush=True)
    if args.csv:
        write(args.csv, SUITE_COLUMNS, rows)


if __name__ == "__main__":
    main()
