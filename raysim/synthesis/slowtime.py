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

__all__ = ["blocks", "interpolate", "scatter_add", "scatter_add_dense", "COL_BLOCK",
           "BLOCK_ROWS"]

#: Columns (float32 values) per product: bounds the buffer at ``BLOCK_ROWS x COL_BLOCK``
#: float32.
COL_BLOCK = 1 << 17
#: Interpolated chirps per product: enough rows for an efficient BLAS product (its
#: threads wake once per product), few enough that the window of their taps skips most
#: of the zeros of the weight matrix.
BLOCK_ROWS = 32


def blocks(plan, rows: int | None = None) -> list[tuple[np.ndarray | slice, int, int,
                                                        np.ndarray]]:
    """The interpolated chirps of ``plan`` in blocks of ``rows`` with their window of taps.

    Returns
    -------
    list of (segments, lo, hi, weights)
        ``segments``: ``(chirps, rows)`` slices, the block's local chirps (one strided
        slice where they are evenly spaced, else runs of consecutive chirps) and their
        rows in the block; they draw on exact rows ``lo .. hi - 1`` (indices into
        ``plan.exact``, the union of their taps) with ``weights`` ``[block, hi - lo]``
        float32 (C-contiguous; zero outside each chirp's taps).
    """
    rows = BLOCK_ROWS if rows is None else int(rows)
    w = plan.weights
    miss = plan.missing
    if miss.size == 0:
        return []
    nz = w != 0
    any_nz = nz.any(axis=1)
    lo = np.where(any_nz, nz.argmax(axis=1), 0)
    hi = np.where(any_nz, w.shape[1] - nz[:, ::-1].argmax(axis=1), 1)
    out = []
    for a in range(0, miss.size, rows):
        b = min(a + rows, miss.size)
        m = miss[a:b]
        step = int(m[1] - m[0]) if m.size > 1 else 1
        if np.all(np.diff(m) == step):             # evenly spaced: one strided view
            segments = [(slice(int(m[0]), int(m[-1]) + 1, step), slice(0, m.size))]
        else:                                      # runs of consecutive chirps
            cut = np.concatenate([[0], np.flatnonzero(np.diff(m) != 1) + 1, [m.size]])
            segments = [(slice(int(m[i]), int(m[j - 1]) + 1), slice(int(i), int(j)))
                        for i, j in zip(cut[:-1], cut[1:], strict=True)]
        w0, w1 = int(lo[a:b].min()), int(hi[a:b].max())
        out.append((segments, w0, w1, np.ascontiguousarray(w[a:b, w0:w1])))
    return out


def _check(out: np.ndarray, exact_rows: np.ndarray, plan) -> None:
    for name, a in (("out", out), ("exact_rows", exact_rows)):
        if a.dtype != np.complex64 or not a.flags.c_contiguous:
            raise ValueError(f"{name} must be C-contiguous complex64, got {a.dtype}")
    if exact_rows.shape != (plan.exact.size,) + out.shape[1:]:
        raise ValueError(f"exact_rows must have shape {(plan.exact.size,) + out.shape[1:]}, "
                         f"got {exact_rows.shape}")


def _banded(dst: np.ndarray, src: np.ndarray, plan, col_block: int, add: bool) -> None:
    """``dst[missing] (+)= weights @ src`` block by block, ``dst`` ``[chirp, columns]`` and
    ``src`` ``[exact, columns]`` float32 views."""
    parts = blocks(plan)
    if not parts:
        return
    buf = np.empty((max(w.shape[0] for *_, w in parts), min(col_block, src.shape[1])),
                   np.float32)
    for c0 in range(0, src.shape[1], col_block):
        c1 = min(c0 + col_block, src.shape[1])
        for segments, lo, hi, w in parts:
            tmp = buf[:w.shape[0], :c1 - c0]
            np.matmul(w, src[lo:hi, c0:c1], out=tmp)
            for chirps, rows in segments:          # views: no gather, no scatter
                if add:
                    dst[chirps, c0:c1] += tmp[rows]
                else:
                    dst[chirps, c0:c1] = tmp[rows]


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
