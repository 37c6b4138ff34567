"""The same seed gives the same numbers on every CPU: the reproduction under numba's generic target.

``learners.sums`` fixes the order of every sum of the learners, and no compiled function of the
simulator or the learners lets the compiler fuse or reorder floating-point operations, so the code
numba compiles for an old CPU (``generic``: no SIMD beyond SSE2, no fused multiply-add) and for the
host (AVX2, AVX-512, …) must compute the same bits. The committed ``docs/reproduction/evaluation.csv``
is the reference: it must come out byte for byte under each target.
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest

COMMITTED = Path(__file__).resolve().parents[1] / "docs" / "reproduction" / "evaluation.csv"


def _reproduce(out: Path, env: dict) -> bytes:
    cmd = [sys.executable, "-m", "pipefollow.cli", "reproduce", "--out", str(out), "--no-figures"]
    subprocess.run(cmd, env=env, check=True, capture_output=True, text=True)
    return (out / "evaluation.csv").read_bytes()


def test_reproduction_on_the_host_target_equals_the_committed_evaluation(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CPU_NAME"}
    assert _reproduce(tmp_path / "run", env) == COMMITTED.read_bytes()


@pytest.mark.slow  # compiles the simulator and the learners for another target (≈ 1–2 min on 2 cores)
def test_reproduction_under_the_generic_cpu_target_equals_the_committed_evaluation(tmp_path):
    env = dict(os.environ, NUMBA_CPU_NAME="generic", NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    assert _reproduce(tmp_path / "run", env) == COMMITTED.read_bytes()
