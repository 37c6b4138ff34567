"""The learners' sums: a fixed order of summation, the same bits under every CPU target."""

import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from pipefollow.learners.sums import LANES, dot, matvec


def reference_dot(a, b):
    """The order :func:`dot` promises, in Python floats (IEEE double, no fused multiply-add)."""
    a, b = a.tolist(), b.tolist()
    n = len(a)
    m = n - n % LANES
    s = [0.0] * LANES
    for i in range(0, m, LANES):
        for j in range(LANES):
            s[j] += a[i + j] * b[i + j]
    tail = 0.0
    for i in range(m, n):
        tail += a[i] * b[i]
    return (((s[0] + s[1]) + (s[2] + s[3])) + ((s[4] + s[5]) + (s[6] + s[7]))) + tail


SIZES = [0, 1, 7, 8, 9, 16, 13, 1764, 22932]


@pytest.mark.parametrize("n", SIZES)
def test_dot_sums_in_the_documented_order(n):
    rng = np.random.default_rng(n)
    a, b = rng.standard_normal(n), rng.standard_normal(n)
    assert dot(a, b) == reference_dot(a, b)  # bit for bit


@pytest.mark.parametrize("n", [13, 1764])
def test_dot_is_the_exact_sum_to_rounding(n):
    rng = np.random.default_rng(100 + n)
    a, b = rng.standard_normal(n), rng.standard_normal(n)
    exact = math.fsum(x * y for x, y in zip(a.tolist(), b.tolist(), strict=True))
    assert abs(dot(a, b) - exact) <= 1e-13 * math.fsum(abs(x * y) for x, y in zip(a, b, strict=True))


def test_dot_order_is_not_the_plain_loop():
    # the test above would pass for any order; this one sees that the order is the documented one
    rng = np.random.default_rng(3)
    a, b = rng.standard_normal(1764), rng.standard_normal(1764)
    plain = 0.0
    for x, y in zip(a.tolist(), b.tolist(), strict=True):
        plain += x * y
    assert plain != reference_dot(a, b)  # these data tell the two orders apart
    assert dot(a, b) == reference_dot(a, b)


def test_matvec_is_dot_per_row():
    rng = np.random.default_rng(4)
    M, x = rng.standard_normal((21, 100)), rng.standard_normal(100)
    assert np.array_equal(matvec(M, x), [reference_dot(row, x) for row in M])


CHILD = """
import json, sys
import numpy as np
from pipefollow.learners.sums import dot
out = []
for n in %r:
    rng = np.random.default_rng(n)
    a, b = rng.standard_normal(n), rng.standard_normal(n)
    out.append(dot(a, b).hex())
print(json.dumps(out))
"""


def host_features():
    from llvmlite import binding

    return {f[1:] for f in binding.get_host_cpu_features().flatten().split(",") if f.startswith("+")}


# numba's targets and the instructions each needs of the host: a target the host cannot run is skipped
TARGETS = {
    "generic": set(),
    "haswell": {"avx2", "fma", "bmi2"},
    "skylake-avx512": {"avx512f", "avx512bw", "avx512dq", "avx512vl"},
    "znver4": {"avx512f", "avx512bw", "avx512dq", "avx512vl", "avx512vnni"},
}


@pytest.mark.slow  # a fresh interpreter compiling for each target (≈ 4 s each)
@pytest.mark.parametrize("target", list(TARGETS))
def test_dot_gives_the_same_bits_under_every_cpu_target(target, tmp_path):
    if not TARGETS[target] <= host_features():
        pytest.skip(f"this host cannot run numba's {target} target")
    env = dict(os.environ, NUMBA_CPU_NAME=target, NUMBA_CACHE_DIR=str(tmp_path))
    res = subprocess.run(
        [sys.executable, "-c", CHILD % (SIZES,)], env=env, capture_output=True, text=True, check=True
    )
    expected = []
    for n in SIZES:
        rng = np.random.default_rng(n)
        a, b = rng.standard_normal(n), rng.standard_normal(n)
        expected.append(reference_dot(a, b).hex())
    assert json.loads(res.stdout) == expected
