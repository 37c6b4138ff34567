"""Wall time of ``pipefollow reproduce`` as a user waits for it: trials, tables, figures and report.

Usage: ``python benchmarks/reproduce.py [--repeats N] [--baseline SRC] [--cold] [--no-figures]``

Each run is a fresh interpreter writing a fresh run folder (``from pipefollow.cli import main``,
what the console script runs), timed from start to exit; its ``evaluation.csv`` is checked to be
byte-identical to ``docs/reproduction/evaluation.csv``. With ``--baseline SRC`` (the ``src``
folder of other code, e.g. ``git archive OLD src | tar -x -C /tmp/old``) the two codes run in
turns, so that both share the machine's load of the moment, and the median of the paired ratios
is printed. Warm runs use the compile cache of ``NUMBA_CACHE_DIR`` (one untimed run first fills
it); ``--cold`` gives every run an empty compile cache of its own.
"""

from __future__ import annotations

import argparse
import filecmp
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "docs" / "reproduction" / "evaluation.csv"
RUN = "import sys; from pipefollow.cli import main; sys.argv[1:] = {args!r}; main()"


def run_once(src: Path, out: Path, cache: str | None, figures: bool, check: bool = True):
    """(wall seconds, CPU seconds of the command and its workers) of one ``reproduce``.

    ``check``: compare its ``evaluation.csv`` with the committed one (not for a baseline's older numbers).
    """
    args = ["reproduce", "--out", str(out)] + ([] if figures else ["--no-figures"])
    env = {**os.environ, "PYTHONPATH": str(src)}
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = cache
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    subprocess.run(
        [sys.executable, "-c", RUN.format(args=args)],
        check=True,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if check and not filecmp.cmp(out / "evaluation.csv", REFERENCE, shallow=False):
        raise SystemExit(f"{src}: evaluation.csv differs from {REFERENCE}")
    return wall, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="timed runs of each code")
    parser.add_argument("--baseline", type=Path, default=None, help="src folder of the code to compare")
    parser.add_argument(
        "--baseline-cache", default=None, help="NUMBA_CACHE_DIR of the baseline [default: the same as this]"
    )
    parser.add_argument("--cold", action="store_true", help="an empty compile cache for every run")
    parser.add_argument("--no-figures", action="store_true", help="time reproduce --no-figures")
    args = parser.parse_args()
    codes = {"this": ROOT / "src"}
    caches = {"this": None, "baseline": args.baseline_cache}
    if args.baseline is not None:
        codes["baseline"] = args.baseline.resolve()
    times: dict[str, list[tuple[float, float]]] = {name: [] for name in codes}
    with tempfile.TemporaryDirectory(prefix="pipefollow-bench-") as tmp:
        tmp = Path(tmp)
        if not args.cold:
            for name, src in codes.items():  # fill the compile cache; not timed
                run_once(src, tmp / f"warm-{name}", caches[name], figures=False, check=name == "this")
        for i in range(args.repeats):
            for name, src in codes.items():
                cache = tempfile.mkdtemp(dir=tmp) if args.cold else caches[name]
                figures, check = not args.no_figures, name == "this"  # a baseline may have other numbers
                wall, cpu = run_once(src, tmp / f"{name}-{i}", cache, figures, check)
                times[name].append((wall, cpu))
                print(f"run {i + 1} {name:<8} wall {wall:6.2f} s  CPU {cpu:6.2f} s", flush=True)
    kind = "cold" if args.cold else "warm"
    print(f"\n{kind} `pipefollow reproduce`, {args.repeats} runs each, load average {os.getloadavg()[0]:.1f}")
    for name, ts in times.items():
        walls, cpus = [w for w, _ in ts], [c for _, c in ts]
        print(
            f"{name:<8} wall median {statistics.median(walls):6.2f} s (min {min(walls):.2f})"
            f"  CPU median {statistics.median(cpus):6.2f} s"
        )
    if "baseline" in times:
        ratios = [n[0] / b[0] for n, b in zip(times["this"], times["baseline"], strict=True)]
        cpu_ratios = [n[1] / b[1] for n, b in zip(times["this"], times["baseline"], strict=True)]
        print(
            f"this / baseline: wall {statistics.median(ratios):.2f} (median of paired ratios), "
            f"CPU {statistics.median(cpu_ratios):.2f}"
        )


if __name__ == "__main__":
    main()
