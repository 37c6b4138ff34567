"""Start-up of the command line: wall time of ``pipefollow --help`` and ``--version``.

Usage: ``python benchmarks/startup.py [--repeats N]``

Each command is a fresh interpreter, run in turns with ``python -c "import numpy"`` and
``python -c "pass"`` so that all share the machine's load of the moment; the medians are printed
beside each other. The console script ``pipefollow`` runs ``from pipefollow.cli import main;
main()``, which is what is timed here (the interpreter of this script, the package it imports).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time

RUN = "import sys; from pipefollow.cli import main; sys.argv[1:]"
COMMANDS = {
    'python -c "pass"': ["-c", "pass"],
    'python -c "import numpy"': ["-c", "import numpy"],
    "pipefollow --help": ["-c", f"{RUN} = ['--help']; main()"],
    "pipefollow --version": ["-c", f"{RUN} = ['--version']; main()"],
}


def wall(args: list[str]) -> float:
    t = time.perf_counter()
    subprocess.run([sys.executable, *args], check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    for cmd in COMMANDS.values():  # warm the file cache and the bytecode
        wall(cmd)
    times: dict[str, list[float]] = {name: [] for name in COMMANDS}
    for _ in range(args.repeats):
        for name, cmd in COMMANDS.items():
            times[name].append(wall(cmd))
    numpy = statistics.median(times['python -c "import numpy"'])
    print(f"{'command':<28} {'median':>8} {'min':>8}  ratio to import numpy")
    for name, ts in times.items():
        med = statistics.median(ts)
        print(f"{name:<28} {med:>7.3f}s {min(ts):>7.3f}s  {med / numpy:.2f}")


if __name__ == "__main__":
    main()
