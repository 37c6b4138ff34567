"""The robustness results (docs/robustness/): every policy trained by the command line, then judged.

Policies, each trained on a new `random:mixed` pipe every 90-s episode in calm water, seeds 0-2:
CACLA, supervised CACLA and SARSA with `pipefollow train --episodes 5000` (450,000 decisions), PPO
with `--algorithm ppo --steps 100000`; and the recipe of 30,000 decisions, seeds 0-4, from its
experiment file (`pipefollow reproduce --experiment examples/recipe-30k.toml`). Then
`pipefollow robustness` on `heldout` (60 s) beside the heuristic and LOS:

    python examples/robustness_table.py --out runs/robustness     # trains what is missing, then judges
    cp runs/robustness/judged/* docs/robustness/ && pipefollow docs results

Every command it runs is printed first; a policy already in OUT/policies is not trained again.
"""

from __future__ import annotations

import argparse
import shlex
import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parent
TRAIN = ["--pipeline", "random:mixed", "--seconds", "90"]
LEARNERS = {  # label → the train options
    "cacla": ["--algorithm", "cacla", "--episodes", "5000"],
    "supervised-cacla": ["--algorithm", "cacla", "--supervised", "--episodes", "5000"],
    "sarsa": ["--algorithm", "sarsa", "--episodes", "5000"],
    "ppo": ["--algorithm", "ppo", "--steps", "100000"],
}
SEEDS = (0, 1, 2)
RECIPE, RECIPE_LABEL = EXAMPLES / "recipe-30k.toml", "recipe-30k"


def run(cmd: list[str]) -> None:
    """Print ``cmd`` as a shell line, then run it (an error stops the script)."""
    print("$", shlex.join(cmd), flush=True)
    subprocess.run(cmd, check=True)


def main() -> None:
    """Command line: see the module docstring."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    pipefollow = [sys.executable, "-m", "pipefollow"]
    controllers = ["--controller", "heuristic", "--controller", "los"]
    for label, options in LEARNERS.items():
        for seed in SEEDS:
            folder = args.out / "policies" / f"{label}-{seed}"
            if not (folder / "policy.npz").exists():
                seeded = [*options, *TRAIN, "--seed", str(seed)]
                run([*pipefollow, "train", *seeded, "--out", str(folder), "--force"])
            controllers += ["--controller", f"{label}={folder / 'policy.npz'}"]
    recipe = args.out / "policies" / RECIPE_LABEL
    run([*pipefollow, "reproduce", "--experiment", str(RECIPE), "--out", str(recipe), "--no-figures"])
    for policy in sorted((recipe / "policies").glob("*.npz")):
        controllers += ["--controller", f"{RECIPE_LABEL}={policy}"]
    run([*pipefollow, "robustness", *controllers, "--out", str(args.out / "judged")])


if __name__ == "__main__":
    main()
