"""Wall time of ``pipefollow compare`` on 15 policies × 100 held-out pipes (target ≤ 5 s).

Usage: ``python benchmarks/compare.py [--repeats N] [--json FILE]`` (``--json``: the record of
``stored.py``, with the load and the machine; ``docs/speed/compare.json``)

Makes 15 policy files in a temporary folder (5 seeds each of CACLA, supervised CACLA and SARSA,
their weights drawn at random from the seed: the timing does not depend on what was learned),
then runs ``pipefollow compare`` on them as a fresh process, in turns with ``python -c "import
numpy"`` so that both share the machine's load; prints the medians, the CPU time of the command
and the machine's load average.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def make_policies(folder: Path) -> list[str]:
    from pipefollow.training.agents import make_agent
    from pipefollow.training.policy_files import save_policy

    paths = []
    for name, kw in (("cacla", {}), ("supervised", {"supervised": True}), ("sarsa", {})):
        for seed in range(5):
            agent = make_agent("sarsa" if name == "sarsa" else "cacla", rng=np.random.default_rng(seed), **kw)
            rng = np.random.default_rng(100 + seed)
            agent.weights[...] = rng.normal(0.0, 0.3, agent.weights.shape)
            paths.append(str(save_policy(agent, folder / f"{name}-{seed}.npz")))
    return paths


def wall(args: list[str]) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    subprocess.run([sys.executable, *args], check=True, stdout=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return time.perf_counter() - t, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--json", default=None, help="also write the figures, the load and the machine here")
    args = parser.parse_args()
    import stored

    load_before = stored.load_average()
    with tempfile.TemporaryDirectory() as tmp:
        policies = make_policies(Path(tmp))
        compare = ["-c", "import sys; from pipefollow.cli import main; sys.argv[1:] = sys.argv[1:]; main()",
                   "compare", *policies, "--json"]  # fmt: skip
        wall(compare)  # warm the compile cache
        times: dict[str, list[tuple[float, float]]] = {"compare": [], "numpy": []}
        for _ in range(args.repeats):
            times["compare"].append(wall(compare))
            times["numpy"].append(wall(["-c", "import numpy"]))
    rows = []
    for name, label in (("numpy", 'python -c "import numpy"'), ("compare", "pipefollow compare, 15 × 100")):
        w = statistics.median(t for t, _ in times[name])
        c = statistics.median(c for _, c in times[name])
        print(f"{label:<32} wall {w:6.2f} s   CPU {c:6.2f} s")
        target = 5.0 if name == "compare" else None
        rows += [(f"{label}, wall", w, target, None), (f"{label}, CPU", c, None, None)]
    if args.json:
        stored.write(args.json, "compare", "wall and CPU", args.repeats, load_before, rows)
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
