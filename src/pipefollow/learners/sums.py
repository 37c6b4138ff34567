"""The learners' linear algebra, with a summation order fixed at compile time.

``np.dot`` and ``@`` inside compiled code call the BLAS library, whose order of summation may
depend on its thread count: Ray workers run single-threaded BLAS, a local process may not, and a
last-bit difference in one value grows into different learning runs. These loops are compiled
once (and cached); the only licence given to the compiler is to reassociate the sum of
:func:`dot` into SIMD lanes, a split fixed by the compiled code. So every process on a machine —
serial, process pool or Ray worker — gives the same numbers for the same seed. Machines with a
different SIMD width (say AVX2 and AVX-512 nodes of one Ray cluster) compile a different split
and can differ in the last bits.
"""

from __future__ import annotations

import numpy as np
from numba import njit


# Only reassociation: SIMD lanes (3× faster here), no assumptions about NaN or infinity.
@njit(cache=True, fastmath={"reassoc"})
def dot(a, b):
    """Σ a_i b_i."""
    s = 0.0
    for i in range(a.shape[0]):
        s += a[i] * b[i]
    return s


@njit(cache=True)
def matvec(M, x):
    """Mx for a matrix M (n × m) and a vector x (m)."""
    out = np.empty(M.shape[0])
    for i in range(M.shape[0]):
        out[i] = dot(M[i], x)
    return out
