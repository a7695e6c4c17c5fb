"""What the engine says about a model file, in the file's terms: its errors
mapped back to the key path at fault, and the warnings of a model that
builds but may not be what was meant."""

from __future__ import annotations

import re
import warnings
from typing import Any

from ..errors import InputError, ModelWarning
from ..interfaces import lines_along_no_contact
from .errors import Loc, ModelFileError, _keypath, _line
from .spec import ModelFile

#: an equilibrium tolerance above this is warned about (the default is 1e-8)
LOOSE_TOLERANCE = 1e-5


def _warn_loose_tolerance(tolerance: float, source: str, nodes: Any) -> None:
    """Warn for a tolerance loose enough to move the results (found
    by fuzzing: 0.00999, allowed, gave the paper's wedge 0.9991 for 0.9786)."""
    if tolerance <= LOOSE_TOLERANCE:
        return
    line = _line(nodes, ("analysis", "tolerance"))
    where = f"{source}:{line}" if line else source
    _warn(
        f"{where}: analysis.tolerance {tolerance:g} counts out-of-balance forces up to that "
        "share of the loads as equilibrium, so a stable result or the low end of a factor "
        "of safety's bracket may be no equilibrium (the paper's wedge: 0.9805 at 1e-3 and "
        "0.9991 at 0.00999, against 0.9786); keep the default 1e-8 unless you know why"
    )


def _warn_unused_lines(system, cfg: ModelFile, own_lines: int, source: str, nodes: Any) -> None:
    """Warn once, naming the file's own joint lines that lie along no
    contact but nearly follow one: their joints are used nowhere, and the
    contact one was meant for keeps another joint (found by fuzzing: a weak
    joint drawn 1 mm off the base of a block left it on the strong default,
    STABLE instead of UNSTABLE, silently).  Lines far from every contact are
    not named: an imported section's traces run on through the fixed ground
    or end inside a block, and a DXF round trip keeps them."""
    if not own_lines or system.model.joint_lines is None:
        return
    lines = system.model.joint_lines[:own_lines]
    unused = lines_along_no_contact(system.interfaces, system.blocks, lines)
    if not len(unused):
        return
    first = int(unused[0])
    line = _line(nodes, ("joint_lines", first))
    where = f"{source}:{line}" if line else source
    if len(unused) == 1:
        what = f"joint_lines[{first}] (joint {cfg.joint_lines[first].joint}) lies"
        fix = "it gives its joint to none; check its points if it was meant for one"
    else:
        listed = ", ".join(f"[{i}]" for i in unused[:5]) + (", ..." if len(unused) > 5 else "")
        what = f"{len(unused)} of the {own_lines} joint lines (joint_lines{listed}) lie"
        fix = "they give their joints to none; check their points if they were meant for one"
    _warn(f"{where}: {what} along no contact between blocks, but close along one: {fix}")


#: rock is this many times as heavy as water (coal 1.2 to dense ore 5)
ROCK_OVER_WATER = (1.0, 5.0)
#: a water unit weight within this factor of the units' own is taken as meant
WATER_SLACK = 1.5
#: converted values may pass the rock band's edges by this factor
ROUNDING = 1.01


def _warn_unit_weights(model, cfg: ModelFile, source: str, nodes: Any) -> None:
    """Warn for unit weights that do not fit the system the ``units`` note
    names (found by fuzzing: water 1.0, the t/m^3 value, in a kN model read
    FS 1.3933 for 1.1072; rock 2.5 in a kN model 1.42 for 1.196)."""
    from ..units import water_unit_weight

    gamma_w = water_unit_weight(cfg.units)
    if gamma_w is None:
        return
    given = model.loads.water_unit_weight
    if given and not gamma_w / WATER_SLACK <= given <= gamma_w * WATER_SLACK:
        line = _line(nodes, ("loads", "water_unit_weight"))
        where = f"{source}:{line}" if line else source
        _warn(
            f"{where}: loads.water_unit_weight {given:g} is not the unit weight of water in "
            f"{cfg.units.split('(')[0].strip()} ({gamma_w:g}): check the value or the units"
        )
    free = ~model.blocks.fixed
    weights = model.blocks.unit_weight[free]
    lo, hi = ROCK_OVER_WATER[0] * gamma_w, ROCK_OVER_WATER[1] * gamma_w
    # (ROUNDING: a unit weight converted from the band's edge in other units,
    # 5 t/m^3 = 312.14 lbf/ft^3 against 5 x 62.4, is not outside it)
    odd = weights[(weights > 0) & ((weights < lo / ROUNDING) | (weights > hi * ROUNDING))]
    if odd.size:
        _warn(
            f"{source}: a rock unit weight of {odd[0]:g} is not {ROCK_OVER_WATER[0]:g} to "
            f"{ROCK_OVER_WATER[1]:g} times that of water in {cfg.units.split('(')[0].strip()} "
            f"({lo:.3g} to {hi:.3g}): check the value or the units"
        )


def _warn_dry_water_table(system, source: str, nodes: Any) -> None:
    """A water table below every joint of the free rock loads nothing (found by
    hostile testing: one at y = -100 under a model at 0 to 2, elevations in
    another datum say, was accepted without a word)."""
    import numpy as np

    from ..loads import pore_pressure

    loads, faces, blocks = system.model.loads, system.interfaces, system.blocks
    free = ~(blocks.fixed[faces.block_a] & blocks.fixed[faces.block_b])
    if not loads.water_table or not free.any():
        return
    table = np.asarray(loads.water_table)
    a, b = faces.start[free], faces.end[free]
    t = np.linspace(0.0, 1.0, 9)
    pts = (a[:, None, :] + t[None, :, None] * (b - a)[:, None, :]).reshape(-1, 2)
    kinks = table[(table[:, 0] > pts[:, 0].min()) & (table[:, 0] < pts[:, 0].max())]
    if pore_pressure(loads, pts).max() > 0 or (kinks[:, 1] > pts[:, 1].min()).any():
        return  # wet somewhere (a kink of the table between the points: maybe)
    line = _line(nodes, ("loads", "water_table"))
    where = f"{source}:{line}" if line else source
    _warn(
        f"{where}: loads.water_table lies at or below every joint of the free rock (the lowest "
        f"at y = {pts[:, 1].min():.6g}), so no joint carries water; check its levels (the "
        "same datum as the blocks), or leave it out"
    )


def _warn_seismic_without_gravity(model, source: str, nodes: Any) -> None:
    """Seismic coefficients (and a pore-pressure ratio) scale the blocks'
    weight; with gravity off that force acts with no weight holding the
    blocks down (found by fuzzing: kh
    0.3 alone, a push of 0.3 W with no normal force, read UNSTABLE)."""
    loads = model.loads
    if loads.gravity:
        return
    if loads.pore_pressure_ratio:  # (found by hostile testing: weightless rock under
        # r_u x its weight of water was lifted off, UNSTABLE with nothing said why)
        line = _line(nodes, ("loads", "pore_pressure_ratio"))
        where = f"{source}:{line}" if line else source
        _warn(
            f"{where}: loads.pore_pressure_ratio with gravity off: the joint water (r_u x "
            "the weight of the rock above) acts with no weight holding the blocks; set "
            "`gravity: true`, or leave the ratio out"
        )
    if not (loads.seismic_h or loads.seismic_v):
        return
    key = "seismic_h" if loads.seismic_h else "seismic_v"
    line = _line(nodes, ("loads", key))
    where = f"{source}:{line}" if line else source
    _warn(
        f"{where}: loads.{key} with gravity off: the seismic force (the coefficient x the "
        "blocks' weight) acts with no weight holding the blocks; set `gravity: true` "
        "for a pseudo-static analysis"
    )


def _warn_coincident_joint_lines(model, source: str) -> None:
    """Joint lines of two different joints lying on each other (found by
    fuzzing: two joint sets with the same dip, spacing and origin, every
    line doubled): a contact along them takes one of the two joints, which
    the file does not say."""
    import numpy as np
    import shapely

    lines = model.joint_lines
    if lines is None or len(lines) < 2:
        return
    which = np.asarray([model.joint_index(j) for j in model.line_joint])
    tol = model.blocks.tolerance
    geoms = shapely.linestrings(lines)
    i, j = shapely.STRtree(geoms).query(geoms, predicate="dwithin", distance=tol)
    keep = (i < j) & (which[i] != which[j])
    i, j = i[keep], j[keep]
    d = lines[:, 1] - lines[:, 0]
    d = d / np.maximum(np.hypot(*d.T), 1e-300)[:, None]
    parallel = np.abs(d[i, 0] * d[j, 1] - d[i, 1] * d[j, 0]) < 1e-9
    i, j = i[parallel], j[parallel]
    if not len(i):
        return
    shared = shapely.length(shapely.intersection(geoms[i], shapely.buffer(geoms[j], tol)))
    hit = np.flatnonzero(shared > 10 * tol)
    if not hit.size:
        return
    k = hit[0]
    a, b = model.joints[which[i[k]]].name, model.joints[which[j[k]]].name
    _warn(
        f"{source}: joint lines of {a!r} and {b!r} lie on each other ({hit.size} pair(s), "
        f"for example over {shared[k]:.3g} from ({lines[i[k], 0, 0]:g}, {lines[i[k], 0, 1]:g})):"
        " a contact there takes one of the two joints; remove one of them, or move one "
        "joint set's origin"
    )


def _warn(text: str) -> None:
    """Issue a :class:`ModelWarning` (at the caller of ``load_model``)."""
    warnings.warn(ModelWarning(text), stacklevel=5)


_BLOCK = re.compile(r"^blocks? (-?\d+)")


def _from_engine(
    exc: InputError,
    cfg: ModelFile,
    ids: dict[int, int],
    names: dict[str, Loc],
    source: str,
    nodes: Any,
) -> ModelFileError:
    """Map an engine InputError back to the key path of the file."""
    where = exc.where
    loc: Loc = ()
    m = _BLOCK.match(where)
    j = re.match(r"joint '(.+)' (\w+)$", where)
    js = re.match(r"joint set '(.+?)'(?: (\w+))?$", where)
    jl = re.match(r"joint_lines (\d+)$", where)
    rr = re.match(r"remove\.regions (\d+)$", where)
    gs = re.match(r"generate_slope (\w+)$", where)  # an argument: the slope's key
    pr = re.match(r"Profile\.simple (\w+)$", where)  # a key of slope.profile
    bk = re.match(r"(bolts .+) (\w+)$", where)
    if gs and cfg.slope is not None:
        loc, label = ("slope", gs.group(1)), ""
    elif pr and cfg.slope is not None:
        loc, label = ("slope", "profile", pr.group(1)), ""
    elif where == "remove.profile":
        loc, label = ("remove", "profile"), ""
    elif bk and bk.group(1) in names:  # a key of a bolt: "bolts NAME spacing"
        loc, label = (*names[bk.group(1)], bk.group(2)), ""
        if loc[0] == "geometry":  # one of the drawing's: which
            label = bk.group(1).removeprefix("bolts ") + ":"
    elif j and j.group(1) in cfg.joints:
        loc, label = ("joints", j.group(1), j.group(2)), ""
    elif js and cfg.slope is not None and js.group(1) in cfg.slope.joint_sets:
        loc = ("slope", "joint_sets", js.group(1)) + ((js.group(2),) if js.group(2) else ())
        label = ""
    elif jl:
        loc, label = ("joint_lines", int(jl.group(1))), ""
    elif rr:
        loc, label = ("remove", "regions", int(rr.group(1))), ""
    elif cfg.blocks is not None and where.startswith("blocks ") and "," in where:
        loc, label = ("blocks",), where
    elif cfg.blocks is not None and m and int(m.group(1)) in ids:
        loc = ("blocks", ids[int(m.group(1))])
        label = where
    elif where in names:
        loc, label = names[where], ""
        if loc[0] == "geometry":  # a bolt of the drawing: which
            label = where.removeprefix("bolts ") + ":"
    elif where in (  # found by fuzzing
        "loads water_table",
        "loads water_unit_weight",
        "loads pore_pressure_ratio",
    ):
        loc, label = ("loads", where.split()[1]), ""  # (was blamed on `slope`)
    elif cfg.slope is not None:
        loc, label = ("slope",), ("" if where == "slope" else where)
    else:
        label = where
    problem = f"{label} {exc.problem}".strip() if label else exc.problem
    fix = exc.fix
    removes = cfg.remove.blocks or cfg.remove.regions or cfg.remove.profile is not None
    if removes and any(w in exc.problem for w in _MISSED):
        # the rock it acted on may be what `remove` took (found by hostile testing)
        fix = f"{fix}; or, if it acted on rock that `remove` takes out, move it or keep that rock"
    return ModelFileError(source, _keypath(loc), problem, fix, _line(nodes, loc))


#: what a load or support that misses every block is told
_MISSED = ("does not act on any block", "does not lie on block boundaries")
