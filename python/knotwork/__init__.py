"""knotwork: isogeometric Poisson solves, convergence and adaptive studies from Python.

A case is a case-file path (TOML or JSON, as for the command line) or a dict with the same
keys; it is validated exactly like a file, and bad input raises :class:`InputError` with the
CLI's one-line message. In a dict, the expressions of [problem] may be vectorized numpy
functions f(x, y) (or f(x, y, z)) instead of formulas; a function ``exact`` needs
``exact_gradient`` (a tuple of functions) and ``source`` (docs/PYTHON.md). Every study returns what ``knotwork <command> --json`` prints, as
Python dicts and lists, and the numbers are the CLI's to the last bit.

    import knotwork
    r = knotwork.run("cases/square_sinsin.toml", degree=3, elements=16)
    print(r.dofs, r.l2_error, r.timings["assembly"])
    study = knotwork.converge("cases/square_sinsin.toml", levels=4, degree=2)
    print(study.column("h"), study.column("l2_error"))

Long calls release the GIL (other Python threads run meanwhile), report their phases to an
optional ``progress`` callback (called with one string per phase, e.g. "level 2/4:
assembly"), and stop with KeyboardInterrupt on Ctrl-C at the next phase boundary (a
factorization or a CG solve in progress completes first). Nothing is written to disk unless
``output=`` names a directory.

Threads: like the ``knotwork`` program, the module uses one OpenBLAS thread unless
OPENBLAS_NUM_THREADS is set, and passive OpenMP waiting unless OMP_WAIT_POLICY is set
(docs/PERFORMANCE.md: spinning threads collapse when cores are shared); OMP_NUM_THREADS
sets the number of threads of the assembly.

BLAS kernels: where OpenBLAS takes the CPU for a generic x86-64 one (Debian 12's OpenBLAS on
CPU models newer than it knows) the module names the kernel the CPU's features allow in
OPENBLAS_CORETYPE, as the program does, unless OPENBLAS_CORETYPE is set; if OpenBLAS was
loaded before knotwork (by numpy, say), it can no longer change its kernels, and importing
knotwork warns with the variable to set.
"""

import os as _os
import warnings as _warnings

_os.environ.setdefault("OMP_WAIT_POLICY", "passive")
_user_blas_threads = "OPENBLAS_NUM_THREADS" in _os.environ
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def _openblas_loaded():
    try:
        with open("/proc/self/maps") as maps:
            return "libopenblas" in maps.read()
    except OSError:
        return True  # cannot tell: leave OpenBLAS as it is


def _name_blas_kernel():
    """OpenBLAS reads OPENBLAS_CORETYPE once, when it loads: ask a fresh process which kernel
    it would take and which this CPU allows (solver/blas_kernel.cpp), before it loads here."""
    if "OPENBLAS_CORETYPE" in _os.environ or _openblas_loaded():
        return
    import subprocess
    import sys
    from importlib.util import find_spec
    probe = ("import importlib.util, sys; s = importlib.util.spec_from_file_location('knotwork._core', sys.argv[1]); "
             "m = importlib.util.module_from_spec(s); s.loader.exec_module(m); print(m.better_blas_kernel())")
    try:
        out = subprocess.run([sys.executable, "-c", probe, find_spec("knotwork._core").origin], capture_output=True,
                             text=True, timeout=60, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError, AttributeError):
        return  # OpenBLAS keeps its own choice; the warning below still applies
    if out:
        _os.environ["OPENBLAS_CORETYPE"] = out


_name_blas_kernel()

import numpy as _np  # noqa: E402

from . import _core  # noqa: E402
from ._core import InputError  # noqa: E402

if not _user_blas_threads:
    _core.set_blas_threads(1)
_better_kernel = "" if "OPENBLAS_CORETYPE" in _os.environ else _core.better_blas_kernel()
if _better_kernel:
    _warnings.warn("OpenBLAS runs its generic %s kernels on this CPU, which allows %s (2x faster factorizations): "
                   "set OPENBLAS_CORETYPE=%s before numpy or knotwork is imported"
                   % (_core.blas_kernel(), _better_kernel, _better_kernel), RuntimeWarning, stacklevel=2)

__all__ = ["run", "converge", "adapt", "space", "system", "dimension", "InputError", "Result", "Study", "Space",
           "System"]

InputError.__doc__ = ("Bad input: a case, an option or a file that knotwork refuses. A ValueError; "
                      "str(e) is the one-line message the command line prints.")
Space = _core.Space
Space.__doc__ = """A spline space built from a case (``knotwork.space(case)`` or ``Result.space``).

Attributes: ``num_functions``, ``num_cells``, ``description``, ``family``, ``degree``,
``is_rational``, ``notes``.
Per cell ``c``: ``functions(c)`` (int32 ids of the functions alive on the cell),
``extraction(c)`` (the matrix C with N_active = C B, B the cell's Bernstein polynomials
ordered a + (p+1) b with a along u), ``cell(c)`` (patch, degree, parameter box and the
boundary name of each side, bottom/right/top/left). ``weights()``: one weight per function for
rational spaces (empty otherwise). Arrays are read-only views of the space's own data.
``evaluate_basis(c, uv)``: for the reference points uv ((n, 2), in [0, 1]^2) of cell ``c``,
the ids of its functions (``functions``), their values (n, functions), physical gradients
(n, functions, dim) and the physical points (n, dim).
Checks of ``knotwork basis``: ``partition_of_unity_error()``, ``rank()`` (numerical rank of
all functions' Bezier coefficients; None when too large for the dense check), and
``dimension_check()`` (functions, rank and the family's dimension counts), and ``report()``:
the whole ``knotwork basis --json`` object.
"""



def _dimension_check(self):
    """The dimension counts of ``knotwork basis`` for this space: ``functions`` (how many the
    construction made), ``rank`` (their numerical rank) and the family's own counts where it
    has them (``dimension_bruteforce``, ``dimension_formula`` for knot segments)."""
    report = self.report()
    counts = {"functions": report["functions"], "rank": report["rank"]}
    counts.update({k: v for k, v in report.items() if k.startswith("dimension")})
    return counts


Space.dimension_check = _dimension_check

_DICT_NAME = "<dict>"


def _name(case, name):
    if name is not None:
        return str(name)
    return _DICT_NAME if isinstance(case, dict) else ""


def _overrides(degree, elements, solver, tolerance, ordering, allow_unverified_space, preconditioner=None,
               matrix=None):
    return {"degree": degree, "elements": elements, "solver": solver, "tolerance": tolerance,
            "ordering": ordering, "allow_unverified_space": allow_unverified_space,
            "preconditioner": preconditioner, "matrix": matrix}


class Result:
    """One solve of a case (``knotwork.run``).

    The keys of ``knotwork run --json`` are in :attr:`data`; the common ones are attributes:
    ``dofs``, ``cells``, ``l2_error``, ``h1_seminorm_error``, ``h1_error`` (None without an
    exact solution), ``timings`` (seconds per phase: setup, assembly, analysis,
    factorization, solve, preconditioner, iterations, errors, ...), ``solver`` (method,
    preconditioner, iterations, residuals), ``notes``, ``family``, ``space_description``.
    ``coefficients``: one per basis function (numpy, read-only, no copy). ``space``: the
    :class:`Space` the case was solved on.
    """

    def __init__(self, core):
        self._core = core
        self.data = core.summary()

    def __getattr__(self, key):
        data = self.__dict__.get("data")
        if data is not None and key in data:
            return data[key]
        raise AttributeError(f"knotwork.Result has no attribute {key!r}")

    @property
    def space_description(self):
        return self.data["space"]

    @property
    def coefficients(self):
        return self._core.coefficients

    @property
    def cell_h1_error_squared(self):
        """Squared H1-seminorm error per cell (sums to h1_seminorm_error**2); empty without exact."""
        return self._core.cell_h1_error_squared

    @property
    def space(self):
        return self._core.space

    def sample(self, n=8):
        """The solution on an (n+1) x (n+1) grid of every cell's parameter square.

        Returns a dict of numpy arrays: ``points`` [cell, j, i, dim] (physical points; dim 2,
        or 3 on surfaces), ``solution`` and ``exact`` and ``error`` (= solution - exact)
        [cell, j, i] (``exact``/``error`` None without an exact solution), ``gradient``
        [cell, j, i, dim], and ``triangles`` (two per grid square, indices into the points
        flattened to [cell*(n+1)**2 + j*(n+1) + i]) for matplotlib's ``tripcolor``::

            s = r.sample(8)
            x, y = s["points"][..., 0].ravel(), s["points"][..., 1].ravel()
            plt.tripcolor(x, y, s["solution"].ravel(), triangles=s["triangles"], shading="gouraud")

        ``pcolormesh`` works per cell: ``plt.pcolormesh(P[c, ..., 0], P[c, ..., 1], U[c])``.
        """
        return self._core.sample(int(n))

    def evaluate(self, points, distance=None):
        """u_h and its gradient at physical points.

        points: an (n, 2) array, or (n, 3) on surfaces (one point may be given flat). Each point
        is found in its cell through an R-tree of the cells' boxes, and the geometry map is
        inverted there by Newton's method. On a surface that gives the closest point of the
        surface, which is accepted within ``distance`` of it (default 1e-8 times the surface's
        size). A point on an edge between cells takes the cell with the lowest number.

        Returns a dict of numpy arrays: ``value`` (n), ``gradient`` (n, dim; the surface
        gradient on surfaces), ``cell`` (n), ``reference`` (n, 2: the point in the cell's
        reference square, as in :meth:`Space.evaluate_basis`) and ``distance`` (n; rounding in
        the plane, the distance to a surface). Points outside the domain raise
        :class:`InputError`, which names their indices.
        """
        return self._core.evaluate(points, distance)

    def write_paraview(self, directory):
        """Writes the ParaView files of the case's [output] (solution.vtu, solution_sampled.vtu)
        into ``directory``; returns their paths. All or nothing: a failure leaves no files."""
        return self._core.write_paraview(directory)

    def __repr__(self):
        err = self.data.get("l2_error")
        err = "no exact solution" if err is None else f"L2 error {err:.6e}"
        return f"<knotwork.Result {self.data['family']}: {self.data['space']}, {self.dofs} dofs, {err}>"


class Study(list):
    """The levels of ``knotwork.converge`` or the steps of ``knotwork.adapt``: a list of dicts
    with the keys of the CLI's JSON (``h``, ``dofs``, ``l2_error``, ``h1_seminorm_error``,
    ``l2_rate``, ``h1_rate``, ... per level; ``dofs``, ``estimator``, ``marked``, ... per
    step). The rest of the JSON object (``case``, ``family``, ``space``, ``solver``,
    ``notes``, ``outputs``, ...) is in :attr:`info`. ``column(key)`` gives one key over all
    entries as a float numpy array (NaN where null), ready for plotting.
    """

    def __init__(self, items, info):
        super().__init__(items)
        self.info = info

    def column(self, key):
        if self and key not in self[0]:
            raise KeyError(f"{key!r}: not a key of the study's entries (they have {', '.join(self[0])})")
        return _np.array([_np.nan if e.get(key) is None else e[key] for e in self], dtype=float)

    def __repr__(self):
        return f"<knotwork.Study {self.info.get('family')}: {self.info.get('space')}, {len(self)} entries>"


def run(case, *, degree=None, elements=None, solver=None, tolerance=None, ordering="auto",
        allow_unverified_space=False, output=None, progress=None, name=None, preconditioner=None, matrix=None):
    """Solves a case once, like ``knotwork run``; returns a :class:`Result`.

    case: a case-file path, or a dict in the case-file schema.
    degree, elements: override [space] degree / elements (as --degree, --elements).
    solver: "direct", "iterative", "auto" or "petsc" (as --solver; "petsc" is PETSc's KSP in
    this one process, with [solver] petsc_options); tolerance: the iterative solve's backward
    error, serial or PETSc's (as --tolerance). preconditioner: the iterative solve's
    ("auto", "jacobi", "boomeramg" or the family's own, e.g. "fast_diagonalization" or
    "multigrid" for tensor-product spaces; as --preconditioner). matrix: how CG gets K, "auto",
    "assembled" or "matrix_free" (as --matrix). ordering: CHOLMOD's
    fill-reducing ordering. allow_unverified_space: as --allow-unverified-space.
    output: a directory for the ParaView files (None: nothing is written).
    progress: a callable taking one string per phase.
    name: what a dict case is called in messages (default "<dict>").
    Raises InputError for bad input, KeyboardInterrupt on Ctrl-C.
    """
    return Result(_core.run(case, _name(case, name),
                            _overrides(degree, elements, solver, tolerance, ordering, allow_unverified_space,
                                       preconditioner, matrix),
                            output, progress))


def converge(case, levels=4, *, degree=None, elements=None, solver=None, tolerance=None, ordering="auto",
             output=None, progress=None, name=None, preconditioner=None, matrix=None):
    """A convergence study under uniform refinement, like ``knotwork converge``.

    Returns a :class:`Study` of ``levels`` dicts (the ``levels`` of ``converge --json``).
    The case needs an exact solution. ``output``: a directory for convergence.csv/json/svg
    and the ParaView collection (None: nothing is written). Other arguments as for :func:`run`.
    """
    if isinstance(levels, bool) or not isinstance(levels, int):
        raise InputError(f"levels: must be an integer, got {levels!r}")
    if not 1 <= levels <= 12:
        raise InputError(f"levels: must be in [1, 12], got {levels}")
    j = _core.converge(case, _name(case, name), levels,
                       _overrides(degree, elements, solver, tolerance, ordering, False, preconditioner, matrix), output,
                       progress)
    return Study(j.pop("levels"), j)


def adapt(case, steps=None, *, theta=None, max_dofs=None, marking=None, strategy=None, min_fraction=None, degree=None, elements=None, solver=None,
          tolerance=None, ordering="auto", allow_dependent=False, output=None, output_every=1, progress=None,
          name=None, preconditioner=None, matrix=None):
    """The adaptive loop (estimate, mark, refine locally, solve), like ``knotwork adapt``.

    steps, theta, max_dofs, marking ("cells" or "functions"), strategy ("dorfler" or
    "maximum"), min_fraction (in [0, 1]): override the case's [adapt]
    (None: as the case says). allow_dependent: go on when an LR space is found linearly
    dependent (``--allow-dependent``). Returns a
    :class:`Study` of the steps (the ``steps`` of ``adapt --json``). The case's family must
    refine locally. output_every: with ``output``, the ParaView files of every K-th step and
    of the last (``--output-every``). Other arguments as for :func:`converge`.
    """
    if isinstance(output_every, bool) or not isinstance(output_every, int) or output_every < 1:
        raise InputError(f"output_every: must be an integer >= 1, got {output_every!r}")
    if steps is not None and (isinstance(steps, bool) or not isinstance(steps, int) or not 1 <= steps <= 200):
        raise InputError(f"steps: must be an integer in [1, 200], got {steps!r}")
    if theta is not None and not (isinstance(theta, (int, float)) and 0 < theta <= 1):
        raise InputError(f"theta: must be in (0, 1], got {theta!r}")
    if max_dofs is not None and (isinstance(max_dofs, bool) or not isinstance(max_dofs, int) or max_dofs < 1):
        raise InputError(f"max_dofs: must be a positive integer, got {max_dofs!r}")
    overrides = _overrides(degree, elements, solver, tolerance, ordering, bool(allow_dependent), preconditioner, matrix)
    overrides["marking"] = marking
    overrides["strategy"] = strategy
    overrides["min_fraction"] = min_fraction
    j = _core.adapt(case, _name(case, name), overrides, steps or 0, float(theta or 0), max_dofs or 0, output,
                    output_every, progress)
    return Study(j.pop("steps"), j)


def space(case, *, degree=None, elements=None, progress=None, name=None):
    """The spline space of a case (its [space], refined as the overrides say): a :class:`Space`."""
    return _core.space(case, _name(case, name), _overrides(degree, elements, None, None, "auto", False), progress)


class System:
    """The assembled linear system of a case over all its basis functions (``knotwork.system``),
    before the Dirichlet functions are eliminated.

    Rows and columns are the space's basis functions in its own numbering: the numbering of
    ``Space.functions(cell)`` and of ``Result.coefficients``.

    - ``stiffness``: the form's matrix a(phi_j, phi_i) = (A grad phi_j, grad phi_i) + (c phi_j,
      phi_i), plus Nitsche's boundary terms when the case imposes Dirichlet data weakly;
      ``scipy.sparse.csr_matrix``, whole and symmetric.
    - ``mass``: (phi_j, phi_i), the same way.
    - ``load``: (f, phi_i), the Neumann terms and Nitsche's data terms (numpy).
    - ``dirichlet``: the functions the Dirichlet projection fixes (int32, ascending; empty with
      Nitsche's method and on closed surfaces); ``dirichlet_values``: their projected values.
    - ``free``: the other functions.
    - ``space``: the :class:`Space`.
    - ``zero_mean``: True on a closed surface without a reaction term. The stiffness then has the
      constants in its kernel, and ``run`` removes f's mean and fixes the solution's mean to zero.

    ``solve()`` gives the coefficients ``knotwork.run`` gives on this space (the case's
    [solver]). The same solution from scipy, with the Dirichlet values moved to the right-hand
    side::

        K, F, d, f = s.stiffness, s.load, s.dirichlet, s.free
        u = numpy.zeros(K.shape[0]); u[d] = s.dirichlet_values
        u[f] = scipy.sparse.linalg.spsolve(K[f][:, f].tocsc(), F[f] - K[f][:, d] @ u[d])

    The arrays are read-only views of the system's own data (no copy).
    """

    def __init__(self, core):
        import scipy.sparse  # python3-scipy: only this part of knotwork needs it
        self._core = core
        n = core.num_functions
        self.stiffness = scipy.sparse.csr_matrix(core.stiffness_csr(), shape=(n, n), copy=False)
        self.mass = scipy.sparse.csr_matrix(core.mass_csr(), shape=(n, n), copy=False)

    @property
    def load(self):
        return self._core.load

    @property
    def dirichlet(self):
        return self._core.dirichlet

    @property
    def dirichlet_values(self):
        return self._core.dirichlet_values

    @property
    def free(self):
        keep = _np.ones(self._core.num_functions, dtype=bool)
        keep[self._core.dirichlet] = False
        return _np.flatnonzero(keep).astype(_np.int32)

    @property
    def space(self):
        return self._core.space

    @property
    def zero_mean(self):
        return self._core.zero_mean

    def solve(self, progress=None):
        """The coefficients of the discrete solution, one per basis function, as ``run`` gives them."""
        return self._core.solve(progress)

    def __repr__(self):
        return (f"<knotwork.System {self.stiffness.shape[0]} functions, {self.stiffness.nnz} stiffness entries, "
                f"{len(self.dirichlet)} Dirichlet>")


def system(case, *, degree=None, elements=None, solver=None, tolerance=None, ordering="auto", progress=None,
           name=None, preconditioner=None):
    """The assembled system of a case: a :class:`System` (stiffness, mass, load, Dirichlet data).

    Arguments as for :func:`run`; solver, tolerance and ordering are used by ``System.solve()``.
    """
    return System(_core.system(case, _name(case, name),
                               _overrides(degree, elements, solver, tolerance, ordering, False, preconditioner),
                               progress))


def dimension(tmesh, *, exact=False, name=None):
    """The dimension of a spline space on a T-mesh by brute force, like ``knotwork dimension --json``.

    tmesh: a T-mesh (partition) file, or a dict with its keys (cells or grid + segments,
    degree, smoothness). exact: exact rational rank instead of two primes.
    """
    return _core.dimension(tmesh, _name(tmesh, name) or _DICT_NAME, bool(exact))
