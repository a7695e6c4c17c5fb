"""One error class for everything a user can get wrong.

Bad input is an *error* (raised); a slope that finds no equilibrium is a
*result* (returned, with its evidence).
"""

from __future__ import annotations


class RockdemError(Exception):
    """Base class of every error rockdem raises on purpose."""


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
