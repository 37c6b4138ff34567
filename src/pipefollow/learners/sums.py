"""The learners' linear algebra, with one summation order on every CPU.

A last-bit difference in one value grows into a different learning run, so every sum of the
learners is computed in an order fixed by this code, not by the compiler, the CPU or a library:

* ``np.dot`` and ``@`` inside compiled code call BLAS, whose order of summation depends on its
  kernels (chosen per CPU) and its thread count; these loops replace them.
* A compiler licensed to reassociate (``fastmath={"reassoc"}``) splits a sum into as many SIMD
  lanes as the target has: AVX2, AVX-512 and Zen machines, or numba's ``generic`` target, then sum
  in different orders. :func:`dot` instead keeps :data:`LANES` explicit partial sums, combined in
  a fixed tree. The compiler may still put the eight running sums into vector registers, but each
  one is the same IEEE sequence of products and sums on every target: the same bits under
  ``NUMBA_CPU_NAME=generic``, ``haswell``, ``skylake-avx512`` and ``znver4`` (tests/test_sums.py
  compares them in subprocesses). No flag of ``fastmath`` is given: ``contract`` would fuse
  multiply and add into FMA where the target has it.

So every process of every machine — serial, process pool or a mixed Ray cluster — gives the same
numbers for the same seed. Speed: on 1,764 features :func:`dot` takes ≈ 1.6× the time of the
reassociated loop and ≈ 0.6× that of a plain loop (benchmarks/README.md).
"""

from __future__ import annotations

import numpy as np
from numba import njit

LANES = 8  # partial sums of :func:`dot`; part of the numbers' definition: changing it changes results


@njit(cache=True)
def dot(a, b):
    """Σ a_i b_i: eight partial sums over i mod 8, combined as ((0+1)+(2+3))+((4+5)+(6+7)), then the tail."""
    n = a.shape[0]
    m = n - n % LANES
    s0 = s1 = s2 = s3 = s4 = s5 = s6 = s7 = 0.0
    for i in range(0, m, LANES):
        s0 += a[i] * b[i]
        s1 += a[i + 1] * b[i + 1]
        s2 += a[i + 2] * b[i + 2]
        s3 += a[i + 3] * b[i + 3]
        s4 += a[i + 4] * b[i + 4]
        s5 += a[i + 5] * b[i + 5]
        s6 += a[i + 6] * b[i + 6]
        s7 += a[i + 7] * b[i + 7]
    tail = 0.0
    for i in range(m, n):
        tail += a[i] * b[i]
    return (((s0 + s1) + (s2 + s3)) + ((s4 + s5) + (s6 + s7))) + tail


@njit(cache=True)
def matvec(M, x):
    """Mx for a matrix M (n × m) and a vector x (m), each row by :func:`dot`."""
    out = np.empty(M.shape[0])
    for i in range(M.shape[0]):
        out[i] = dot(M[i], x)
    return out
