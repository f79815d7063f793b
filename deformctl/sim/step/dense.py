"""Small dense solves inside the step kernels (the contact problem's active blocks, the warm
start's normal equations).
"""

from __future__ import annotations

from numba import njit

from deformctl.arraytypes import FloatArray


@njit(cache=True)
def _solve_dense(a: FloatArray, b: FloatArray, out: FloatArray) -> bool:
    """Gaussian elimination with partial pivoting (in place); False when singular."""
    n = b.shape[0]
    scale = 0.0
    for i in range(n):
        scale = max(scale, abs(a[i, i]))
    for col in range(n):
        piv = col
        for r in range(col + 1, n):
            if abs(a[r, col]) > abs(a[piv, col]):
                piv = r
        if abs(a[piv, col]) <= 1e-12 * scale:
            return False
        if piv != col:
            for c in range(n):
                a[col, c], a[piv, c] = a[piv, c], a[col, c]
            b[col], b[piv] = b[piv], b[col]
        for r in range(col + 1, n):
            f = a[r, col] / a[col, col]
            if f != 0.0:
                for c in range(col, n):
                    a[r, c] -= f * a[col, c]
                b[r] -= f * b[col]
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for c in range(i + 1, n):
            acc -= a[i, c] * out[c]
        out[i] = acc / a[i, i]
    return True


@njit(cache=True)
def _lu_factor(a: FloatArray, n: int) -> bool:
    """In-place LU without pivoting of ``a[:n, :n]`` (Delassus matrices: nearly symmetric, SPD)."""
    for k in range(n):
        piv = a[k, k]
        if not piv > 0.0:
            return False
        for i in range(k + 1, n):
            f = a[i, k] / piv
            a[i, k] = f
            if f != 0.0:
                for j in range(k + 1, n):
                    a[i, j] -= f * a[k, j]
    return True


@njit(cache=True)
def _lu_solve(a: FloatArray, n: int, b: FloatArray) -> None:
    """Solve with the factor of :func:`_lu_factor`, in place on ``b[:n]``."""
    for i in range(n):
        acc = b[i]
        for j in range(i):
            acc -= a[i, j] * b[j]
        b[i] = acc
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for j in range(i + 1, n):
            acc -= a[i, j] * b[j]
        b[i] = acc / a[i, i]
