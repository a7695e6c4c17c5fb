"""Proof of "no equilibrium": the statically admissible force field LP.

Any equilibrium the DEM finds is a set of spring-point forces, normal
``N_k >= -T_k`` (tensile capacity) and shear ``|S_k| <= c_k w_k + N_k tan phi_k``
(strengths divided by the factor), that balances the loads.  The linear
program

    maximise mu  subject to  B^T [-N; S] + Bb^T [T; V] = mu f_ext,
                             the strength limits,  0 <= mu <= MU_CAP

(``T, V``: the axial and shear forces of the bolts' crossings, within
their capacities; :mod:`rockdem.bolts`)
finds the largest multiple ``mu`` of the loads that such a force field can
carry (HiGHS, through SciPy).  If ``mu < load_factor`` no solver can find
equilibrium there: a rigorous proof of failure.  ``mu >= load_factor``
proves nothing (friction without dilatancy can fail earlier), so it only
confirms failures.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from .spring_law import SpringState, strength

#: the LP stops at this multiple of the load (the answer "at least this")
MU_CAP = 2.0
#: certified when the admissible multiple falls short of the load by this share
MARGIN = 1e-6
#: the equilibrium LP is solved for models up to this many spring points
#: (HiGHS interior point: 2.3 s at 2,769 springs, 26 s at 9,200: faster than linear)
CERTIFY_MAX_SPRINGS = 4_000


@dataclass(frozen=True)
class Certificate:
    """Largest admissible load multiple ``mu`` at a strength factor."""

    load_factor: float
    strength_factor: float
    mu: float | None  # None: the LP solver gave no answer
    status: str

    @property
    def proves_failure(self) -> bool:
        return self.mu is not None and self.mu < self.load_factor * (1.0 - MARGIN)

    def __str__(self) -> str:
        if self.mu is None:
            return f"equilibrium LP: no answer ({self.status})"
        head = (
            f"equilibrium LP at F = {self.strength_factor:.6g}: statically admissible forces "
            f"carry at most {self.mu:.4g} times the loads"
        )
        if self.proves_failure:
            return f"{head}, less than the {self.load_factor:.4g} applied"
        return f"{head} ({self.load_factor:.4g} applied: an admissible force field exists)"


def admissible_load(
    system, state: SpringState, load_factor: float, factor: float, region=None
) -> Certificate:
    """Solve the LP for ``system`` with the strengths of ``state`` divided by ``factor``.

    ``region`` (bool per block, optional) keeps only the equilibrium equations
    of those free blocks and the springs on their interfaces.  Dropping
    equations relaxes the LP, so "no admissible field in the region" still
    proves that none exists in the whole model; the LP is then as small as
    the mechanism, not the model.
    """
    asm = system.assembly
    springs = system.springs
    f = system.f_ext * asm.dof_scale
    f_scale = float(np.max(np.abs(f))) if asm.n_dof else 0.0
    if asm.n_dof == 0 or f_scale == 0.0:
        return Certificate(load_factor, factor, MU_CAP, "no load")
    c, tan_phi, tensile = strength(springs, state, factor, system.model.settings.reduce_tensile)
    w = springs.weight
    op = sp.csr_array(asm.operator)
    bolts = system.bolts
    if bolts is not None:  # bolt forces are variables too, within their capacities
        op_b = sp.csr_array(bolts.operator)
        b_lo = np.concatenate([bolts.t_min, -bolts.v_max])
        b_hi = np.concatenate([bolts.t_max, bolts.v_max])
    if region is not None:
        keep_block = np.asarray(region, dtype=bool) & ~system.blocks.fixed
        rows = np.sort(asm.dof[keep_block].ravel())
        faces = system.interfaces
        touch = keep_block[faces.block_a] | keep_block[faces.block_b]
        keep = touch[springs.interface]
        pick = np.flatnonzero(np.repeat(keep, 2))
        op = op[pick][:, rows]
        if bolts is not None:
            ends = faces.block_a[bolts.interface], faces.block_b[bolts.interface]
            near = keep_block[ends[0]] | keep_block[ends[1]]
            op_b = op_b[np.flatnonzero(np.repeat(near, 2))][:, rows]
            b_lo = b_lo[np.concatenate([near, near])]
            b_hi = b_hi[np.concatenate([near, near])]
        f = f[rows]
        scale_rows = asm.dof_scale[rows]
        c, tan_phi, tensile, w = c[keep], tan_phi[keep], tensile[keep], w[keep]
        if not len(rows) or not np.any(f):
            return Certificate(load_factor, factor, None, "empty region")
    else:
        scale_rows = asm.dof_scale
    n = len(w)
    scale = sp.diags_array(scale_rows)  # unknowns are forces / f_scale
    # equilibrium rows (scaled forces and moments / length): -Bn^T N + Bs^T S - mu f = 0
    A_eq = sp.hstack([-(op[0::2].T), op[1::2].T], format="csr")
    n_b = 0
    if bolts is not None:  # + Ba^T T + Bv^T V (axial and shear forces of the crossings)
        A_eq = sp.hstack([A_eq, op_b[0::2].T, op_b[1::2].T], format="csr")
        n_b = len(b_lo)
    A_eq = sp.hstack([scale @ A_eq, sp.csr_array(-(f / f_scale)[:, None])], format="csr")
    eye = sp.eye_array(n, format="csr")
    T = sp.diags_array(tan_phi)
    # +S - tan N <= c w ;  -S - tan N <= c w   (forces scaled by f_scale)
    A_ub = sp.vstack(
        [
            sp.hstack([-T, eye, sp.csr_array((n, n_b + 1))]),
            sp.hstack([-T, -eye, sp.csr_array((n, n_b + 1))]),
        ],
        format="csr",
    )
    b_ub = np.concatenate([c * w, c * w]) / f_scale
    lower_n = -tensile * w / f_scale
    bounds = np.empty((2 * n + n_b + 1, 2))
    bounds[:n] = np.column_stack([lower_n, np.full(n, np.inf)])
    bounds[n : 2 * n] = (-np.inf, np.inf)
    if n_b:
        bounds[2 * n : 2 * n + n_b] = np.column_stack([b_lo, b_hi]) / f_scale
    bounds[-1] = (0.0, MU_CAP)
    cost = np.zeros(2 * n + n_b + 1)
    cost[-1] = -1.0
    from scipy.optimize import linprog  # 0.3 s to import: only when an LP is solved

    res = linprog(
        cost,
        A_ub=A_ub,
        b_ub=b_ub,
        A_eq=A_eq,
        b_eq=np.zeros(A_eq.shape[0]),
        bounds=bounds,
        method="highs-ipm",
    )
    if res.status != 0:
        return Certificate(load_factor, factor, None, res.message)
    return Certificate(load_factor, factor, max(float(res.x[-1]), 0.0) + 0.0, "optimal")


# ------------------------------------------------ proofs attached to results
def certificate_for(system, state, load_factor, factor, region=None) -> Certificate:
    """The equilibrium LP (rockdem.certificate), or a note that it was skipped.

    ``region``: only these blocks' equations (a relaxation that still proves
    failure), used when the whole model is too large for the LP.
    """
    n = system.springs.n_springs
    if region is not None:
        faces = system.interfaces
        touch = region[faces.block_a] | region[faces.block_b]
        n = int(touch[system.springs.interface].sum())
    if n > CERTIFY_MAX_SPRINGS:
        text = f"not solved ({n:,} spring points > {CERTIFY_MAX_SPRINGS:,})"
        return Certificate(load_factor, factor, None, text)
    return admissible_load(system, state, load_factor, factor, region)


def with_certificate(system, ev, state, load_factor, factor, cert=None):
    """``ev`` with the equilibrium LP's verdict on a failed solve at
    (``load_factor``, ``factor``) with the strengths of ``state``."""
    if cert is None or cert.strength_factor != factor:
        cert = certificate_for(system, state, load_factor, factor)
    return replace(
        ev, certified=cert.proves_failure, certificate=str(cert), certified_at=cert.strength_factor
    )


def prove_in_region(system, failed, state, factor: float):
    """A failure the whole-model LP could not check (too large): the LP on
    the moving blocks alone, which proves failure for the whole model too."""
    ev = failed.evidence
    if ev.certified or not failed.unstable_blocks.size:
        return failed
    if system.springs.n_springs <= CERTIFY_MAX_SPRINGS:
        return failed  # the whole-model LP was solved: a region cannot prove more
    region = np.zeros(system.blocks.n_blocks, dtype=bool)
    region[np.isin(system.blocks.ids, failed.unstable_blocks)] = True
    cert = certificate_for(system, state, 1.0, factor, region)
    if not cert.proves_failure:
        return failed
    text = f"{cert} (on the {int(region.sum()):,} moving blocks)"
    ev = replace(ev, certified=True, certificate=text, certified_at=factor)
    return replace(failed, steps=(*failed.steps[:-1], replace(failed.steps[-1], evidence=ev)))


def prove_failed_trial(system, failed, state, factor: float, trials):
    """The failed trial with the equilibrium LP's verdict at ``factor`` (the
    strengths of ``state``, the last stable trial's flags), and the trial list
    with that trial's evidence updated."""
    last = failed.steps[-1]
    ev = with_certificate(system, last.evidence, state, 1.0, factor)
    failed = replace(failed, steps=(*failed.steps[:-1], replace(last, evidence=ev)))
    failed = prove_in_region(system, failed, state, factor)
    ev = failed.evidence
    trials = list(trials)
    last_failed = max(i for i, t in enumerate(trials) if not t.stable)
    trials[last_failed] = replace(trials[last_failed], evidence=ev)
    return failed, trials
