"""Slow-time interpolation of a decimated render: banded, in place, with reused buffers.

A :class:`~raysim.synthesis.decimate.DecimationPlan` gives every interpolated chirp
``n`` weights on its nearest exact chirps, ``rows[n] = sum_i w[n, i] rows[exact[i]]``.
Each chirp draws on at most a few dozen neighbours (its taps), so the weight matrix
``[missing, exact]`` is banded: a whole-matrix product spends most of its
multiplications on zeros (about 95 % for a factor of 2 on 256 chirps). Here the
interpolated chirps are taken in runs of consecutive chirps that share the same
window of exact chirps (the chirps of one gap, as a rule); each run is one small
product ``[run, taps] @ [taps, columns]`` written into a reused buffer and added
into its rows of the output in place. Column blocks bound the buffer.

:func:`scatter_add_dense` keeps the whole-matrix product (the reference of the
tests and of the benchmark ``raysim.bench.suite.bench_interpolation``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["runs", "interpolate", "scatter_add", "scatter_add_dense", "COL_BLOCK"]

#: Columns (float32 values) per product: bounds the buffer at ``run x COL_BLOCK`` float32.
COL_BLOCK = 1 << 15


def runs(plan) -> list[tuple[int, int, int, int, np.ndarray]]:
    """The interpolated chirps of ``plan`` as runs sharing one window of exact chirps.

    Returns
    -------
    list of (first, last, lo, hi, weights)
        Chirps ``first .. last - 1`` (local indices, consecutive, all interpolated)
        draw on exact rows ``lo .. hi - 1`` (indices into ``plan.exact``) with
        ``weights`` ``[last - first, hi - lo]`` float32 (C-contiguous).
    """
    w = plan.weights
    if plan.missing.size == 0:
        return []
    nz = w != 0
    any_nz = nz.any(axis=1)
    lo = np.where(any_nz, nz.argmax(axis=1), 0)
    hi = np.where(any_nz, w.shape[1] - nz[:, ::-1].argmax(axis=1), 1)
    miss = plan.missing
    # a new run where the chirp is not the next one or the window changes
    cut = np.flatnonzero((np.diff(miss) != 1) | (np.diff(lo) != 0) | (np.diff(hi) != 0)) + 1
    out = []
    for a, b in zip(np.concatenate([[0], cut]), np.concatenate([cut, [miss.size]]),
                    strict=True):
        a, b = int(a), int(b)
        out.append((int(miss[a]), int(miss[a]) + (b - a), int(lo[a]), int(hi[a]),
                    np.ascontiguousarray(w[a:b, lo[a]:hi[a]])))
    return out


def _check(out: np.ndarray, exact_rows: np.ndarray, plan) -> None:
    for name, a in (("out", out), ("exact_rows", exact_rows)):
        if a.dtype != np.complex64 or not a.flags.c_contiguous:
            raise ValueError(f"{name} must be C-contiguous complex64, got {a.dtype}")
    if exact_rows.shape != (plan.exact.size,) + out.shape[1:]:
        raise ValueError(f"exact_rows must have shape {(plan.exact.size,) + out.shape[1:]}, "
                         f"got {exact_rows.shape}")


def _banded(dst: np.ndarray, src: np.ndarray, plan, col_block: int, add: bool) -> None:
    """``dst[missing] (+)= weights @ src`` run by run, ``dst`` ``[chirp, columns]`` and
    ``src`` ``[exact, columns]`` float32 views."""
    parts = runs(plan)
    if not parts:
        return
    buf = np.empty((max(b - a for a, b, *_ in parts), min(col_block, src.shape[1])),
                   np.float32)
    for c0 in range(0, src.shape[1], col_block):
        c1 = min(c0 + col_block, src.shape[1])
        for a, b, lo, hi, w in parts:
            tmp = buf[:b - a, :c1 - c0]
            np.matmul(w, src[lo:hi, c0:c1], out=tmp)
            if add:
                dst[a:b, c0:c1] += tmp
            else:
                dst[a:b, c0:c1] = tmp


def interpolate(rows: np.ndarray, plan, col_block: int = COL_BLOCK) -> None:
    """Fill ``rows[plan.missing]`` from ``rows[plan.exact]`` in place.

    Parameters
    ----------
    rows : ndarray, shape ``[chirp, ...]``, complex64, C-contiguous
        Rendered chirps (local indices), exact rows filled.
    plan : DecimationPlan
    col_block : int
        Columns (float32 values) per product (bounds the buffer).
    """
    if plan.missing.size == 0:
        return
    if rows.dtype != np.complex64 or not rows.flags.c_contiguous:
        raise ValueError(f"rows must be C-contiguous complex64, got {rows.dtype}")
    flat = rows.reshape(rows.shape[0], -1).view(np.float32)
    # the exact rows are read while the missing ones are written: disjoint rows
    src = flat[plan.exact] if plan.exact.size else flat[:0]
    _banded(flat, src, plan, col_block, add=False)


def scatter_add(out: np.ndarray, exact_rows: np.ndarray, plan,
                col_block: int = COL_BLOCK) -> None:
    """Add the exact chirps and their interpolation into a whole block.

    Parameters
    ----------
    out : ndarray, shape ``[chirp, ...]``, complex64, C-contiguous
        Receives ``exact_rows`` at ``plan.exact`` and ``weights @ exact_rows`` at
        ``plan.missing`` (added).
    exact_rows : ndarray, shape ``[n_exact, ...]``, complex64, C-contiguous
    plan : DecimationPlan
    col_block : int
        Columns (float32 values) per product (bounds the buffer).
    """
    _check(out, exact_rows, plan)
    for i, n in enumerate(plan.exact):             # row by row: no copy of the exact block
        out[n] += exact_rows[i]
    if plan.missing.size == 0:
        return
    src = exact_rows.reshape(exact_rows.shape[0], -1).view(np.float32)
    dst = out.reshape(out.shape[0], -1).view(np.float32)
    _banded(dst, src, plan, col_block, add=True)


def scatter_add_dense(out: np.ndarray, exact_rows: np.ndarray, plan,
                      col_block: int = 1 << 16) -> None:
    """:func:`scatter_add` by the whole weight matrix (zeros included) and fancy indexing:
    the reference of the banded form."""
    _check(out, exact_rows, plan)
    for i, n in enumerate(plan.exact):
        out[n] += exact_rows[i]
    if plan.missing.size == 0:
        return
    src = exact_rows.reshape(exact_rows.shape[0], -1).view(np.float32)
    dst = out.reshape(out.shape[0], -1).view(np.float32)
    for c0 in range(0, src.shape[1], col_block):
        c1 = min(c0 + col_block, src.shape[1])
        dst[plan.missing, c0:c1] += plan.weights @ src[:, c0:c1]
