"""A structure of the user's own: mass and stiffness matrices from an FE code, or modal data.

Beam 1 may be any linear, clamped structure touched at one translational DOF (the contact
point, where the tip force acts too). The engine needs of it what it needs of a cantilever
(`impactbeams.modes.UserBeam`): the lowest natural frequencies with each mass-normalised mode's
value at the contact DOF, the participation factors of a support motion, the static flexibility
at the contact DOF and the kinetic norm of the static contact-load shape.

* `MatrixStructure` (M, K, dense or scipy.sparse): the modes from the symmetric problem
  ``K phi = omega^2 M phi`` solved through the flexibility, so that the low modes keep their
  digits on fine meshes (eigh(K, M) loses a relative eps (omega_max / omega_1)^2 on them):
  dense, with K = L L^T, the largest eigenvalues 1 / omega^2 of ``L^-1 M L^-T``; sparse, by
  shift-invert Lanczos about 0 (``eigsh(K, M=M, sigma=0)``). The static flexibility at the
  contact DOF is solved from K itself (``K u = e_c``), not summed over truncated modes.
* `ModalStructure`: the same data given directly.

`read_structure` reads either from a ``.npz`` file (array names in `NPZ_NAMES`). Every input is
checked on construction: one ParameterError naming what is wrong, before any work. SciPy is
imported only when a structure is built (``import impactbeams`` stays light).
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
from pathlib import Path
from typing import Any

import numpy as np

from impactbeams.checks import ParameterError, is_integer, is_real, require

# |K - K^T| allowed, relative to the largest |K|: an FE assembly's round-off, far below it
_SYMMETRY = 1e-12
# a Cholesky pivot below this relative to the largest diagonal entry: K is singular
_SINGULAR = 1e-15


@dataclasses.dataclass(frozen=True)
class UserModes:
    """The lowest modes of a user structure (SI units).

    ``frequencies`` (rad/s, ascending); ``contact``: each mass-normalised mode's value at the
    contact DOF (kg^-1/2, >= 0); ``gamma``: participation factors phi_n^T M r of the support
    motion (kg^1/2), zero if the structure has no influence vector (`Params` then refuses a
    shaker that moves it).
    """

    frequencies: np.ndarray
    contact: np.ndarray
    gamma: np.ndarray
    name: str

    def tip(self, derivative: int = 0) -> np.ndarray:
        """Each mode's value at the contact DOF (``derivative`` 0 only: a DOF has no slope)."""
        require("derivative", derivative, derivative == 0,
                f"{self.name} is a user structure: only its contact DOF's values are known")
        return self.contact

    def participation(self) -> np.ndarray:
        """Gamma_n (kg^1/2)."""
        return self.gamma


class _UserStructure:
    """What both kinds share: the checks of the engine's requests (not a cantilever)."""

    name: str
    length: float

    def require_support(self, base_amplitude: Any) -> None:
        """ParameterError if ``base_amplitude`` (m) > 0 anywhere and it has no influence vector."""
        require("base_amplitude", base_amplitude, self.moves_with_support or bool(
            np.all(np.asarray(base_amplitude) == 0.0)), f"{self.name} has no influence vector "
            "(participation factors): a shaker cannot move it; give one, or a shaker that "
            "leaves beam 1's clamp")

    def unit_tip_shape(self, x: np.ndarray, derivative: int = 0) -> np.ndarray:
        """Refused: a user structure has no positions along a beam."""
        raise ParameterError(f"{self.name} is a user structure (matrices or modal data): "
                             "fields along a beam are not defined for it; leave fields out")

    def _checked_count(self, n: int, available: int) -> int:
        require("n_modes", n, is_integer(n) and 1 <= n <= available,
                f"{self.name} has {available} modes: n_modes must be from 1 to {available}")
        return int(n)


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class MatrixStructure(_UserStructure):
    """A linear structure given by its mass and stiffness matrices (SI units).

    Args:
        mass: M (kg, kg m, kg m^2 per DOF), N x N, symmetric positive definite, dense or
            scipy.sparse.
        stiffness: K (N/m, N/rad, N m/rad per DOF), N x N, symmetric positive definite (the
            structure clamped: no rigid-body mode), dense or scipy.sparse.
        contact_dof: the index of the translational DOF where the contact (and the tip force)
            acts, 0 <= contact_dof < N.
        length: a length scale of the structure (m): deflections are small against it (the
            checks of the clearance and the drives), as a beam's length is.
        influence: the DOFs' motion under a unit support motion (None: no shaker), N values;
            1 at the contact DOF (the contact point moves rigidly with the support).
        name: how messages call it (``structure1``); source: where it came from (a file).
    """

    mass: Any
    stiffness: Any
    contact_dof: int
    length: float
    influence: np.ndarray | None = None
    name: str = "structure1"
    source: str = ""

    def __post_init__(self) -> None:
        import scipy.sparse

        sparse = scipy.sparse.issparse(self.mass) or scipy.sparse.issparse(self.stiffness)
        M, K = (_matrix(f"{self.name}.{label}", value, sparse)
                for label, value in (("mass", self.mass), ("stiffness", self.stiffness)))
        require(f"{self.name}.stiffness", f"{K.shape[0]} x {K.shape[1]}", K.shape == M.shape,
                f"must have the mass matrix's shape, {M.shape[0]} x {M.shape[1]}")
        size = K.shape[0]
        require(f"{self.name}.contact_dof", self.contact_dof,
                is_integer(self.contact_dof) and 0 <= self.contact_dof < size,
                f"must be a DOF index from 0 to {size - 1}")
        _check_length(self.name, self.length)
        influence = _influence(self.name, self.influence, size, self.contact_dof)
        factor = (_sparse_factor if sparse else _dense_factor)(f"{self.name}.stiffness", K)
        (_sparse_factor if sparse else _dense_factor)(f"{self.name}.mass", M)
        unit = np.zeros(size)
        unit[self.contact_dof] = 1.0
        static = factor(unit)  # K u = e_c: the flexibility's column at the contact DOF
        compliance = float(static[self.contact_dof])
        shape = static / compliance
        for key, value in (("mass", M), ("stiffness", K), ("contact_dof", int(self.contact_dof)),
                           ("length", float(self.length)), ("influence", influence),
                           ("_sparse", sparse), ("digest", _digest(M, K, influence)),
                           ("tip_compliance", compliance),
                           ("static_mass", float(shape @ (M @ shape)))):
            object.__setattr__(self, key, value)

    def __repr__(self) -> str:
        kind = "sparse" if self._sparse else "dense"
        where = f", from {self.source}" if self.source else ""
        return (f"MatrixStructure({self.size} DOFs, {kind}, contact_dof={self.contact_dof}, "
                f"length={self.length!r}, sha256={self.digest}{where})")

    @property
    def size(self) -> int:
        """N, the number of DOFs."""
        return int(self.stiffness.shape[0])

    @property
    def mode_limit(self) -> int:
        """The most modes it has: N."""
        return self.size

    @property
    def moves_with_support(self) -> bool:
        """Whether a shaker can move it (an influence vector was given)."""
        return self.influence is not None

    def modes(self, n: int) -> UserModes:
        """The ``n`` lowest modes, mass-normalised, each positive at the contact DOF."""
        return _matrix_modes(self, self._checked_count(n, self.size))

    def describe(self, n: int) -> str:
        """Its eigenproblem's size, method and memory, for ``n`` modes (one line)."""
        if self._sparse and n < self.size - 1:
            stored = sum(a.data.nbytes + a.indices.nbytes + a.indptr.nbytes
                         for a in (self.mass, self.stiffness))
            method = "shift-invert Lanczos about 0 (scipy eigsh, sigma=0)"
            memory = stored + 8 * self.size * (2 * n + 20)  # matrices, Lanczos basis
        else:
            method = "the flexibility's symmetric eigenproblem (K = L L^T, LAPACK eigh)"
            memory = 8 * self.size**2 * 5  # M, K, L, L^-1 M L^-T, its eigenvectors
        return (f"{self.name}: {self.size} DOFs ({'sparse' if self._sparse else 'dense'}), "
                f"contact at DOF {self.contact_dof}; its {n} lowest modes by {method}, "
                f"about {memory / 2**20:.3g} MiB")


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class ModalStructure(_UserStructure):
    """A linear structure given by its modal data (SI units).

    Args:
        frequencies: its lowest natural frequencies (rad/s), positive, ascending.
        contact_values: each mass-normalised mode's value at the contact DOF (kg^-1/2).
        tip_compliance: its static flexibility at the contact DOF (m/N), at least the modes'
            share sum(contact_values^2 / frequencies^2).
        static_mass: u^T M u (kg) of the static contact-load shape u with unit deflection at
            the contact (the energies of every contact need it: the kinetic energy of the
            quasi-static part).
        length: a length scale (m), as `MatrixStructure`'s.
        participation: phi_n^T M r of a unit support motion (kg^1/2); None: no shaker.
    """

    frequencies: np.ndarray
    contact_values: np.ndarray
    tip_compliance: float
    static_mass: float
    length: float
    participation: np.ndarray | None = None
    name: str = "structure1"
    source: str = ""

    def __post_init__(self) -> None:
        frequencies = _vector(f"{self.name}.frequencies", self.frequencies, None)
        require(f"{self.name}.frequencies", self.frequencies,
                bool(np.all(frequencies > 0)) and bool(np.all(np.diff(frequencies) >= 0)),
                "must be positive and ascending (rad/s)")
        size = frequencies.size
        given = _vector(f"{self.name}.contact_values", self.contact_values, size)
        # each mode's sign made positive at the contact, its participation factor's with it
        sign = np.where(given < 0, -1.0, 1.0)
        values = sign * given
        gamma = None if self.participation is None else sign * _vector(
            f"{self.name}.participation", self.participation, size)
        _check_length(self.name, self.length)
        modal = float(np.sum(values**2 / frequencies**2))
        require(f"{self.name}.tip_compliance", self.tip_compliance,
                is_real(self.tip_compliance) and np.isfinite(self.tip_compliance)
                and self.tip_compliance >= modal * (1 - 1e-12),
                f"must be at least the modes' flexibility sum(contact_values^2 / "
                f"frequencies^2) = {modal:.6g} m/N (the static flexibility holds every mode)")
        require(f"{self.name}.static_mass", self.static_mass,
                is_real(self.static_mass) and 0 < self.static_mass < np.inf, "must be > 0 (kg)")
        for key, value in (("frequencies", frequencies), ("contact_values", values),
                           ("participation", gamma), ("tip_compliance",
                                                      float(self.tip_compliance)),
                           ("length", float(self.length)),
                           ("static_mass", float(self.static_mass))):
            object.__setattr__(self, key, value)
        object.__setattr__(self, "digest", _digest(
            frequencies, values, gamma, np.array([self.tip_compliance, self.length,
                                                  self.static_mass])))

    def __repr__(self) -> str:
        where = f", from {self.source}" if self.source else ""
        return (f"ModalStructure({self.frequencies.size} modes, length={self.length!r}, "
                f"sha256={self.digest}{where})")

    @property
    def mode_limit(self) -> int:
        """The number of modes given."""
        return int(self.frequencies.size)

    @property
    def moves_with_support(self) -> bool:
        """Whether a shaker can move it (participation factors were given)."""
        return self.participation is not None

    def modes(self, n: int) -> UserModes:
        """The first ``n`` modes given."""
        n = self._checked_count(n, self.mode_limit)
        gamma = np.zeros(n) if self.participation is None else self.participation[:n]
        return UserModes(self.frequencies[:n], self.contact_values[:n], gamma, self.name)

    def describe(self, n: int) -> str:
        """What it is, in one line."""
        return (f"{self.name}: modal data of {self.mode_limit} modes (frequencies, values at "
                f"the contact DOF), {n} used")


@functools.lru_cache(maxsize=16)
def _matrix_modes(structure: MatrixStructure, n: int) -> UserModes:
    """The ``n`` lowest modes of ``structure`` (once per process and n)."""
    import scipy.linalg
    import scipy.sparse.linalg

    M, K, size = structure.mass, structure.stiffness, structure.size
    if structure._sparse and n < size - 1:
        # shift-invert about 0: eigenvalues nearest 0, to eps relative to the largest of them
        # a fixed start: ARPACK's default is random, and the modes' last bits would follow it
        start = np.random.default_rng(0).standard_normal(size)
        eigenvalues, phi = scipy.sparse.linalg.eigsh(K.tocsc(), k=n, M=M.tocsc(), sigma=0.0,
                                                     which="LM", tol=0.0, v0=start)
        order = np.argsort(eigenvalues)
        eigenvalues, phi = eigenvalues[order], phi[:, order]
    else:
        dense_K = K.toarray() if structure._sparse else K
        dense_M = M.toarray() if structure._sparse else M
        lower = scipy.linalg.cholesky(dense_K, lower=True)
        # L^-1 M L^-T: its largest eigenvalues 1 / omega^2, accurate to eps / omega_1^2
        half = scipy.linalg.solve_triangular(lower, dense_M, lower=True)
        flexibility = scipy.linalg.solve_triangular(lower, half.T, lower=True)
        flexibility = (flexibility + flexibility.T) / 2
        mu, psi = scipy.linalg.eigh(flexibility, subset_by_index=[size - n, size - 1])
        eigenvalues = 1.0 / mu[::-1]
        phi = scipy.linalg.solve_triangular(lower, psi[:, ::-1], lower=True, trans="T")
    if not np.all(eigenvalues > 0):
        raise ParameterError(f"{structure.name}.stiffness is not allowed: it is not positive "
                             f"definite (an eigenvalue {eigenvalues.min():.3g})")
    phi = phi / np.sqrt(np.einsum("in,in->n", phi, M @ phi))
    contact = phi[structure.contact_dof]
    phi = phi * np.where(contact < 0, -1.0, 1.0)
    gamma = np.zeros(n) if structure.influence is None else phi.T @ (M @ structure.influence)
    return UserModes(np.sqrt(eigenvalues), np.abs(contact), gamma, structure.name)


def _digest(*arrays: Any) -> str:
    """The first 12 hex digits of the SHA-256 of ``arrays``' values.

    What a repr (a Dataset's attribute, a sweep's hash) tells two structures apart by.
    """
    digest = hashlib.sha256()
    for array in arrays:
        if array is None:
            continue
        parts = (array.data, array.indices, array.indptr) if hasattr(array, "indptr") else (
            array,)
        for part in parts:
            digest.update(np.ascontiguousarray(part).tobytes())
    return digest.hexdigest()[:12]


def _matrix(name: str, value: Any, sparse: bool) -> Any:
    """``value`` as a real, finite, square, symmetric matrix (CSC if ``sparse``), or refused."""
    import scipy.sparse

    if scipy.sparse.issparse(value):
        matrix = scipy.sparse.csr_matrix(value, dtype=float) if np.isrealobj(value.data) else None
    else:
        array = np.asarray(value) if isinstance(value, (np.ndarray, list, tuple)) else None
        ok = array is not None and np.issubdtype(array.dtype, np.number) and np.isrealobj(array)
        matrix = np.asarray(array, dtype=float) if ok else None
    require(name, type(value).__name__, matrix is not None,
            "must be a real matrix (a NumPy array or scipy.sparse)")
    require(name, f"shape {matrix.shape}", matrix.ndim == 2 and matrix.shape[0] == matrix.shape[1]
            and matrix.shape[0] >= 1, "must be a square matrix, N x N")
    values = matrix.data if scipy.sparse.issparse(matrix) else matrix
    require(name, "a matrix with NaN or inf", bool(np.all(np.isfinite(values))),
            "every entry must be finite")
    asymmetry = abs(matrix - matrix.T).max()
    scale = abs(matrix).max()
    require(name, f"a matrix with max |A - A^T| = {asymmetry:.3g}",
            asymmetry <= _SYMMETRY * scale, f"must be symmetric (to {_SYMMETRY:g} of max |A| = "
            f"{scale:.3g})")
    symmetric = (matrix + matrix.T) / 2  # the same bits where it is symmetric exactly
    if sparse:
        return scipy.sparse.csc_matrix(symmetric)
    return np.ascontiguousarray(symmetric)


def _dense_factor(name: str, matrix: np.ndarray) -> Any:
    """A solver with ``matrix`` by its Cholesky factor, or ParameterError if not SPD."""
    import scipy.linalg

    try:
        factor = scipy.linalg.cho_factor(matrix, lower=True)
    except np.linalg.LinAlgError:
        factor = None
    positive = factor is not None and np.min(np.diag(factor[0])) ** 2 > _SINGULAR * np.max(
        np.diag(matrix))
    require(name, "a matrix", positive, "must be positive definite (a stiffness: not "
            "singular, the structure held against rigid-body motion)")
    return lambda b: scipy.linalg.cho_solve(factor, b)


def _sparse_factor(name: str, matrix: Any) -> Any:
    """A solver with ``matrix`` by a symmetric LU (its pivots' signs are its eigenvalues')."""
    import scipy.sparse.linalg

    try:
        lu = scipy.sparse.linalg.splu(matrix, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                                     options={"SymmetricMode": True})
    except RuntimeError:
        lu = None
    # with symmetric pivots (perm_r = perm_c) U's diagonal has the signs of the eigenvalues
    pivots = None if lu is None else lu.U.diagonal()
    positive = (lu is not None and np.array_equal(lu.perm_r, lu.perm_c)
                and bool(np.all(pivots > _SINGULAR * abs(matrix.diagonal()).max())))
    require(name, "a matrix", positive, "must be positive definite (a stiffness: not "
            "singular, the structure held against rigid-body motion)")
    return lu.solve


def _influence(name: str, influence: Any, size: int, contact_dof: int) -> np.ndarray | None:
    if influence is None:
        return None
    r = _vector(f"{name}.influence", influence, size)
    require(f"{name}.influence[{contact_dof}]", float(r[contact_dof]),
            abs(r[contact_dof] - 1.0) <= 1e-12, "must be 1: the contact DOF moves with the "
            "support (the gap is measured from it)")
    return r


def _vector(name: str, value: Any, size: int | None) -> np.ndarray:
    array = np.asarray(value) if isinstance(value, (np.ndarray, list, tuple)) else None
    ok = (array is not None and array.ndim == 1 and array.size >= 1
          and np.issubdtype(array.dtype, np.number) and np.isrealobj(array)
          and (size is None or array.size == size))
    length = "" if size is None else f" of {size} values"
    require(name, value if array is None or array.size < 5 else f"{array.size} values", ok,
            f"must be a real vector{length}")
    array = np.asarray(array, dtype=float)
    require(name, "a vector with NaN or inf", bool(np.all(np.isfinite(array))),
            "every value must be finite")
    return array


def _check_length(name: str, length: Any) -> None:
    require(f"{name}.length", length, is_real(length) and 0 < length < np.inf,
            "must be > 0 (m): the structure's size, against which deflections are small")


# the arrays a .npz file may hold: a matrix structure or modal data (optional ones marked)
NPZ_NAMES = {
    MatrixStructure: {"mass": True, "stiffness": True, "contact_dof": True, "length": True,
                      "influence": False},
    ModalStructure: {"frequencies": True, "contact_values": True, "tip_compliance": True,
                     "static_mass": True, "length": True, "participation": False},
}
_SCALARS = ("contact_dof", "length", "tip_compliance", "static_mass")


def read_structure(path: str | Path, name: str = "structure1") -> MatrixStructure | ModalStructure:
    """The structure in the ``.npz`` file ``path``: the arrays of `NPZ_NAMES`.

    A sparse ``mass`` or ``stiffness`` is given by ``<matrix>_rows``, ``_cols``, ``_values``
    (COO triplets) and ``size`` (N).
    """
    path = Path(path)
    require(name, str(path), path.suffix == ".npz" and path.is_file(),
            "must name an existing .npz file (matrices or modal data)")
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {key: data[key] for key in data.files}
    except (OSError, ValueError) as error:
        raise ParameterError(f"{name} = {str(path)!r} is not allowed: not a readable .npz "
                             f"file ({error})") from None
    arrays = _assembled(arrays, name, path)
    kind = MatrixStructure if "stiffness" in arrays else ModalStructure
    names = NPZ_NAMES[kind]
    for key in arrays:
        require(f"{name} array {key!r}", str(path), key in names,
                f"{kind.__name__} files hold {', '.join(names)}")
    for key, needed in names.items():
        require(name, str(path), key in arrays or not needed,
                f"the file has no array {key!r} ({kind.__name__} needs it)")
    values = {key: (value.item() if key in _SCALARS and value.ndim == 0 else value)
              for key, value in arrays.items()}
    return kind(**values, name=name, source=str(path))


def _assembled(arrays: dict[str, np.ndarray], name: str, path: Path) -> dict[str, Any]:
    """Sparse matrices given as row, column, value triplets, assembled (sizes from ``size``)."""
    import scipy.sparse

    for matrix in ("mass", "stiffness"):
        parts = [f"{matrix}_{part}" for part in ("rows", "cols", "values")]
        if not any(key in arrays for key in parts):
            continue
        require(name, str(path), all(key in arrays for key in parts) and "size" in arrays,
                f"a sparse {matrix} needs {', '.join(parts)} and size")
        rows, cols, values = (arrays.pop(key) for key in parts)
        size = int(arrays["size"])
        arrays[matrix] = scipy.sparse.coo_matrix((values, (rows, cols)), shape=(size, size))
    arrays.pop("size", None)
    return arrays
