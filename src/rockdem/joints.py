"""Joint properties: the strength and stiffness of one kind of interface."""

from __future__ import annotations

from dataclasses import dataclass

from .errors import InputError, check_number


@dataclass(frozen=True)
class Joint:
    """Properties of a joint set, a rock bridge, or the contact with the ground.

    Stiffnesses are per unit length of interface per unit displacement
    (for example kN/m^2/m); strengths are stresses (kN/m^2).

    Parameters
    ----------
    normal_stiffness : float
        ``kn``; choose it large against the loads (Chang: its absolute value
        hardly changes the collapse result).
    shear_stiffness : float, optional
        ``ks``; default ``kn / stiffness_ratio``.
    friction_angle : float
        Peak friction angle in degrees, 0 <= phi < 90.
    cohesion : float
        Peak cohesion c >= 0.
    tensile_strength : float
        Tension cut-off >= 0 (0: an open joint carries no tension).
    residual_cohesion : float, optional
        Cohesion after the point has yielded.  Default 0 (brittle, as in
        3DEC's Coulomb joint); set it equal to ``cohesion`` for a ductile joint.
    residual_friction_angle : float, optional
        Friction angle after yield, default ``friction_angle``.
    residual_tensile_strength : float, optional
        Tensile strength after the point has yielded in shear.  Default 0
        (a sheared joint is open to tension); None keeps ``tensile_strength``.
        A point that has failed in tension never carries tension again.
    stiffness_ratio : float
        ``kn / ks`` used when ``shear_stiffness`` is not given (2 to 3 for
        rock: ``2 (1 + nu)``).
    name : str
        Name reported with results (joint set, ``"bridge"``, ``"ground"``).

    Examples
    --------
    >>> Joint(normal_stiffness=1e6, friction_angle=30).shear_stiffness
    400000.0
    """

    normal_stiffness: float
    friction_angle: float
    shear_stiffness: float | None = None
    cohesion: float = 0.0
    tensile_strength: float = 0.0
    residual_cohesion: float | None = 0.0
    residual_friction_angle: float | None = None
    residual_tensile_strength: float | None = 0.0
    stiffness_ratio: float = 2.5
    name: str = "joint"

    def __post_init__(self) -> None:
        where = f"joint {self.name!r}"
        check_number(where, "normal_stiffness", self.normal_stiffness, lo=0.0, open_lo=True)
        check_number(where, "stiffness_ratio", self.stiffness_ratio, lo=0.0, open_lo=True)
        ks_given = self.shear_stiffness is not None
        if not ks_given:
            if not 1e-2 <= self.stiffness_ratio <= 1e2:
                raise InputError(
                    f"{where} stiffness_ratio",
                    f"kn / ks = {self.stiffness_ratio:.3g} is out of range",
                    "use kn / ks between 0.01 and 100 (2 to 3 for rock: 2 (1 + nu))",
                )
            object.__setattr__(
                self, "shear_stiffness", self.normal_stiffness / self.stiffness_ratio
            )
        check_number(where, "shear_stiffness", self.shear_stiffness, lo=0.0, open_lo=True)
        ratio = self.normal_stiffness / self.shear_stiffness
        if not 1e-2 <= ratio <= 1e2:
            key = "shear_stiffness" if ks_given else "stiffness_ratio"
            raise InputError(
                f"{where} {key}",
                f"kn / ks = {ratio:.3g} is out of range",
                "use kn / ks between 0.01 and 100 (2 to 3 for rock: 2 (1 + nu))",
            )
        check_number(where, "friction_angle", self.friction_angle, lo=0.0, hi=90.0)
        check_number(where, "cohesion", self.cohesion, lo=0.0)
        check_number(where, "tensile_strength", self.tensile_strength, lo=0.0)
        if self.residual_cohesion is None:
            object.__setattr__(self, "residual_cohesion", self.cohesion)
        if self.residual_friction_angle is None:
            object.__setattr__(self, "residual_friction_angle", self.friction_angle)
        if self.residual_tensile_strength is None:
            object.__setattr__(self, "residual_tensile_strength", self.tensile_strength)
        check_number(where, "residual_cohesion", self.residual_cohesion, lo=0.0)
        check_number(where, "residual_tensile_strength", self.residual_tensile_strength, lo=0.0)
        check_number(
            where, "residual_friction_angle", self.residual_friction_angle, lo=0.0, hi=90.0
        )
        for residual, peak in (
            ("residual_cohesion", "cohesion"),
            ("residual_friction_angle", "friction_angle"),
            ("residual_tensile_strength", "tensile_strength"),
        ):  # failure never strengthens a joint
            if getattr(self, residual) > getattr(self, peak):
                raise InputError(
                    f"{where} {residual}",
                    f"{getattr(self, residual):g} is above the peak {peak} {getattr(self, peak):g}",
                    f"give at most {getattr(self, peak):g} (null keeps the peak)",
                )

    @property
    def ductile(self) -> Joint:
        """The same joint with its strength kept after shear yield."""
        return _replace(
            self,
            residual_cohesion=self.cohesion,
            residual_friction_angle=self.friction_angle,
            residual_tensile_strength=self.tensile_strength,
        )


def _replace(joint: Joint, **changes) -> Joint:
    from dataclasses import replace

    return replace(joint, **changes)


#: largest ratio of the normal stiffnesses of the joints a model uses.  The
#: collapse result hardly depends on the stiffness where all joints share
#: it, but contrasts change it, and beyond this the solver's verdicts were
#: measured wrong: the toppling example with its column joints 100 times
#: stiffer than the base read FS 0.30 (0.73 with equal stiffnesses), 1,000
#: times stiffer 0.31 "confirmed"; the perpendicular-joints example 0.998
#: and 0.997 at 10 and 100 times (0.911), 0.805 at 1/100.
STIFFNESS_CONTRAST_MAX = 100.0


def check_stiffness_contrast(joints, used) -> float:
    """The ratio of the largest to the smallest normal stiffness among the
    joints ``joints[i]`` for ``i`` in ``used``; an InputError above
    STIFFNESS_CONTRAST_MAX, naming the two joints."""
    used = sorted({int(i) for i in used})
    if not used:
        return 1.0
    kn = {i: joints[i].normal_stiffness for i in used}
    stiff, soft = max(used, key=kn.get), min(used, key=kn.get)
    contrast = kn[stiff] / kn[soft]
    if contrast > STIFFNESS_CONTRAST_MAX:

        def name(i):
            return f"'{joints[i].name}'" if joints[i].name else f"{i}"

        raise InputError(
            f"joint {name(stiff)}",
            f"is {contrast:.3g} times as stiff as joint {name(soft)} (normal stiffness "
            f"{kn[stiff]:g} against {kn[soft]:g}): beyond {STIFFNESS_CONTRAST_MAX:g} times the "
            "factor of safety depends on the contrast and the solver's verdicts are not reliable",
            f"give the joints normal stiffnesses within {STIFFNESS_CONTRAST_MAX:g} times of "
            "each other (the collapse result hardly depends on their common size)",
        )
    return contrast
