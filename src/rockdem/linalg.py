"""Sparse LU factorisation: the cost of every Newton iteration.

Every tangent of one model has the same sparsity pattern, so the work that
depends only on the pattern is done once per model:

* **PARDISO** (Intel MKL, through ``pypardiso``; installed by default where
  MKL wheels exist): a :class:`Factorizer` keeps one PARDISO handle; the
  symbolic analysis (fill-reducing ordering) runs on the first matrix and
  every later tangent is only refactorised numerically (phase 22), then
  solved (phase 33) without the two default steps of iterative refinement
  (each a further solve; 29,000 unknowns: solve 0.027 -> 0.016 s, relative
  residual 1e-12 either way).  The MKL library is located once per process.
* **SuperLU** (SciPy, always available): a fresh LU per matrix with the
  minimum-degree ordering of ``A + A^T`` (the pattern is structurally
  symmetric), which fills in much less than COLAMD here.  Above
  ``PARDISO_FROM`` unknowns diagonal pivots are preferred (threshold
  ``DIAGONAL_PIVOT``, SuperLU's symmetric mode): partial pivoting swaps
  rows away from that ordering, and on a 9,638-block slope (28,914
  unknowns) the factors filled to 159 million entries, 110 s per
  factorisation, against 5.5 million and 0.3-0.4 s with diagonal pivots
  (relative residual 2e-14 either way).  Small systems keep partial
  pivoting: their fill does not matter, and the paths of the toppling
  verification cases were validated with it.

``ROCKDEM_SOLVER=superlu`` forces SuperLU (``pardiso`` insists on PARDISO,
``auto`` or unset: PARDISO where installed; anything else is refused).
:func:`backend` tells which one runs (``rockdem check`` prints it).

**Reproducible runs.**  Threaded PARDISO sums in an order that changes from
run to run (measured: two different elastic solutions, in the last bits,
over six runs of the same 1,021-block model), and the explicit dynamics
that confirms failures is chaotic: those bits can change a verdict.  MKL's
conditional numerical reproducibility (``MKL_CBWR=AUTO``) is therefore set
before MKL loads, unless the user set ``MKL_CBWR``: the same model gives
the same numbers on the same machine with the same number of threads.
"""

from __future__ import annotations

import os

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .errors import InputError

_PYPARDISO: object = False  # not looked for yet; None when not installed

#: MKL reads this when it loads (first PARDISO handle): reproducible results
os.environ.setdefault("MKL_CBWR", "AUTO")


def _mkl_runtime() -> str | None:
    """The path of MKL's ``mkl_rt`` from the installed ``mkl`` package's file
    list, or None.  pypardiso otherwise walks the whole environment for it
    (0.3 s per process, at its import)."""
    import importlib.metadata as metadata

    try:
        files = metadata.files("mkl") or []
    except metadata.PackageNotFoundError:
        return None
    found = sorted((f for f in files if "mkl_rt" in f.name), key=lambda f: len(str(f)))
    for f in found:
        path = f.locate()
        if os.path.isfile(path):
            return os.path.realpath(path)
    return None


def _pardiso_module():
    """pypardiso, imported on first use (0.2 s: not at ``rockdem --version``)."""
    global _PYPARDISO
    if _PYPARDISO is False:
        if "PYPARDISO_MKL_RT" not in os.environ and (mkl_rt := _mkl_runtime()):
            os.environ["PYPARDISO_MKL_RT"] = mkl_rt
        try:  # optional accelerator
            import pypardiso
        except ImportError:  # pragma: no cover - depends on the installation
            pypardiso = None
        _PYPARDISO = pypardiso
    return _PYPARDISO


#: smallest system (unknowns) factorised with PARDISO when it is installed
#: (below it SuperLU's lower call overhead wins)
PARDISO_FROM = 600

_MKL_RT: str | None = None  # the MKL library found by the first PARDISO handle


#: what ``ROCKDEM_SOLVER`` may say ("" or "auto": PARDISO where installed)
SOLVER_CHOICES = ("auto", "pardiso", "superlu")


def _requested_solver() -> str:
    """``ROCKDEM_SOLVER``, checked: an InputError for a value that would
    otherwise be ignored, or "pardiso" where it is not installed."""
    asked = os.environ.get("ROCKDEM_SOLVER", "").strip().lower() or "auto"
    if asked not in SOLVER_CHOICES:
        raise InputError(
            "ROCKDEM_SOLVER",
            f"{asked!r} is not a solver",
            f"set it to one of {', '.join(SOLVER_CHOICES)}, or unset it",
        )
    if asked == "pardiso" and _pardiso_module() is None:
        raise InputError(
            "ROCKDEM_SOLVER",
            "asks for PARDISO, which is not installed here",
            "install it (pip install 'rockdem[fast]') or unset ROCKDEM_SOLVER for SuperLU",
        )
    return asked


def backend(n: int = PARDISO_FROM + 1) -> str:
    """The factorisation used for ``n`` unknowns: ``"pardiso"`` or ``"superlu"``."""
    asked = _requested_solver()
    if n > PARDISO_FROM and asked != "superlu" and _pardiso_module() is not None:
        return "pardiso"
    return "superlu"


def _pardiso_handle():
    """A new PARDISO handle; the library search (slow: a walk of the
    environment when ``mkl_rt`` is not on the loader path) happens once."""
    global _MKL_RT
    if _MKL_RT is not None:
        os.environ.setdefault("PYPARDISO_MKL_RT", _MKL_RT)
    solver = _pardiso_module().PyPardisoSolver(mtype=11)  # real non-symmetric
    _MKL_RT = solver.libmkl._name
    return solver


#: SuperLU takes a diagonal pivot unless it is smaller than this share of
#: the largest entry of its column (stiffness matrices are nearly diagonally
#: dominant; the shifted tangent is too)
DIAGONAL_PIVOT = 0.01


class _SuperLU:
    def __init__(self, A) -> None:
        large = A.shape[0] > PARDISO_FROM
        self.lu = spla.splu(
            sp.csc_array(A),
            permc_spec="MMD_AT_PLUS_A",
            diag_pivot_thresh=DIAGONAL_PIVOT if large else 1.0,
            options={"SymmetricMode": large},
        )

    def solve(self, b: np.ndarray) -> np.ndarray:
        x = self.lu.solve(b)
        if not np.all(np.isfinite(x)):
            raise RuntimeError("factor is singular")
        return x


class _PardisoFactor:
    """The current numeric factor of a :class:`Factorizer`'s PARDISO handle."""

    def __init__(self, owner: Factorizer, generation: int) -> None:
        self.owner, self.generation = owner, generation

    def solve(self, b: np.ndarray) -> np.ndarray:
        if self.generation != self.owner.generation:
            raise RuntimeError("stale factor: the matrix was refactorised since")
        return self.owner._solve(b)


class Factorizer:
    """Factorise a sequence of matrices that share one sparsity pattern.

    ``factorize(A)`` returns an object with ``solve(b)``; with PARDISO the
    object is valid until the next ``factorize`` of the same factorizer
    (one handle, symbolic analysis once, numeric refactorisation after).
    Raises RuntimeError if ``A`` is singular.
    """

    def __init__(self) -> None:
        self.generation = 0
        self.count = 0  # numeric factorisations done
        self._solver = None
        self._csr = None  # CSR matrix whose data is refilled
        self._perm = None  # csr.data = csc.data[perm]
        self._key = None

    def factorize(self, A):
        self.count += 1
        if backend(A.shape[0]) != "pardiso":
            return _SuperLU(A)
        A = sp.csc_array(A)
        key = (A.shape[0], A.nnz, A.indptr.ctypes.data, A.indices.ctypes.data)
        phase = 22
        if self._solver is None or key != self._key:
            pattern = sp.csc_array((np.arange(A.nnz, dtype=float), A.indices, A.indptr), A.shape)
            csr = sp.csr_matrix(pattern)
            csr.sort_indices()
            self._perm = csr.data.astype(np.int64)
            self._csr = csr
            if self._solver is None:
                self._solver = _pardiso_handle()
            self._key = key
            phase = 12  # analysis + numeric factorisation
        self._csr.data = np.ascontiguousarray(A.data[self._perm])
        self._solver.set_phase(phase)
        try:
            self._solver._call_pardiso(self._csr, np.zeros(A.shape[0]))
        except _pardiso_module().pardiso_wrapper.PyPardisoError as exc:
            self._key = None  # analyse again next time
            raise RuntimeError(f"PARDISO: {exc}") from exc
        if phase == 12:  # PARDISO filled iparm with its defaults: keep them, but ...
            self._solver.iparm[0] = 1
            # ... refine the solution iteratively only where pivots were perturbed
            # (the default, 2 steps always, makes each solve cost 3; Newton
            # measures its own residual)
            self._solver.iparm[7] = 0
        self.generation += 1
        return _PardisoFactor(self, self.generation)

    def _solve(self, b: np.ndarray) -> np.ndarray:
        self._solver.set_phase(33)
        x = self._solver._call_pardiso(self._csr, np.asfortranarray(b, dtype=float))
        if not np.all(np.isfinite(x)):
            raise RuntimeError("factor is singular")
        return x

    def __del__(self) -> None:  # PARDISO keeps its factors until told otherwise
        solver = getattr(self, "_solver", None)
        if solver is not None:
            try:
                solver.free_memory(everything=True)
            except Exception:  # pragma: no cover - interpreter shutdown
                pass


def norm(x: np.ndarray) -> float:
    """Euclidean norm without BLAS: ``np.linalg.norm`` goes through a threaded
    BLAS dot that costs ~1.5 ms on 30,000 entries (10 ms on a busy machine,
    where its threads wait for cores); this is ~0.07 ms, called in every
    line-search trial and every relaxation step.  (``np.add.reduce`` is what
    ``np.sum`` calls, without its ~5 us wrapper.)"""
    return float(np.sqrt(np.add.reduce(x * x, axis=None)))
