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
carry (HiGHS's dual simplex, through highspy).  If ``mu < load_factor`` no solver can find
equilibrium there: a rigorous proof of failure.  ``mu >= load_factor``
proves nothing (friction without dilatancy can fail earlier), so it only
confirms failures.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from .limit import LimitProof
from .spring_law import SpringState, strength

#: the LP stops at this multiple of the load (the answer "at least this")
MU_CAP = 2.0
#: certified when the admissible multiple falls short of the load by this share
MARGIN = 1e-6
#: the equilibrium LP is solved for models up to this many spring points
CERTIFY_MAX_SPRINGS = 250_000
#: ... and on larger ones, for the moving blocks' equations alone (a region),
#: where these touch up to this many (a 94,533-block brick slope, 848,805
#: spring points: the whole LP took 19-21 s and 1.5 GB to prove failure in
#: its presolve; the brick slopes' failed trials moved 6,026 of 9,638 and
#: 19,183 of 28,556 blocks, whose LPs took 0.7 and 3.3 s)
REGION_MAX_SPRINGS = 500_000
#: the dual simplex gives up (no answer) after 3 iterations per equilibrium
#: row (1,021 blocks: an admissible field was found in 1.8 per row, a
#: cohesive failure proven in 1.3) ...
LP_ITERATIONS_PER_ROW = 3.0
#: a quick LP (a proof tried where failure is only expected) gives up after
#: this many (brick slopes of 1,000 to 10,000 blocks: every proof within
#: 0.1% of the limit came from the presolve, 0 iterations; where the loads
#: are carried, 1,000 blocks took 8,500 iterations, 1.1 s, to say so)
QUICK_ITERATIONS = 300
#: ... and on large models after LP_WORK / rows^2 (an iteration costs about
#: rows^2 x 6e-9 s: 0.5 ms at 8,856 rows, 4.6 ms at 28,914): about 0.5 s.
#: A cohesionless failure is proven without any (86,013 spring points: 0.8 s)
LP_WORK = 8e10


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
        carried = (
            "none of the loads (no multiple of them, however small)"
            if self.mu == 0
            else f"at most {self.mu:.4g} times the loads"
        )
        head = (
            f"equilibrium LP at F = {self.strength_factor:.6g}: statically admissible forces "
            f"carry {carried}"
        )
        if self.proves_failure and self.mu == 0:
            return head
        if self.proves_failure:
            return f"{head}, less than the {self.load_factor:.4g} applied"
        # (said plainly: beside a toppling column's confirmed failure, "an
        # admissible force field exists" read as a contradiction; the LP lets
        # every joint carry its friction whether it would open or not)
        return (
            f"{head} ({self.load_factor:.4g} applied: forces within the joints' strengths "
            "could balance the loads, so the LP does not prove failure; whether the blocks "
            "can take up such forces is for the other checks)"
        )


def admissible_load(
    system, state: SpringState, load_factor: float, factor: float, region=None, quick=False
) -> Certificate:
    """Solve the LP for ``system`` with the strengths of ``state`` divided by ``factor``.

    ``region`` (bool per block, optional) keeps only the equilibrium equations
    of those free blocks and the springs on their interfaces.  Dropping
    equations relaxes the LP, so "no admissible field in the region" still
    proves that none exists in the whole model; the LP is then as small as
    the mechanism, not the model.  ``quick``: give up after few simplex
    iterations (see :data:`QUICK_ITERATIONS`): a proof of failure near the
    limit comes from HiGHS's presolve, or within a few iterations; an LP
    that carries the loads needs about as many as it has rows.
    """
    asm = system.assembly
    springs = system.springs
    # the loads as forces and moments: the LP scales its rows itself (the
    # loads' moments were scaled twice, by the block size squared, and on a
    # column whose model's mean block size was 32.6 m the LP "proved"
    # failure at F = 1, where it stands; found by the work-controlled search)
    f = system.f_ext
    f_scale = float(np.max(np.abs(f * asm.dof_scale))) if asm.n_dof else 0.0
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
        if state.bolts_waiting:  # bolts to go in after the loads carry nothing yet
            waiting = np.tile(np.isnan(state.bolt_reference[:, 0]), 2)
            b_lo, b_hi = np.where(waiting, 0.0, b_lo), np.where(waiting, 0.0, b_hi)
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
    # unknowns are forces / f_scale
    bolt_part = (op_b, b_lo / f_scale, b_hi / f_scale) if bolts is not None else None
    mu, status = _max_load_multiple(
        op,
        bolt_part,
        scale_rows,
        f / f_scale,
        c * w / f_scale,
        tan_phi,
        tensile * w / f_scale,
        quick,
    )
    if mu is None:
        return Certificate(load_factor, factor, None, status)
    return Certificate(load_factor, factor, max(mu, 0.0) + 0.0, "optimal")


def _max_load_multiple(op, bolt_part, scale_rows, load, cw, tan_phi, tension, quick=False):
    """The largest load multiple ``mu`` (HiGHS dual simplex), or None
    and why not.

    The spring-point forces are written on the edges of their strength
    polygon, so that every limit is a bound and the only rows are the
    equilibrium equations (one per unknown of the model).  With the limits
    as inequality rows (the textbook form) HiGHS took 8 s at 8,955 spring
    points; in this form a failure is proven in 0.07 s (0.7 s at 86,013).

    For ``N >= -T`` and ``|S| <= c w + N tan phi`` (forces): the apex of
    the cone, ``N = -c w / tan phi``, cuts the tension off where it comes
    first, ``T' = min(T, c w / tan phi)``; then with ``a = c w - T' tan phi
    >= 0``, every admissible pair is ``N = -T' + u + v``, ``S = tan phi (u -
    v) + r`` with ``u, v >= 0`` and ``|r| <= a`` (and every such pair is
    admissible).
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        apex = np.where(tan_phi > 0, cw / tan_phi, np.inf)
    t_eff = np.minimum(tension, apex)
    a = np.maximum(cw - t_eff * tan_phi, 0.0)
    n = len(cw)
    bn_t, bs_t = op[0::2].T, op[1::2].T  # -Bn^T N + Bs^T S (+ bolts) = mu f
    tan = sp.diags_array(tan_phi)
    shear = a > 0  # (no column where the polygon's edge has no cohesive part)
    blocks = [-bn_t + bs_t @ tan, -bn_t - bs_t @ tan, bs_t[:, np.flatnonzero(shear)]]
    lo = [np.zeros(2 * n), -a[shear]]
    hi = [np.full(2 * n, np.inf), a[shear]]
    if bolt_part is not None:  # + Ba^T T + Bv^T V: the bolts' forces, within their capacities
        op_b, b_lo, b_hi = bolt_part
        blocks += [op_b[0::2].T, op_b[1::2].T]
        lo.append(b_lo)
        hi.append(b_hi)
    blocks.append(sp.csr_array(-load[:, None]))
    lo.append([0.0])
    hi.append([MU_CAP])
    scale = sp.diags_array(scale_rows)
    A = sp.csc_array(scale @ sp.hstack(blocks, format="csc"))
    rhs = -(scale @ (bn_t @ t_eff))  # the -T' part of N, moved to the right
    cost = np.zeros(A.shape[1])
    cost[-1] = -1.0
    limit = _iteration_limit(A.shape[0], quick)
    return _solve_lp(cost, A, rhs, np.concatenate(lo), np.concatenate(hi), limit)


def _solve_lp(cost, A, rhs, lo, hi, iteration_limit):
    """``min cost x`` with ``A x = rhs``, ``lo <= x <= hi`` by HiGHS's dual
    simplex (highspy: imported in 15 ms, where SciPy's ``linprog`` took
    0.15-0.3 s, a third of the two-block wedge's whole ``rockdem fos``).
    Returns the last unknown, or None and why not."""
    import highspy

    # the bare solver class: the wrapper's constructor prints a banner on
    # stdout before any option can silence it (it would break --json)
    h = getattr(highspy, "_Highs", highspy.Highs)()
    # (no "threads": HiGHS keeps one thread pool per process, and a run asking
    # for another size than the process's other HiGHS users fails; the dual
    # simplex is serial anyway)
    for option, value in (
        ("output_flag", False),
        ("solver", "simplex"),
        ("simplex_strategy", 1),  # dual
        ("simplex_iteration_limit", iteration_limit),
    ):
        h.setOptionValue(option, value)
    lp = highspy.HighsLp()
    lp.num_row_, lp.num_col_ = A.shape
    lp.col_cost_ = cost
    lp.col_lower_ = lo
    lp.col_upper_ = np.minimum(hi, highspy.kHighsInf)
    lp.row_lower_ = lp.row_upper_ = rhs
    lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    lp.a_matrix_.start_ = A.indptr
    lp.a_matrix_.index_ = A.indices
    lp.a_matrix_.value_ = A.data
    h.passModel(lp)
    if h.run() == highspy.HighsStatus.kError:
        return None, "HiGHS stopped with an error"
    status = h.getModelStatus()
    if status != highspy.HighsModelStatus.kOptimal:
        return None, h.modelStatusToString(status)
    return float(h.getSolution().col_value[-1]), "optimal"


def _iteration_limit(rows: int, quick: bool = False) -> int:
    """Dual simplex iterations before the LP on ``rows`` equations gives up."""
    full = int(min(LP_ITERATIONS_PER_ROW * rows + 1000, LP_WORK / max(rows, 1) ** 2))
    return min(full, QUICK_ITERATIONS) if quick else full


#: LP solves of the bisection for a rigorous upper bound above a bracket
#: whose top is not proven (each 0.1-0.7 s from 1,000 to 10,000 blocks)
BOUND_SOLVES = 6


def upper_bound(system, state, failed, lo: float, hi: float, solves: int = BOUND_SOLVES):
    """The smallest strength factor in ``(lo, hi]`` at which the equilibrium
    LP proves failure, to ``(hi - lo) / 2^(solves - 1)``; None when it does
    not prove it at ``hi``.

    Weaker joints carry less, so "proven" is monotone in the factor and a
    bisection finds its edge.  Where Newton stalls below the limit (no
    second solver checks a stall above 20,000 unknowns) the LP still bounds
    the factor of safety from above: a 2,322-block planar-sliding slope
    (exact 1.4866) stalled at 1.4781, confirmed only at 1.5076; the LP
    proves failure from 1.4873.  With non-associated friction (toppling)
    the LP's edge can lie far above the limit: then it proves nothing in
    the range and costs one LP.  On models too large for the LP, the moving
    blocks' equations alone (``failed.unstable``) still prove it.
    """
    region = None
    if system.springs.n_springs > CERTIFY_MAX_SPRINGS:
        if not failed.unstable.any():
            return None
        region = failed.unstable

    def proves(factor: float) -> bool:
        return certificate_for(system, state, 1.0, factor, region).proves_failure

    if not proves(hi):
        return None
    for _ in range(solves - 1 if lo < hi else 0):
        mid = 0.5 * (lo + hi)
        if proves(mid):
            hi = mid
        else:
            lo = mid
    return hi


# ------------------------------------------------ proofs attached to results
def certificate_for(system, state, load_factor, factor, region=None, quick=False) -> Certificate:
    """The equilibrium LP (rockdem.certificate), or a note that it was skipped.

    ``region``: only these blocks' equations (a relaxation that still proves
    failure), used when the whole model is too large for the LP.  ``quick``:
    see :func:`admissible_load`.  The answers are kept on the system: the
    search asks for the same proof again when it reports it.
    """
    key = (id(system.springs), *_cache_key(system, state, load_factor, factor, region))
    known = system.certificates.get(key)
    if known is not None and (known.proves_failure or known.mu is not None or quick):
        return known
    cert = _certificate_for(system, state, load_factor, factor, region, quick)
    if known is None or cert.proves_failure or cert.mu is not None:
        system.certificates[key] = cert
    return cert


def lp_limit_proof(system, state, load_factor: float, width: float) -> LimitProof:
    """The factor-of-safety search's proof of a limit (rockdem.limit): the
    quick equilibrium LP at the strengths of ``state``; on models too large
    for it, the LP of the mechanism's blocks (``moving``), which proves
    failure for the whole model too."""
    large = system.springs.n_springs > CERTIFY_MAX_SPRINGS

    def proves(factor: float, moving=None) -> bool | None:
        if large and (moving is None or not moving.any()):
            return None
        region = moving if large else None
        cert = certificate_for(system, state, load_factor, factor, region, quick=True)
        if cert.mu is None and cert.status.startswith("not solved"):
            return None  # (too large a region: a failure nearer the limit may move fewer)
        return cert.proves_failure

    return LimitProof(proves, width)


def _cache_key(system, state, load_factor, factor, region):
    """What an LP's answer depends on besides the system: the strengths in
    force (of the failure flags; the same for any flags where no strength is
    lost on failing), the bolts installed, the factors and the region."""
    reduce = system.model.settings.reduce_tensile
    parts = [a.tobytes() for a in strength(system.springs, state, factor, reduce)]
    if state.bolt_reference is not None:
        parts.append(np.packbits(np.isnan(state.bolt_reference[:, 0])).tobytes())
    if region is not None:
        parts.append(np.packbits(np.asarray(region, dtype=bool)).tobytes())
    data = b"".join(parts)
    return (float(load_factor), float(factor), hash(data), len(data))


def _certificate_for(system, state, load_factor, factor, region, quick) -> Certificate:
    n, most = system.springs.n_springs, CERTIFY_MAX_SPRINGS
    if region is not None:
        faces = system.interfaces
        touch = region[faces.block_a] | region[faces.block_b]
        n, most = int(touch[system.springs.interface].sum()), REGION_MAX_SPRINGS
    if n > most:
        text = f"not solved ({n:,} spring points > {most:,})"
        return Certificate(load_factor, factor, None, text)
    return admissible_load(system, state, load_factor, factor, region, quick)


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
