"""The sections that say how to analyse the slope: solver settings, strength
reduction and the stabilisation design."""

# pydantic copies mutable defaults; ruff cannot see that _Section is a BaseModel
# ruff: noqa: RUF012

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, field_validator, model_validator

from ..model import MAX_ITERATIONS, MAX_LOAD_STEPS, TOLERANCE_RANGE
from ..strength_reduction import MAX_TRIALS, trial_bound
from .sections import RemoveSpec
from .values import Direction, Magnitude, Point, _Section, bounded, whole

#: Most stabilisation rounds, and designs and stages.
MAX_ROUNDS = 50
MAX_DESIGNS = 50

Factor = bounded(1e-6, 1e6)


class StrengthReductionSpec(_Section):
    """Settings of the factor of safety by strength reduction (`rockdem fos`)."""

    width: bounded(1e-6, 1.0) = 0.005
    """Stop when the bracket [stable, unstable] is narrower than this."""
    start: Factor = 1.0
    """First trial factor."""
    grow: bounded(1.0, 100.0, open_lo=True) = 1.5
    """Factor between trials while no failure has been found."""
    smallest: Factor = 0.05
    """Give up (strength-independent mechanism) below this factor."""
    largest: Factor = 100.0
    """Give up (no failure) above this factor."""

    def options(self) -> dict[str, float]:
        """The keywords of :func:`rockdem.factor_of_safety` these settings give."""
        return {
            "width": self.width,
            "start": self.start,
            "grow": self.grow,
            "smallest": self.smallest,
            "largest": self.largest,
        }

    @model_validator(mode="after")
    def _order(self) -> StrengthReductionSpec:
        if not self.smallest < self.start < self.largest:
            raise ValueError("needs smallest < start < largest")
        n = trial_bound(self.width, self.start, self.grow, self.smallest, self.largest)
        if n > MAX_TRIALS:
            raise ValueError(
                f"these settings allow up to {n} trials, more than {MAX_TRIALS}: "
                "use a larger `grow` or `width`, or a narrower smallest..largest"
            )
        return self


class AnalysisSpec(_Section):
    """How the equations are integrated and solved."""

    quadrature: Literal["lobatto", "gauss"] = "lobatto"
    """Spring point rule along each interface: lobatto (includes the ends, exact
    pivoting) or gauss (2 points = the seed paper's lumped springs)."""
    points_per_interface: whole(2, 5) = 3
    """Spring points per interface (3 with lobatto is Simpson's rule)."""
    load_steps: whole(1, MAX_LOAD_STEPS) = 5
    """Increments in which the loads are applied (staged gravity)."""
    tolerance: bounded(*TOLERANCE_RANGE, open_hi=True) = 1e-8
    """Equilibrium when the out-of-balance force is below tolerance x the external force."""
    max_iterations: whole(1, MAX_ITERATIONS) = 100
    """Newton iterations per solve before a step is declared failed."""
    reduce_tensile: bool = True
    """Divide the tensile strength by the trial factor in strength reduction too."""
    strength_reduction: StrengthReductionSpec = StrengthReductionSpec()
    """Factor of safety search."""


class TrialSpec(_Section):
    """A stabilisation design to try: a removal from the model as it is."""

    name: str
    """Label of the trial in the report."""
    remove: RemoveSpec
    """What this design removes (blocks, regions and/or a new profile), counted from the
    model as it is (after the top-level `remove`)."""
    stabilise: bool = False
    """Then remove mechanism blocks until the target factor of safety is reached (as
    `rockdem stabilise` does), to see how much more removal the design needs."""

    @field_validator("name")
    @classmethod
    def _named(cls, name: str) -> str:
        # (hostile round 7: `name: ''` was taken, a trial with no label in the report)
        if not name.strip():
            raise ValueError(
                f"the trial has {'an empty' if not name else 'a blank'} name; give it a name "
                "(it labels the trial's row in the report)"
            )
        return name


class SupportSearchSpec(_Section):
    """Where a support force is tried (the force itself is found by search)."""

    at: Point | None = None
    """Point of application on the face `[x, y]` (default: the free surface of the
    critical mechanism, nearest its centroid)."""
    angle: Direction = 195.0
    """Direction of the force on the rock in degrees counter-clockwise from +x (195:
    into the slope, 15 degrees below horizontal, as a down-dipping anchor pulls)."""
    largest: Magnitude | None = None
    """Give up above this force (default: twice the weight of the free rock)."""


class BoltPatternSpec(_Section):
    """A bolt for `rockdem stabilise` to size: rows on the face of the critical
    mechanism at the widest spacing along the slope that reaches the target."""

    capacity: Magnitude
    """Axial yield force of one bolt."""
    axial_stiffness: Magnitude
    """Axial force per unit opening of a crossed joint, one bolt."""
    angle: Direction = 195.0
    """Direction from the head into the rock, degrees counter-clockwise from +x."""
    row_spacing: Magnitude | None = None
    """Distance between rows along the face (default: 4 rows, then 8 and 16)."""
    length: Magnitude | None = None
    """Bolt length (default: through the moving rock plus `anchorage`)."""
    anchorage: Magnitude | None = None
    """Length beyond the moving rock (default: half the depth through it)."""
    bond_strength: Magnitude | None = None
    """Grout bond force per unit length (null: the steel yields first)."""
    kind: Literal["bolt", "cable"] = "bolt"
    """`cable`: no compression and no dowel action."""
    installed: Literal["before_loads", "after_loads"] = "before_loads"
    """When the bolts go in: with the loads, or into the slope standing under
    them (see `bolts[i]`; a slope that fails under its loads needs `before_loads`)."""


class StageSpec(_Section):
    """One excavation stage (bench): what it removes."""

    name: str
    """Label of the stage in the report."""
    remove: RemoveSpec
    """What this stage removes (blocks, regions and/or a new profile)."""

    @field_validator("name")
    @classmethod
    def _named(cls, name: str) -> str:
        # (hostile round 7: `name: ''` was taken, a stage with no label in the report)
        if not name.strip():
            raise ValueError(
                f"the stage has {'an empty' if not name else 'a blank'} name; give it a name "
                "(it labels the stage's row in the report)"
            )
        return name


class StabilisationSpec(_Section):
    """Settings of `rockdem stabilise`: target, designs to compare, excavation stages."""

    target_fos: bounded(0.0, 20.0, open_lo=True) = 1.3
    """Factor of safety the stabilisation must reach."""
    max_rounds: whole(1, MAX_ROUNDS) = 6
    """Block-removal rounds before giving up."""
    max_removal: bounded(0.0, 1.0, open_lo=True) = 0.3
    """Largest share of the free rock (by area) that block removal may take."""
    smallest_set: bool = True
    """Look for a smaller set among the mechanism blocks (from the top down) when
    removing all of them reaches the target."""
    berm: list[Point] | None = Field(default=None, min_length=2)
    """A berm design: the new ground profile `[[x, y], ...]` (left to right), compared
    with the other measures."""
    support: SupportSearchSpec | None = None
    """Where to try a support force (null: on the critical mechanism, angle 195)."""
    bolts: BoltPatternSpec | None = None
    """A bolt to size in a pattern on the critical mechanism's face (null: no bolt row
    in the comparison)."""
    trials: Annotated[list[TrialSpec], Field(max_length=MAX_DESIGNS)] = []
    """Removal designs to rate side by side (each from the model as it is)."""
    stages: Annotated[list[StageSpec], Field(max_length=MAX_DESIGNS)] = []
    """Excavation stages, analysed in order carrying the joint state forward."""
