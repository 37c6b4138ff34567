"""The learners' linear algebra, with a fixed order of summation.

``np.dot`` and ``@`` inside compiled code call the BLAS library, whose order of summation may
depend on its thread count: Ray workers run single-threaded BLAS, a local process may not, and a
last-bit difference in one value grows into different learning runs. These loops sum in one
fixed order, so the same seed gives the same numbers in every process and on every backend.
"""

from __future__ import annotations

import numpy as np
from numba import njit


# ``fastmath`` lets the compiler split the sums into SIMD lanes; the split is fixed when the
# function is compiled, so every process running the same compiled code sums in the same order.
@njit(cache=True, fastmath=True)
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
