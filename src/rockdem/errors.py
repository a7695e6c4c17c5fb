"""One error class for everything a user can get wrong.

Bad input is an *error* (raised); a slope that finds no equilibrium is a
*result* (returned, with its evidence).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator
from contextlib import contextmanager


class RockdemError(Exception):
    """Base class of every error rockdem raises on purpose."""


class ModelWarning(UserWarning):
    """A model that builds but may not be what was meant (a joint line along
    no contact, a loose equilibrium tolerance): issued with :mod:`warnings`,
    so that Python callers see its category and can filter it; the command
    line prints it as ``warning: ...``."""


@contextmanager
def collecting_model_warnings() -> Iterator[list[str]]:
    """The texts of the ModelWarnings issued inside the block, in a list (for
    a report that must carry them), whatever the filters say about showing
    them; every warning is then issued again outside, for the filters and
    the display the caller has."""
    seen: list[str] = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ModelWarning)
        try:
            yield seen
        finally:
            records = list(caught)
    for w in records:
        if issubclass(w.category, ModelWarning):
            seen.append(" ".join(str(w.message).split()))
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno, source=w.source)


class InputError(RockdemError, ValueError):
    """Bad input: the message names the item at fault and how to fix it.

    Parameters
    ----------
    where : str
        The block, joint, key path or file position at fault
        (for example ``"block 3"`` or ``"joints.bedding.friction_angle"``).
    problem : str
        What is wrong.
    fix : str
        What the user should do about it.
    """

    def __init__(self, where: str, problem: str, fix: str = "") -> None:
        self.where = where
        self.problem = problem
        self.fix = fix
        text = f"{where}: {problem}"
        if fix:
            text += f"; {fix}"
        super().__init__(text)


def check_number(
    where: str,
    key: str,
    value,
    *,
    lo: float | None = None,
    hi: float | None = None,
    open_lo: bool = False,
) -> float:
    """``value`` as a finite float within ``[lo, hi)`` (``(lo, hi)`` if ``open_lo``).

    Raises
    ------
    InputError
        Naming ``where key``, the value and the range to use.
    """
    if isinstance(value, bool | str | bytes) or type(value).__name__ == "bool_":
        # float(True) is 1.0 and float("30") is 30.0: not numbers the user meant
        raise InputError(f"{where} {key}", f"{value!r} is not a number", "give a number")
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where} {key}", f"{value!r} is not a number", "give a number") from exc
    if not math.isfinite(v):
        raise InputError(f"{where} {key}", f"{value} is not finite", "give a finite number")
    if lo is not None and (v < lo or (open_lo and v == lo)):
        rel = ">" if open_lo else ">="
        raise InputError(f"{where} {key}", f"{v:g} is out of range", f"give a value {rel} {lo:g}")
    if hi is not None and v >= hi:
        raise InputError(f"{where} {key}", f"{v:g} is out of range", f"give a value < {hi:g}")
    return v
