"""The B operator, the degree-of-freedom map and the sparse stiffness.

Every spring point ``k`` maps the six displacements of its two blocks
``(ux_a, uy_a, w_a, ux_b, uy_b, w_b)`` to its relative displacement
``(dn, ds)`` through a 2 x 6 matrix ``B_k``.  The stiffness
``K = sum_k w_k B_k^T D_k B_k`` has a fixed sparsity pattern (3 x 3 blocks
for every pair of touching free blocks): it is computed once and its values
are refilled per iteration by one precomputed sparse product of the spring
moduli.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from .blocks import Blocks
from .interfaces import Interfaces
from .springs import Springs


@dataclass(frozen=True, eq=False, repr=False)
class Assembly:
    """Everything needed to turn displacements into forces and stiffness.

    Attributes
    ----------
    dof : ndarray of int, shape (n_blocks, 3)
        Global equation number of each block's (ux, uy, w); -1 when fixed.
    B : ndarray, shape (n_springs, 2, 6)
        Rows ``dn`` and ``ds``; columns block a then block b.
    columns : ndarray of int, shape (n_springs, 6)
        Equation numbers of the six columns of ``B`` (-1 = fixed).
    length_scale : float
        Mean block size: scales moments and rotations in norms.
    """

    dof: np.ndarray
    n_dof: int
    B: np.ndarray
    columns: np.ndarray
    weight: np.ndarray
    points_per_interface: int
    indptr: np.ndarray
    indices: np.ndarray
    scatter: np.ndarray  # (n_interfaces * 36,) position in data, or -1
    length_scale: float
    #: ``B`` as one sparse (2 n_springs, n_dof) operator: rows dn0, ds0, dn1, ...
    operator: sp.csr_array | None = None

    @property
    def nnz(self) -> int:
        return len(self.indices)

    @property
    def dof_scale(self) -> np.ndarray:
        """Multiply a residual by this to compare forces and moments/length."""
        s = np.ones(self.n_dof)
        s[2::3] = 1.0 / self.length_scale
        return s

    # ---------------------------------------------------------- kinematics
    def relative_displacement(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(dn, ds)`` at every spring point for free-dof displacements ``q``."""
        d = (self.operator @ q).reshape(-1, 2)
        return d[:, 0], d[:, 1]

    def internal_force(self, force: np.ndarray) -> np.ndarray:
        """``sum_k w_k B_k^T p_k`` for generalised forces ``p`` (n_springs, 2)."""
        return self.weighted_transpose @ np.ascontiguousarray(force).ravel()

    @cached_property
    def _stiffness_map(self) -> sp.csr_array:
        """Maps the weighted spring moduli ``w [d_nn; d_sn; d_ss]`` (stacked) to
        the values of the fixed pattern: one sparse product per tangent.

        Entry ``(p, k)`` is ``Bn_i Bn_j`` (``Bs_i Bn_j``, ``Bs_i Bs_j`` for
        the second and third stack) of spring ``k`` for every pattern value
        ``p = (i, j)`` it touches; fixed columns are dropped.  (Replaces a
        batched 6 x 6 product per interface and a gather: 10,000 blocks
        10.3 -> 8.0 ms per tangent; it holds 108 values per spring, 1.1 GB
        at 94,533 blocks.)
        """
        n = len(self.weight)
        m = self.points_per_interface
        Bn, Bs = self.B[:, 0, :], self.B[:, 1, :]
        # the interfaces' 6 x 6 positions in the pattern, repeated for their points
        pos = np.repeat(self.scatter.reshape(-1, 36), m, axis=0)  # (n, 36)
        valid = pos >= 0
        # built column by column (a column per spring and stack, its rows in the
        # order of the 6 x 6 block): no coordinate-format copies, which took
        # 5.3 GB at 94,533 blocks
        rows = pos[valid].astype(np.int32)
        per_spring = np.concatenate([[0], np.cumsum(valid.sum(axis=1))])
        total = int(per_spring[-1])
        data = np.empty(3 * total)
        for stack, (left, right) in enumerate(((Bn, Bn), (Bs, Bn), (Bs, Bs))):
            outer = (left[:, :, None] * right[:, None, :]).reshape(n, 36)
            data[stack * total : (stack + 1) * total] = outer[valid]
        del pos, valid
        indptr = np.concatenate([per_spring, per_spring[1:] + total, per_spring[1:] + 2 * total])
        if 3 * total < np.iinfo(np.int32).max:  # 32-bit indices throughout: no 64-bit copy
            indptr = indptr.astype(np.int32)
        shape = (self.nnz, 3 * n)
        by_column = sp.csc_array((data, np.tile(rows, 3), indptr), shape=shape)
        del data, rows, indptr
        # kept by row: the product then gathers instead of scattering (10,000
        # blocks: 6.3 -> 3.9 ms per tangent) and sums every row in the same
        # (column) order, so the values are bit for bit the same
        by_row = sp.csr_array(by_column)
        del by_column
        by_row.sort_indices()
        return compact_indices(by_row)

    @cached_property
    def weighted_transpose(self) -> sp.csr_array:
        """``B^T W``: internal forces from the flat forces ``p.ravel()`` in one
        sparse product (every residual and every explicit step)."""
        w = sp.diags_array(np.repeat(self.weight, 2))
        return compact_indices(sp.csr_array(self.operator.T @ w))

    def stiffness(self, d_nn, d_sn, d_ss, shift: float = 0.0, base=None) -> sp.csc_array:
        """Tangent ``sum w B^T D B`` (+ ``shift * base``) on the fixed pattern.

        ``D = [[d_nn, 0], [d_sn, d_ss]]`` per point (non-symmetric when
        friction couples shear to normal stress).
        """
        w = self.weight
        data = self._stiffness_map @ np.concatenate([w * d_nn, w * d_sn, w * d_ss])
        if shift and base is not None:
            data = data + shift * base.data
        return sp.csc_array((data, self.indices, self.indptr), shape=(self.n_dof, self.n_dof))


def compact_indices(a):
    """``a`` with 32-bit index arrays where they fit: the sparse products read
    half the index memory (B q is about 1.9x faster at 10,000 blocks)."""
    if max(a.nnz, *a.shape) < np.iinfo(np.int32).max:
        a.indices = a.indices.astype(np.int32, copy=False)
        a.indptr = a.indptr.astype(np.int32, copy=False)
    return a


def build_assembly(blocks: Blocks, faces: Interfaces, springs: Springs) -> Assembly:
    """B operator, equation numbers and the sparsity pattern (computed once)."""
    free = ~blocks.fixed
    n_free = int(free.sum())
    dof = np.full((blocks.n_blocks, 3), -1, dtype=np.int64)
    dof[free] = np.arange(3 * n_free).reshape(-1, 3)

    a = faces.block_a[springs.interface]
    b = faces.block_b[springs.interface]
    n = faces.normal[springs.interface]
    t = faces.tangent[springs.interface]
    ra = springs.point - blocks.centroid[a]
    rb = springs.point - blocks.centroid[b]

    def cross(r, v):
        return r[:, 0] * v[:, 1] - r[:, 1] * v[:, 0]

    B = np.empty((springs.n_springs, 2, 6))
    for row, v in enumerate((n, t)):
        B[:, row, 0:2] = -v
        B[:, row, 2] = -cross(ra, v)
        B[:, row, 3:5] = v
        B[:, row, 5] = cross(rb, v)
    columns = np.concatenate([dof[a], dof[b]], axis=1)

    # sparsity pattern: the 6 x 6 block of every interface
    face_cols = np.concatenate([dof[faces.block_a], dof[faces.block_b]], axis=1)
    rows = np.repeat(face_cols, 6, axis=1).ravel()
    cols = np.tile(face_cols, (1, 6)).ravel()
    valid = (rows >= 0) & (cols >= 0)
    n_dof = 3 * n_free
    key = cols[valid].astype(np.int64) * max(n_dof, 1) + rows[valid]
    # every free dof also gets its diagonal, so the pattern is never empty
    diag = np.arange(n_dof, dtype=np.int64) * (n_dof + 1)
    unique, inverse = np.unique(np.concatenate([key, diag]), return_inverse=True)
    scatter = np.full(len(rows), -1, dtype=np.int64)
    scatter[valid] = inverse[: int(valid.sum())]
    indices = (unique % max(n_dof, 1)).astype(np.int32)
    col_of = unique // max(n_dof, 1)
    indptr = np.concatenate([[0], np.cumsum(np.bincount(col_of, minlength=n_dof))]).astype(np.int32)
    length_scale = float(np.sqrt(np.mean(np.abs(blocks.area)))) or 1.0
    # the sparse operator: entry (2k + row, column) = B[k, row, j]; fixed dofs dropped
    op_rows = np.broadcast_to(2 * np.arange(springs.n_springs)[:, None, None], B.shape)
    op_rows = op_rows + np.arange(2)[None, :, None]
    op_cols = np.broadcast_to(columns[:, None, :], B.shape)
    keep = op_cols >= 0
    operator = compact_indices(
        sp.csr_array(
            (B[keep], (op_rows[keep], op_cols[keep])), shape=(2 * springs.n_springs, n_dof)
        )
    )
    return Assembly(
        dof,
        n_dof,
        B,
        columns,
        springs.weight,
        springs.points_per_interface,
        indptr,
        indices,
        scatter,
        length_scale,
        operator,
    )
