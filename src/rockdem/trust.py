"""How far to trust a result: the statements an engineer checks before
signing (the bracket, how the failure is known, the solver's evidence, the
model's limits), in plain sentences for the report and the command line."""

from __future__ import annotations

import numpy as np

from .results import Analysis, FactorOfSafety, bracket_decimals

PROOF_TEXT = {
    "lp-certificate": "proven: no statically admissible force field carries the loads "
    "(equilibrium LP), whatever the solver",
    "dynamic-relaxation": "confirmed, not proven: a second solver (dynamic relaxation) "
    "leaves the blocks moving",
    "undecided": "not settled: the solver found no equilibrium, an admissible force field "
    "exists and the second solver did not confirm a mechanism; the factor may be higher",
}


def toppling_caution(fos: FactorOfSafety | None) -> list[str]:
    """A sentence when the factor of safety is the limit of a mechanism with
    toppling blocks that the equilibrium LP does not prove.

    With friction and no dilatancy a toppling limit is not unique: the LP
    finds admissible forces beyond it, and the limit the springs reach
    depends on how the joints are discretised.  Measured on a 14-column
    Goodman & Bray staircase (treads 25, base 30, face 55, phi 35; G&B
    0.9289): 0.9187 / 0.9650 / 0.9681 / 0.8919 with 2 / 3 / 4 / 5 Lobatto
    points, 0.8593 / 0.9016 with 2 / 3 Gauss points; the bundled toppling
    example 0.702 with 2 Lobatto points, 0.730 with 3 or 5 (G&B 0.735).
    """
    failed = fos.failed_analysis if fos is not None else None
    if failed is None or fos.value is None or failed.evidence.proof == "lp-certificate":
        return []
    from .modes import failure_modes

    modes = failure_modes(failed)
    toppling = [*modes.blocks("topples"), *modes.blocks("slides and topples")]
    if not toppling:
        return []
    settings = failed.system.model.settings
    return [
        f"The mechanism topples ({len(toppling)} block{'s' if len(toppling) > 1 else ''}) and "
        "the equilibrium LP does not prove its limit: with friction a toppling limit is not "
        "unique, and it depends on the spring points of the joints (a Goodman & Bray "
        "staircase, 0.929 by limit equilibrium, read 0.859 to 0.968 with 2 to 5 points; "
        f"this run: {settings.points_per_interface} {settings.quadrature} points).  Compare "
        "with 2 and 5 points (`rockdem study` of the file with `study: {sweep: "
        "{analysis.points_per_interface: {values: [2, 3, 5]}}}`) and with Goodman & Bray "
        "(`rockdem le` on a `limit_equilibrium: toppling` case file)."
    ]


def trust_statements(a: Analysis, fos: FactorOfSafety | None = None) -> list[str]:
    """Sentences on the reliability of ``a`` (and of ``fos``), most important first."""
    out = []
    failed = fos.failed_analysis if fos is not None else (None if a.stable else a)
    if fos is not None and fos.value is not None:
        lo, hi = fos.bracket
        d = bracket_decimals(lo, hi)  # "found at 0.7299 and lost at 0.7299" told nothing
        if fos.value == lo < hi:  # a bracket the search could not narrow
            out.append(
                f"Factor of safety {fos.value:.4f}: equilibrium was found at F = {lo:.{d}f} and "
                f"failure confirmed at F = {hi:.{d}f}; the search could not narrow that "
                "bracket, so the value is its stable end, the largest factor found stable."
            )
        else:
            out.append(
                f"Factor of safety {fos.value:.4f}: equilibrium was found at F = {lo:.{d}f} and "
                f"lost at F = {hi:.{d}f}; the value is the middle of that bracket "
                f"(+-{(hi - lo) / 2:.1g})."
            )
        bound = fos.certified_upper_bound
        if bound is not None:
            out.append(f"Rigorous upper bound (equilibrium LP): F <= {bound:.4f}.")
        top = fos.confirmed_upper_bound
        if top is not None and top > hi:
            cap = min(top, bound) if bound is not None else top
            proven = f" and proven from F = {cap:.4f} (LP)" if cap < top else ""
            out.append(
                f"Failure is confirmed at F = {top:.4f} (dynamic relaxation){proven}; between "
                f"{hi:.4f} and {cap:.4f} it is neither proven nor confirmed, so the limit lies "
                f"between {lo:.4f} and {cap:.4f}.  The value takes Newton's loss of equilibrium "
                "for the limit (on a 2,322-block test slope it was 0.6% below the exact one)."
            )
    elif fos is not None:
        lo, hi = fos.bracket
        top = "no failure found" if not np.isfinite(hi) else f"failing at F = {hi:.4g}"
        bottom = f"stable at F = {lo:.4g}" if lo > 0 else "stable at no factor tried"
        out.append(f"No factor of safety ({fos.mode}): {bottom}, {top}.")
        if fos.mode == "strength-independent":
            out.append(
                f"The mechanism forms even with the strengths divided by {hi:.4g} ({1 / hi:.3g} "
                "times their values): toppling, a free block, or joints with no strength to "
                "scale (c = 0 and phi = 0), which strength reduction cannot rate; rate it by "
                "the support force that holds it (`rockdem stabilise`)."
            )
    if failed is not None:
        ev = failed.evidence
        proof = ev.proof or "undecided"
        if fos is not None and fos.certified_upper_bound is not None and proof != "lp-certificate":
            # bedded-slope: "The failure is confirmed, not proven" two lines after
            # "proven from F = 1.2097 (LP)": it is the bracket's top that is not
            out.append(
                f"At the top of the bracket (F = {fos.bracket[1]:.4f}) the failure is "
                f"{PROOF_TEXT[proof]}; the LP proves it only from its bound."
            )
        else:
            out.append(f"The failure is {PROOF_TEXT[proof]}.")
        if ev.relaxation:
            out.append(f"Second solver, {ev.relaxation}.")
        if fos is not None and proof != "lp-certificate":
            from .continuation import stall_checked

            n_dof = a.system.assembly.n_dof
            if not stall_checked(n_dof):
                out.append(
                    f"On a model this large ({n_dof:,} unknowns) a Newton stall at the top of "
                    "the bracket is not checked by the second solver (too slow): failure is "
                    "only confirmed a little above the bracket, and the factor of safety may "
                    "lie anywhere up to that factor or the LP's bound, where given (a "
                    "94,533-block brick slope read 1.8978 against the exact 1.9238; the LP "
                    "bounded it at 1.9244)."
                )
        if ev.certificate:
            out.append(f"{ev.certificate[0].upper()}{ev.certificate[1:]}.")
        if failed.limit_interfaces is not None:
            from .modes import failure_modes

            modes = failure_modes(failed)
            guessed = modes.ids[modes.at_transition]
            if 0 < guessed.size < int((modes.code > 0).sum()):
                ids = ", ".join(str(i) for i in guessed[:20]) + (
                    ", ..." if guessed.size > 20 else ""
                )
                out.append(
                    f"Block(s) {ids} stood at the limit on a base partly open and partly at "
                    "its strength, between sliding and toppling: the mode shown is that of "
                    "the motion beyond the limit, which is chaotic in its detail."
                )
        out.append(
            f"Newton: {ev.reason} after {ev.iterations} iterations "
            f"(last out-of-balance {ev.residuals[-1]:.1e} of the loads)."
            if ev.residuals
            else f"Newton: {ev.reason}."
        )
    out += relaxed_steps(a)
    settings = a.system.model.settings
    out.append(
        f"Each joint is represented by {settings.points_per_interface} spring points "
        f"({settings.quadrature} rule); stresses between them are interpolated."
    )

    for shown in (a, fos.stable_analysis if fos is not None else None):
        text = large_displacement(shown) if shown is not None else None
        if text is not None:
            out.insert(0, f"{text[0].upper()}{text[1:]}.")
            break
    limit = fos.stable_analysis if fos is not None else None  # the state at the limit
    out += cohesion_lost_in_tension(limit if limit is not None else a)
    out += cohesion_lost_in_shear(limit if limit is not None else a)
    out += stiffness_contrast(a)
    out += toppling_caution(fos)
    if a.system.model.loads.water_table:
        out.append(
            "Water acts on joints below the water table (hydrostatic, on both faces); free "
            "faces are dry and no seepage is computed."
        )
    ru = a.system.model.loads.pore_pressure_ratio
    if ru:
        out.append(
            f"Water is a pore-pressure ratio r_u = {ru:g}: every joint carries r_u times the "
            "vertical overburden of rock above it (a quick check, not a flow field)."
        )
    return out


def relaxed_steps(a: Analysis) -> list[str]:
    """One sentence per load step whose equilibrium Newton could not find and
    dynamic relaxation did (:func:`rockdem.analysis.analyse` goes on from it)."""
    from .continuation import RELAXED

    out = []
    for step in a.steps:
        ev = step.evidence
        if step.converged and ev.relaxation:
            how = (
                "taken as the relaxation left it (within 1e-7 of the loads)"
                if ev.reason == RELAXED
                else "then polished by Newton"
            )
            out.append(
                f"Load step {step.stage}: Newton stalled and dynamic relaxation found the "
                f"equilibrium, {how} ({ev.relaxation})."
            )
    return out


def cohesion_lost_in_tension(a: Analysis) -> list[str]:
    """A sentence when spring points of joints with cohesion or tensile strength
    failed in tension in ``a``: each loses its bond over the whole share of the
    joint it stands for, so the bond lost depends on the number of points.
    (A block on a 30 degree plane, c = 5, seismic kh = 0.1 and kv = 0.05,
    its resultant outside the middle third: the heel point opened, FS 1.2561
    with 3 points, 1.2834 with 4, 1.2947 with 5, 1.3108 by limit equilibrium
    with the base closed.)"""
    from .springs import quadrature

    springs, state = a.system.springs, a.state
    bonded = (springs.cohesion > 0) | (springs.tensile > 0)
    lost = int((state.broken & bonded).sum())
    if lost == 0:
        return []
    settings = a.system.model.settings
    _, weights = quadrature(settings.quadrature, settings.points_per_interface)
    share = min(weights) / weights.sum()
    return [
        f"{lost} spring point(s) of joints with cohesion or tensile strength failed in "
        f"tension: each loses its bond over the share of the joint it stands for (at least "
        f"{share:.0%} with {settings.points_per_interface} {settings.quadrature} points), so "
        "the bond lost, and the result, depend on the number of spring points; where that "
        "bond matters, compare with another number of points per interface."
    ]


def cohesion_lost_in_shear(a: Analysis) -> list[str]:
    """A sentence when spring points of brittle joints (residual cohesion below
    the peak) yielded in shear in ``a``: the joint then fails progressively,
    point by point, and its limit depends on the number of points.  (Wyllie &
    Mah's plane failure, c 25, residual 0, crack water 3 m: 1.128 / 1.114 /
    1.022 with 2 / 3 / 5 points, Hoek & Bray's ductile 1.247.)"""
    springs, state = a.system.springs, a.state
    brittle = springs.cohesion_residual < springs.cohesion
    lost = int((state.yielded & ~state.broken & brittle).sum())
    if lost == 0:
        return []
    settings = a.system.model.settings
    return [
        f"{lost} spring point(s) of brittle joints (residual_cohesion below cohesion) yielded "
        "in shear and lost their cohesion: the joint fails progressively, point by point, so "
        "the result depends on the number of spring points (a plane failure with c 25, "
        "residual 0, read 1.128 / 1.114 / 1.022 with 2 / 3 / 5 points, and 1.247 with the "
        f"cohesion kept); this run: {settings.points_per_interface} {settings.quadrature} "
        "points.  Compare with 2 and 5 points, and with residual_cohesion equal to cohesion "
        "(the limit-equilibrium assumption)."
    ]


#: joints whose normal stiffnesses differ by more than this get a sentence
#: (rockdem.joints refuses more than STIFFNESS_CONTRAST_MAX)
CONTRAST_NOTED = 10.0


def stiffness_contrast(a: Analysis) -> list[str]:
    """A sentence when the joints in use differ in normal stiffness by more
    than CONTRAST_NOTED times: a progressive failure's factor then depends on
    the contrast (the perpendicular-joints example: 0.911 with equal
    stiffnesses, 0.998 with one set 10 times stiffer, 0.805 with it 100
    times softer)."""
    from .joints import check_stiffness_contrast

    system = a.system
    contrast = check_stiffness_contrast(system.model.joints, system.interfaces.joint)
    if contrast <= CONTRAST_NOTED:
        return []
    return [
        f"The joints' normal stiffnesses differ by up to {contrast:.3g} times: with "
        "non-associated friction the factor of safety of a progressive failure depends on "
        "that contrast (an example slope: 0.911 with equal stiffnesses, 0.998 with one set "
        "10 times stiffer); compare with equal stiffnesses."
    ]


#: an equilibrium in which a joint opens or slides by more than this share of
#: the mean block size, or a block turns more than this many radians, is
#: beyond the small displacements the method assumes (a 10,000-block brick
#: slope standing under gravity: joints slid up to 0.06 block sizes, turned
#: 0.002 rad; with the 1,000-block slope's joint stiffness, the 94,533-block
#: slope's back column slid 0.57 block sizes past the fixed boundary: it fired,
#: as it should).  (Not the blocks' own translations: on a 94,533-block slope
#: the elastic settlement under gravity is 0.7 block sizes, every joint's
#: displacement a small share of it; not
#: the share of each interface's length: brick slopes have interfaces of a
#: few mm where bricks' corners meet.)
LARGE_DISPLACEMENT = 0.25


def large_displacement(a: Analysis) -> str | None:
    """A warning when the equilibrium ``a`` opened or slid its joints, or
    turned its blocks, far beyond small displacements (joints of stiffness 1
    under a 10 m slope: blocks moved 2.8 km and turned 43 times, reported
    stable); None otherwise, or when ``a`` is not stable."""
    system = a.system
    if not a.stable or system.assembly.n_dof == 0:
        return None
    asm = system.assembly
    free = ~system.blocks.fixed
    dn, ds = asm.relative_displacement(a.q)
    moved = float(np.max(np.maximum(np.abs(dn), np.abs(ds))))
    # the size of the free blocks (the assembly's length scale also counts the
    # fixed ground: a 3 m block beside 6,000 m^2 of ground slid 5.8 m unflagged)
    size = float(np.sqrt(np.mean(np.abs(system.blocks.area[free])))) or asm.length_scale
    share = moved / size
    turn = float(np.abs(a.displacement[:, 2]).max())
    if share <= LARGE_DISPLACEMENT and turn <= LARGE_DISPLACEMENT:
        return None
    fix = "the joints are too soft for these loads: raise their normal_stiffness"
    if system.bolts is not None:
        fix = (
            "the joints are too soft for these loads, or the bolts reach their force only "
            "after this much slip: raise the joints' normal_stiffness or the bolts' "
            "axial_stiffness"
        )
    return (
        f"in equilibrium a joint opens or slides by up to {moved:.3g} ({share:.3g} times the "
        f"mean size of the free blocks) and the blocks turn up to {turn:.3g} rad: far beyond "
        f"the small displacements the method assumes, so the verdict does not hold; {fix}"
    )
