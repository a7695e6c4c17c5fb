"""Sparse LU factorisation: the cost of every Newton iteration.

SciPy's SuperLU (COLAMD ordering) is always available.  When the optional
``pypardiso`` package (Intel MKL PARDISO, ``pip install rockdem[fast]``) is
installed it is used for systems of more than ``PARDISO_FROM`` unknowns:
about 5x faster on 30,000 unknowns, with the same answers to round-off (on
small systems its call overhead makes it slower).
``ROCKDEM_SOLVER=superlu`` forces SuperLU.
"""

from __future__ import annotations

import os

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

try:  # optional accelerator
    import pypardiso as _pypardiso
except ImportError:  # pragma: no cover - depends on the installation
    _pypardiso = None


#: smallest system (unknowns) factorised with PARDISO when it is installed
PARDISO_FROM = 5000


def backend(n: int = PARDISO_FROM + 1) -> str:
    """The factorisation used for ``n`` unknowns: ``"pardiso"`` or ``"superlu"``."""
    forced = os.environ.get("ROCKDEM_SOLVER", "").lower() == "superlu"
    if _pypardiso is not None and not forced and n > PARDISO_FROM:
        return "pardiso"
    return "superlu"


class _Pardiso:
    def __init__(self, A: sp.sparray) -> None:
        self.A = sp.csr_matrix(A)
        self.solver = _pypardiso.PyPardisoSolver(mtype=11)  # real non-symmetric
        self.solver.factorize(self.A)

    def __del__(self) -> None:  # PARDISO keeps its factors until told otherwise
        solver = getattr(self, "solver", None)
        if solver is not None:
            solver.free_memory(everything=True)

    def solve(self, b: np.ndarray) -> np.ndarray:
        x = self.solver.solve(self.A, b)
        if not np.all(np.isfinite(x)):
            raise RuntimeError("factor is singular")
        return x


def factorize(A: sp.sparray):
    """An object with ``solve(b)``; raises RuntimeError if A is singular."""
    if backend(A.shape[0]) == "pardiso":
        return _Pardiso(A)
    return spla.splu(sp.csc_array(A), permc_spec="COLAMD")
