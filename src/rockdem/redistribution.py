"""One load level to equilibrium, with the failures redistributed.

A converged solve commits the spring state (which springs yielded, opened
or broke); where a committed failure sheds strength (brittle cohesion, the
tensile bond) the excess force goes to the neighbouring springs and the same
load is solved again, round after round, until no more strength is lost:
the paper's progressive redistribution, until every interface is in
equilibrium and compatible with the deformations, or no equilibrium exists.
"""

from __future__ import annotations

import warnings

from .continuation import RELAXED, solve_equilibrium
from .errors import ModelWarning
from .linalg import norm
from .relaxation import TOLERANCE as RELAXATION_TOLERANCE
from .solver import KINKED, Solve, residual
from .spring_law import commit, strength, widest_openings_first

#: cascade limit: re-solves at one load level after strength was lost
MAX_CASCADE = 100


def settle(
    system,
    state,
    q0,
    load_factor,
    factor,
    stage,
    base_factor=None,
    total=False,
    resolution=None,
    first: Solve | None = None,
    proven=None,
    limit_proof=None,
):
    """Solve at one load level, re-solving while committed failures shed strength.

    Returns ``(solve, state)``; the state is committed only if the solve
    converged.  ``total=True`` keeps the plastic slip at zero (the shear
    spring follows the total relative displacement): used by the strength
    trials, see :func:`factor_of_safety`.  ``first``: the first solve, when
    it was found another way (an equilibrium of the dynamic relaxation).
    """
    tol = system.model.settings.tolerance
    scale = system.assembly.dof_scale
    f_norm = norm(load_factor * system.f_ext * scale)
    sol = first or solve_equilibrium(
        system,
        state,
        load_factor=load_factor,
        strength_factor=factor,
        q0=q0,
        base_factor=base_factor,
        resolution=resolution,
        proven=proven,
        limit_proof=limit_proof,
    )
    iterations, history = sol.iterations, list(sol.residuals)
    for _ in range(MAX_CASCADE):
        if not sol.converged:
            break
        dn, ds = system.assembly.relative_displacement(sol.q)
        in_force = strength(system.springs, state, factor, system.model.settings.reduce_tensile)
        response, deferred = widest_openings_first(
            system.springs, state, sol.response, dn, in_force
        )
        new_state = commit(system.springs, state, response, ds, stage)
        if system.bolts is not None:  # bolts that reached their capacity, and when
            yielded = system.bolts.forces(sol.q, new_state.bolt_reference)[2]
            new_state = new_state.with_bolt_yield(yielded, stage)
        if total:
            new_state = new_state.without_slip()
        resp, r = residual(system, sol.q, new_state, load_factor, factor)
        state = new_state
        # an equilibrium of the dynamic relaxation (or a Newton solve that stopped
        # within that method's tolerance) holds to that tolerance
        held = max(tol, RELAXATION_TOLERANCE) if sol.reason in (RELAXED, KINKED) else tol
        if (f_norm == 0 or norm(r * scale) <= held * f_norm) and not deferred:
            sol = Solve(True, sol.q, resp, iterations, history, sol.reason, sol.direction)
            break
        sol = solve_equilibrium(
            system,
            state,
            load_factor=load_factor,
            strength_factor=factor,
            q0=sol.q,
            base_factor=factor,
        )
        iterations += sol.iterations
        history += sol.residuals
    else:
        if sol.converged:  # (never seen: bonds breaking widest first add rounds)
            warnings.warn(
                ModelWarning(
                    f"the failures at load step {stage} kept spreading for {MAX_CASCADE} "
                    "rounds of redistribution; the last round's failures are not committed"
                ),
                stacklevel=2,
            )
    out = Solve(
        sol.converged,
        sol.q,
        sol.response,
        iterations,
        history,
        sol.reason,
        sol.direction,
        sol.reached,
        sol.reached_q,
        sol.failed_at,
        sol.relaxation,
    )
    return out, state
