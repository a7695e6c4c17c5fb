"""Units for labels, read from a model's free-text ``units`` note.

rockdem computes in whatever consistent units the model uses; the file says
which in its ``units`` note ("kN, m, kPa (angles in degrees)", "t, m, t/m^2",
"MN-m-MPa").  :func:`parse_units` reads a force and a length unit out of it
(and a stress unit, or derives force/length^2), so that every force, stress,
area and displacement printed can carry its unit.  A note that names no
system (empty, "SI", "consistent") gives :data:`UNKNOWN`: labels stay bare.

>>> u = parse_units("kN, m, kPa (angles in degrees)")
>>> u.force, u.stress, u.area, u.label("force")
('kN', 'kPa', 'm^2', 'kN')
>>> parse_units("t, m").stress
't/m^2'
"""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["UNKNOWN", "Units", "contradiction", "parse_units"]

#: ("lb" as engineers write it for a pound-force: "lb, ft, psf")
FORCES = ("N", "kN", "MN", "GN", "t", "tf", "kgf", "lbf", "lb", "kip", "kips")
LENGTHS = ("m", "mm", "cm", "km", "ft", "in")
#: stress units named as such (a "force/length^2" token is recognised too)
STRESSES = ("Pa", "kPa", "MPa", "GPa", "psi", "psf", "ksi", "ksf")


@dataclass(frozen=True)
class Units:
    """A force and a length unit, and the stress unit (None when not known)."""

    force: str | None = None
    length: str | None = None
    stress: str | None = None

    @property
    def known(self) -> bool:
        """True when the note named a force and a length unit."""
        return self.force is not None and self.length is not None

    @property
    def area(self) -> str | None:
        return f"{self.length}^2" if self.length else None

    @property
    def displacement(self) -> str | None:
        return self.length

    @property
    def force_per_length(self) -> str | None:
        return f"{self.force}/{self.length}" if self.known else None

    @property
    def unit_weight(self) -> str | None:
        return f"{self.force}/{self.length}^3" if self.known else None

    def unit(self, quantity: str) -> str | None:
        """The unit of ``"force"``, ``"stress"``, ``"area"``, ``"length"``,
        ``"displacement"``, ``"force_per_length"`` or ``"unit_weight"``."""
        return getattr(self, quantity)

    def label(self, quantity: str) -> str:
        """The unit of ``quantity`` or ``""``."""
        return self.unit(quantity) or ""

    def suffix(self, quantity: str, fmt: str = " ({})") -> str:
        """``" (kN)"`` for a heading, ``""`` when the unit is not known."""
        u = self.unit(quantity)
        return fmt.format(u) if u else ""

    def __str__(self) -> str:
        if not self.known:
            return "units not stated"
        return f"{self.force}, {self.length}, {self.stress}"


UNKNOWN = Units()


def _stress_token(tok: str) -> str | None:
    """``"t/m^2"``, ``"t/m2"``, ``"kN/m²"`` ... as ``"force/length^2"``, or a named stress."""
    if tok in STRESSES:
        return tok
    m = re.fullmatch(r"([A-Za-z]+)/([A-Za-z]+)(?:\^?2|²)", tok)
    if m and m.group(1) in FORCES and m.group(2) in LENGTHS:
        return f"{m.group(1)}/{m.group(2)}^2"
    return None


#: forces and lengths in newtons and metres (for the unit weight of water)
_NEWTONS = {"N": 1.0, "kN": 1e3, "MN": 1e6, "GN": 1e9, "t": 9806.65, "tf": 9806.65}
_NEWTONS |= {"kgf": 9.80665, "lbf": 4.4482216, "lb": 4.4482216, "kip": 4448.2216}
_NEWTONS |= {"kips": 4448.2216}
_METRES = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "km": 1e3, "ft": 0.3048, "in": 0.0254}


def water_unit_weight(note: str | None) -> float | None:
    """The unit weight of water in the units a ``units`` note names, to three
    figures (9.81 kN/m^3, 1 t/m^3, 62.4 lbf/ft^3); None when the note names
    no force and length unit."""
    u = parse_units(note)
    if not u.known:
        return None
    value = 9806.65 * _METRES[u.length] ** 3 / _NEWTONS[u.force]
    return float(f"{value:.3g}")


def _tokens(note: str) -> list[str]:
    """The words of a ``units`` note up to its first parenthesis."""
    text = note.split("(", 1)[0]
    return [t for t in re.split(r"[,;\s]+|(?<=[A-Za-z0-9])-(?=[A-Za-z])", text) if t]


def length_of(note: str | None) -> str | None:
    """The length unit a ``units`` note names, with or without a force unit
    (a drawing is converted to it: found by fuzzing, ``units: ft`` and
    ``units: lb, ft, psf`` drawings were read in metres)."""
    lengths = [t for t in _tokens(note or "") if t in LENGTHS]
    if len(lengths) > 1 and lengths[0] == "in":  # "units in kN and m": a word, not inches
        lengths = lengths[1:]
    return lengths[0] if lengths else None


def parse_units(note: str | None) -> Units:
    """The units a model's ``units`` note names.

    The note is read up to its first parenthesis; its tokens are split at
    commas, semicolons, blanks and hyphens.  The first force unit and the
    first length unit make the system; the stress is the first stress token
    ("kPa", "t/m^2"), else force/length^2.  Without both a force and a
    length unit the result is :data:`UNKNOWN`.
    """
    if not note:
        return UNKNOWN
    text = note.split("(", 1)[0]
    tokens = [t for t in re.split(r"[,;\s]+|(?<=[A-Za-z0-9])-(?=[A-Za-z])", text) if t]
    force = next((t for t in tokens if t in FORCES), None)
    lengths = [t for t in tokens if t in LENGTHS]
    if len(lengths) > 1 and lengths[0] == "in":  # "units in kN and m": a word, not inches
        lengths = lengths[1:]
    length = lengths[0] if lengths else None
    stress = next((s for s in map(_stress_token, tokens) if s), None)
    if force is None or length is None:
        return UNKNOWN
    return Units(force, length, stress or f"{force}/{length}^2")


#: SI multiples, to check that a note's stress is its force / length^2
_SI_FORCE = {"N": 1.0, "kN": 1e3, "MN": 1e6, "GN": 1e9}
_SI_LENGTH = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "km": 1e3}
_SI_STRESS = {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9}


def contradiction(note: str | None) -> str | None:
    """What makes a ``units`` note inconsistent (None if nothing): two force or
    two length units, or an SI stress unit that is not force / length^2
    ("kN, m, MPa": the stresses computed from kN and m are kPa, and would be
    labelled MPa).

    >>> contradiction("kN, m, MPa")
    'kN / m^2 is kPa, not MPa'
    >>> contradiction("kN, m, kPa (angles in degrees)") is None
    True
    """
    if not note:
        return None
    text = note.split("(", 1)[0]
    tokens = [t for t in re.split(r"[,;\s]+|(?<=[A-Za-z0-9])-(?=[A-Za-z])", text) if t]
    forces = list(dict.fromkeys(t for t in tokens if t in FORCES))
    lengths = list(dict.fromkeys(t for t in tokens if t in LENGTHS))
    if len(lengths) > 1 and lengths[0] == "in":  # "units in kN and m"
        lengths = lengths[1:]
    if len(forces) > 1:
        return f"names two force units ({forces[0]} and {forces[1]})"
    if len(lengths) > 1:
        return f"names two length units ({lengths[0]} and {lengths[1]})"
    u = parse_units(note)
    if u.known and u.force in _SI_FORCE and u.length in _SI_LENGTH and u.stress in _SI_STRESS:
        ratio = _SI_FORCE[u.force] / _SI_LENGTH[u.length] ** 2
        if not 0.999 < ratio / _SI_STRESS[u.stress] < 1.001:
            same = next((k for k, v in _SI_STRESS.items() if 0.999 < ratio / v < 1.001), None)
            derived = same or f"{ratio:g} Pa"
            return f"{u.force} / {u.length}^2 is {derived}, not {u.stress}"
    return None
