"""A structure of the user's own: mass and stiffness matrices from an FE code, or modal data.

Beam 1 may be any linear, clamped structure touched at one or several translational DOFs (its
contact DOFs) and driven by the harmonic force at one DOF (its force DOF, by default the
contact DOF at the tip). Each contact DOF has a position (m), which a contact names as it names
a point of a beam (``Contact(position1=...)``, ``contact_position1``); the force DOF is the
structure's tip, at ``length``, where a contact given no position acts. The engine needs of it
what it needs of a cantilever (`impactbeams.modes.UserBeam`): the lowest natural frequencies
with each mass-normalised mode's value at these points, the participation factors of a support
motion, the static flexibility between the points (the beam's Green's function at them) and
the kinetic norm of the static tip-load shape.

* `MatrixStructure` (M, K, dense or scipy.sparse): the modes from the symmetric problem
  ``K phi = omega^2 M phi`` solved through the flexibility, so that the low modes keep their
  digits on fine meshes (eigh(K, M) loses a relative eps (omega_max / omega_1)^2 on them):
  dense, with K = L L^T, the largest eigenvalues 1 / omega^2 of ``L^-1 M L^-T``; sparse, by
  shift-invert Lanczos about 0 (``eigsh(K, M=M, sigma=0)``). The static flexibility between
  the points is solved from K itself (``K u = e_c``, one solve per point), not summed over
  truncated modes.
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
# |(Phi^T C Phi)_mn| allowed relative to sqrt(d_m d_n), d the diagonal: the engine damps each
# mode on its own (diag(2 zeta_n omega_n)) and drops the rest, which changes the modes'
# damping forces by at most that fraction. Rayleigh damping's projection onto the computed
# modes is diagonal to round-off: measured 8e-13 (the tests' 40-element FE cantilever, dense,
# all 80 modes) and 2e-11 (200 elements, sparse shift-invert): five decades below
_MODAL_COUPLING = 1e-6


@dataclasses.dataclass(frozen=True)
class UserModes:
    """The lowest modes of a user structure (SI units).

    ``frequencies`` (rad/s, ascending); ``values``: each mass-normalised mode's value at each
    point of the structure (its contact DOFs and its force DOF; kg^-1/2), one column per point
    at ``positions`` (m); ``tip_values``: the column of the tip (the force DOF), each >= 0;
    ``gamma``: participation factors phi_n^T M r of the support motion (kg^1/2), zero if the
    structure has no influence vector (`Params` then refuses a shaker that moves it);
    ``damping_ratios``: each mode's own damping ratio zeta_n, None if the structure has no
    damping of its own (the run's ``damping_ratio`` then damps every mode).
    """

    frequencies: np.ndarray
    values: np.ndarray
    positions: tuple[float, ...]
    tip_values: np.ndarray
    gamma: np.ndarray
    name: str
    damping_ratios: np.ndarray | None = None

    def tip(self, derivative: int = 0) -> np.ndarray:
        """Each mode's value at the tip, the force DOF (``derivative`` 0: a DOF has no slope)."""
        _require_value(self.name, derivative)
        return self.tip_values

    def __call__(self, x: np.ndarray, derivative: int = 0) -> np.ndarray:
        """Each mode's value at the points at positions ``x`` (m), shape (modes, len(x))."""
        _require_value(self.name, derivative)
        columns = [_point_index(self.name, self.positions, float(at)) for at in np.atleast_1d(x)]
        return self.values[:, columns]

    def participation(self) -> np.ndarray:
        """Gamma_n (kg^1/2)."""
        return self.gamma


def _require_value(name: str, derivative: int) -> None:
    require("derivative", derivative, derivative == 0,
            f"{name} is a user structure: only its values at its contact and force DOFs are "
            "known")


def _point_index(owner: str, positions: tuple[float, ...], x: float,
                 name: str = "position") -> int:
    """The index of the point at position ``x`` (m), or ParameterError naming the positions."""
    require(name, x, x in positions,
            f"{owner} is touched only at its contact DOFs and its force DOF, at positions "
            f"{', '.join(map(repr, positions))} (m)")
    return positions.index(x)


class _UserStructure:
    """What both kinds share: the checks of the engine's requests and its points.

    Each kind sets ``point_positions`` (m, one per point: its contact DOFs, then its force DOF
    if it is none of them, at ``length``), ``tip_index`` (the force DOF's point) and
    ``point_flexibility`` (m/N, the static flexibility between the points, symmetric) and
    ``ratios`` (its given modal damping ratios, or None); a matrix structure its ``damping``.
    """

    name: str
    length: float
    point_positions: tuple[float, ...]
    tip_index: int
    point_flexibility: np.ndarray
    ratios: np.ndarray | None
    damping: Any = None  # modal data has no damping matrix

    def require_support(self, base_amplitude: Any) -> None:
        """ParameterError if ``base_amplitude`` (m) > 0 anywhere and it has no influence vector."""
        require("base_amplitude", base_amplitude, self.moves_with_support or bool(
            np.all(np.asarray(base_amplitude) == 0.0)), f"{self.name} has no influence vector "
            "(participation factors): a shaker cannot move it; give one, or a shaker that "
            "leaves beam 1's clamp")

    def require_run_damping(self, damping_ratio: Any) -> None:
        """ParameterError if ``damping_ratio`` is > 0 anywhere and it has damping of its own.

        Each mode has one damping: its own or the run's ratio (`FreePhase.damping_ratios`).
        """
        largest = float(np.max(damping_ratio))
        require("damping_ratio", largest, largest == 0.0 or not self.has_damping,
                f"{self.name} has damping of its own (its damping matrix or ratios): leave "
                "damping_ratio out (0), or give the structure no damping")

    def require_position(self, name: str, x: float) -> None:
        """ParameterError naming ``name`` unless ``x`` (m) is one of its points' positions."""
        _point_index(self.name, self.point_positions, x, name)

    @property
    def several_points(self) -> bool:
        """Whether it has points other than its tip (contact DOFs apart from the force DOF)."""
        return len(self.point_positions) > 1

    def flexibility(self, x: Any, y: Any) -> np.ndarray:
        """Deflection at the points at ``x`` under unit forces at the points at ``y`` (m/N).

        Shape (len(x), len(y)); positions in m, each one of its points'.
        """
        rows = [_point_index(self.name, self.point_positions, float(a))
                for a in np.atleast_1d(x)]
        columns = [_point_index(self.name, self.point_positions, float(b))
                   for b in np.atleast_1d(y)]
        return self.point_flexibility[np.ix_(rows, columns)]

    def unit_tip_shape(self, x: np.ndarray, derivative: int = 0) -> np.ndarray:
        """The static tip-load shape with unit tip deflection at the points at ``x`` (m).

        Its values at the points only: a user structure has no positions between them.
        """
        _require_value(self.name, derivative)
        tip = self.tip_index
        return self.flexibility(x, self.length)[:, 0] / self.point_flexibility[tip, tip]

    @property
    def has_damping(self) -> bool:
        """Whether it has damping of its own (a damping matrix or modal damping ratios)."""
        return self.ratios is not None or self.damping is not None

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
        contact_dof: the index of the translational DOF where a contact acts, 0 <= contact_dof
            < N, or a sequence of such indices, all different (its contact DOFs).
        length: a length scale of the structure (m): deflections are small against it (the
            checks of the clearance and the drives), as a beam's length is. The tip (the
            force DOF) sits at it.
        influence: the DOFs' motion under a unit support motion (None: no shaker), N values;
            1 at the contact DOFs and the force DOF (they move rigidly with the support).
        name: how messages call it (``structure1``); source: where it came from (a file).
        positions: each contact DOF's position (m, 0 < x <= length, all different), which a
            contact names (``Contact(position1=x)``); None: the one contact DOF at ``length``.
        force_dof: the DOF where the harmonic force (``force_amplitude``) acts, the
            structure's tip at ``length``; None: the contact DOF at ``length``. A contact DOF
            other than the force DOF must not sit at ``length``.
        damping: its damping matrix C (N s/m per DOF), N x N, symmetric positive
            semidefinite, dense or scipy.sparse, diagonal in its modes (Rayleigh damping
            alpha M + beta K is): each mode's ratio zeta_n = (Phi^T C Phi)_nn / (2 omega_n).
            None: no damping of its own (the run's ``damping_ratio`` damps every mode).
        damping_ratios: instead of ``damping``, the damping ratio of each of its lowest modes,
            each 0 <= zeta_n < 1; it then has as many modes as ratios (at most N).
    """

    mass: Any
    stiffness: Any
    contact_dof: Any
    length: float
    influence: np.ndarray | None = None
    name: str = "structure1"
    source: str = ""
    positions: Any = None
    force_dof: int | None = None
    damping: Any = None
    damping_ratios: Any = None

    def __post_init__(self) -> None:
        import scipy.sparse

        sparse = scipy.sparse.issparse(self.mass) or scipy.sparse.issparse(self.stiffness)
        M, K = (_matrix(f"{self.name}.{label}", value, sparse)
                for label, value in (("mass", self.mass), ("stiffness", self.stiffness)))
        require(f"{self.name}.stiffness", f"{K.shape[0]} x {K.shape[1]}", K.shape == M.shape,
                f"must have the mass matrix's shape, {M.shape[0]} x {M.shape[1]}")
        size = K.shape[0]
        _check_length(self.name, self.length)
        contact_dofs = _dofs(f"{self.name}.contact_dof", self.contact_dof, size)
        positions = _positions(self.name, self.positions, len(contact_dofs), self.length)
        force_dof = _force_dof(self.name, self.force_dof, contact_dofs, positions, self.length,
                               size)
        dofs, points = _points(contact_dofs, positions, force_dof, self.length)
        influence = _influence(self.name, self.influence, size, dofs)
        factor = (_sparse_factor if sparse else _dense_factor)(f"{self.name}.stiffness", K)
        (_sparse_factor if sparse else _dense_factor)(f"{self.name}.mass", M)
        statics = []
        for dof in dofs:  # K u = e_c, one solve each: the flexibility's columns at the points
            unit = np.zeros(size)
            unit[dof] = 1.0
            statics.append(factor(unit))
        flexibility = np.array([[static[dof] for static in statics] for dof in dofs])
        tip = dofs.index(force_dof)
        compliance = float(flexibility[tip, tip])
        shape = statics[tip] / compliance
        contact = contact_dofs[0] if len(contact_dofs) == 1 else contact_dofs
        C, ratios = _own_damping(self.name, self.damping, self.damping_ratios, size)
        for key, value in (("mass", M), ("stiffness", K), ("contact_dof", contact),
                           ("damping", C), ("ratios", ratios),
                           ("length", float(self.length)), ("influence", influence),
                           ("positions", positions), ("point_positions", points),
                           ("force_dof", force_dof),
                           ("point_dofs", dofs), ("tip_index", tip),
                           ("point_flexibility", (flexibility + flexibility.T) / 2),
                           ("_sparse", sparse),
                           ("digest", _digest(M, K, influence, C, ratios)),
                           ("tip_compliance", compliance),
                           ("static_mass", float(shape @ (M @ shape)))):
            object.__setattr__(self, key, value)

    def __repr__(self) -> str:
        kind = "sparse" if self._sparse else "dense"
        where = f", from {self.source}" if self.source else ""
        points = (f", positions={self.positions!r}, "
                  f"force_dof={self.force_dof}" if self.several_points else "")
        damped = ", damped" if self.has_damping else ""
        return (f"MatrixStructure({self.size} DOFs, {kind}, contact_dof={self.contact_dof}, "
                f"length={self.length!r}{points}{damped}, sha256={self.digest}{where})")

    @property
    def contact_dofs(self) -> tuple[int, ...]:
        """Its contact DOFs, as given."""
        dofs = self.contact_dof
        return dofs if isinstance(dofs, tuple) else (dofs,)

    @property
    def size(self) -> int:
        """N, the number of DOFs."""
        return int(self.stiffness.shape[0])

    @property
    def mode_limit(self) -> int:
        """The most modes it has: N, or as many as its damping ratios if given."""
        return self.size if self.ratios is None else min(self.size, self.ratios.size)

    @property
    def moves_with_support(self) -> bool:
        """Whether a shaker can move it (an influence vector was given)."""
        return self.influence is not None

    def modes(self, n: int) -> UserModes:
        """The ``n`` lowest modes, mass-normalised, each positive at the force DOF."""
        return _matrix_modes(self, self._checked_count(n, self.mode_limit))

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
                f"{self._where()}; its {n} lowest modes by {method}, about "
                f"{memory / 2**20:.3g} MiB")

    def _where(self) -> str:
        """Where it is touched and driven, in words."""
        if not self.several_points:
            return f"contact at DOF {self.contact_dof}"
        contacts = ", ".join(f"{dof} (x = {x!r} m)" for dof, x in zip(
            self.contact_dofs, self.positions, strict=False))
        return f"contacts at DOFs {contacts}, force at DOF {self.force_dof}"


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class ModalStructure(_UserStructure):
    """A linear structure given by its modal data (SI units).

    Args:
        frequencies: its lowest natural frequencies (rad/s), positive, ascending.
        contact_values: each mass-normalised mode's value at the contact DOF (kg^-1/2); with
            several points, one column per point (modes x points): its contact DOFs and its
            force DOF, the point at ``length``.
        tip_compliance: its static flexibility at the contact DOF (m/N), at least the modes'
            share sum(contact_values^2 / frequencies^2); with several points the flexibility
            matrix between them (m/N, points x points), symmetric, positive definite and at
            least the modes' share (what it leaves, the residual, positive semidefinite).
        static_mass: u^T M u (kg) of the static tip-load shape u with unit deflection at the
            tip, the force DOF (the energies of every contact need it: the kinetic energy of
            the quasi-static part).
        length: a length scale (m), as `MatrixStructure`'s; the tip (the force DOF) sits at it.
        participation: phi_n^T M r of a unit support motion (kg^1/2); None: no shaker.
        positions: each point's position (m, 0 < x <= length, all different), one of them
            ``length``, where the force acts; None: the one point, at ``length``.
        damping_ratios: each given mode's damping ratio zeta_n, 0 <= zeta_n < 1; None: no
            damping of its own (the run's ``damping_ratio`` damps every mode).
    """

    frequencies: np.ndarray
    contact_values: np.ndarray
    tip_compliance: Any
    static_mass: float
    length: float
    participation: np.ndarray | None = None
    name: str = "structure1"
    source: str = ""
    positions: Any = None
    damping_ratios: Any = None

    def __post_init__(self) -> None:
        frequencies = _vector(f"{self.name}.frequencies", self.frequencies, None)
        require(f"{self.name}.frequencies", self.frequencies,
                bool(np.all(frequencies > 0)) and bool(np.all(np.diff(frequencies) >= 0)),
                "must be positive and ascending (rad/s)")
        size = frequencies.size
        given = _mode_values(f"{self.name}.contact_values", self.contact_values, size)
        _check_length(self.name, self.length)
        count = given.shape[1]
        positions = _positions(self.name, self.positions, count, self.length)
        require(f"{self.name}.positions", self.positions, self.length in positions,
                f"must hold length = {self.length!r} (m): the tip, where the force acts")
        tip = positions.index(self.length)
        # each mode's sign made positive at the tip, its participation factor's with it
        sign = np.where(given[:, tip] < 0, -1.0, 1.0)
        values = sign[:, None] * given
        gamma = None if self.participation is None else sign * _vector(
            f"{self.name}.participation", self.participation, size)
        flexibility = _point_flexibility(self.name, self.tip_compliance, values, frequencies)
        require(f"{self.name}.static_mass", self.static_mass,
                is_real(self.static_mass) and 0 < self.static_mass < np.inf, "must be > 0 (kg)")
        one = values[:, 0] if count == 1 else values  # the one point's: a vector as given
        ratios = None if self.damping_ratios is None else _ratios(
            f"{self.name}.damping_ratios", self.damping_ratios, size)
        for key, value in (("frequencies", frequencies), ("contact_values", one),
                           ("ratios", ratios),
                           ("participation", gamma),
                           ("tip_compliance", float(flexibility[tip, tip])),
                           ("length", float(self.length)),
                           ("static_mass", float(self.static_mass)), ("positions", positions),
                           ("point_positions", positions),
                           ("tip_index", tip), ("point_flexibility", flexibility),
                           ("_tip_values", np.ascontiguousarray(values[:, tip]))):
            object.__setattr__(self, key, value)
        extra = (*((flexibility, np.array(positions)) if count > 1 else ()),
                 *(() if ratios is None else (ratios,)))
        object.__setattr__(self, "digest", _digest(
            frequencies, one, gamma, np.array([self.tip_compliance, self.length,
                                               self.static_mass]), *extra))

    def __repr__(self) -> str:
        where = f", from {self.source}" if self.source else ""
        points = f", positions={self.positions!r}" if self.several_points else ""
        damped = ", damped" if self.has_damping else ""
        return (f"ModalStructure({self.frequencies.size} modes, length={self.length!r}"
                f"{points}{damped}, sha256={self.digest}{where})")

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
        values = self.contact_values.reshape(self.mode_limit, -1)
        ratios = None if self.ratios is None else self.ratios[:n]
        return UserModes(self.frequencies[:n], values[:n], self.point_positions,
                         self._tip_values[:n], gamma, self.name, ratios)

    def describe(self, n: int) -> str:
        """What it is, in one line."""
        where = (f"the points at {', '.join(map(repr, self.positions))} m" if
                 self.several_points else "the contact DOF")
        return (f"{self.name}: modal data of {self.mode_limit} modes (frequencies, values at "
                f"{where}), {n} used")


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
    tip = phi[structure.force_dof]
    phi = phi * np.where(tip < 0, -1.0, 1.0)
    gamma = np.zeros(n) if structure.influence is None else phi.T @ (M @ structure.influence)
    frequencies = np.sqrt(eigenvalues)
    if structure.damping is not None:
        ratios = _modal_ratios(structure.name, structure.damping, phi, frequencies)
    else:
        ratios = None if structure.ratios is None else structure.ratios[:n]
    return UserModes(frequencies, phi[list(structure.point_dofs)].T, structure.point_positions,
                     np.abs(tip), gamma, structure.name, ratios)


def _modal_ratios(name: str, damping: Any, phi: np.ndarray,
                  frequencies: np.ndarray) -> np.ndarray:
    """zeta_n = (Phi^T C Phi)_nn / (2 omega_n), or refused if C couples the modes."""
    projected = phi.T @ (damping @ phi)
    own = np.diag(projected).copy()
    require(f"{name}.damping", "a matrix with a negative modal damping "
            f"{own.min():.3g}", bool(np.all(own >= 0.0)), "must be positive semidefinite")
    scale = np.sqrt(np.outer(own, own))
    coupling = np.abs(projected - np.diag(own))
    worst = float(np.max(coupling / np.where(scale > 0, scale, 1.0)))
    require(f"{name}.damping", f"a matrix coupling the modes by {worst:.3g}",
            bool(np.all(coupling <= _MODAL_COUPLING * scale)),
            f"must be diagonal in the modes (|(Phi^T C Phi)_mn| <= {_MODAL_COUPLING:g} sqrt("
            "(Phi^T C Phi)_mm (Phi^T C Phi)_nn)): the engine damps each mode on its own; give "
            "Rayleigh damping alpha M + beta K or damping_ratios")
    return _ratios(f"{name}.damping", own / (2.0 * frequencies), frequencies.size,
                   "its modal damping ratios (Phi^T C Phi)_nn / (2 omega_n)")


def _ratios(name: str, value: Any, size: int | None, what: str = "") -> np.ndarray:
    """Modal damping ratios, each 0 <= zeta < 1 (underdamped modes), or refused."""
    ratios = _vector(name, value, size)
    worst = float(ratios.max()) if np.all(ratios >= 0) else float(ratios.min())
    require(name, worst if what == "" else f"{what} up to {worst:.6g}",
            bool(np.all((ratios >= 0) & (ratios < 1))),
            "must satisfy 0 <= zeta_n < 1 (underdamped modes)")
    return ratios


def _own_damping(name: str, damping: Any, ratios: Any, size: int,
                 ) -> tuple[Any, np.ndarray | None]:
    """The damping matrix C (checked) or the modal damping ratios, at most one of them."""
    import scipy.sparse

    require(f"{name}.damping_ratios", "given with damping", damping is None or ratios is None,
            "give either the damping matrix or the modal damping ratios, not both")
    if ratios is not None:
        return None, _ratios(f"{name}.damping_ratios", ratios, None)
    if damping is None:
        return None, None
    C = _matrix(f"{name}.damping", damping, scipy.sparse.issparse(damping))
    require(f"{name}.damping", f"{C.shape[0]} x {C.shape[1]}", C.shape == (size, size),
            f"must have the mass matrix's shape, {size} x {size}")
    diagonal = C.diagonal()
    require(f"{name}.damping", f"a matrix with diagonal entry {diagonal.min():.3g}",
            bool(np.all(diagonal >= 0)), "must be positive semidefinite")
    return C, None


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


def _influence(name: str, influence: Any, size: int, dofs: tuple[int, ...],
               ) -> np.ndarray | None:
    """The influence vector, 1 at each point's DOF ``dofs`` (the contacts' and the force's)."""
    if influence is None:
        return None
    r = _vector(f"{name}.influence", influence, size)
    for dof in dofs:
        require(f"{name}.influence[{dof}]", float(r[dof]), abs(r[dof] - 1.0) <= 1e-12,
                "must be 1: the contact and force DOFs move with the support (the gaps and "
                "the tip are measured from it)")
    return r


def _dofs(name: str, value: Any, size: int) -> tuple[int, ...]:
    """``value``, one DOF index or several, as a tuple of different indices below ``size``."""
    several = isinstance(value, (tuple, list, np.ndarray)) and np.ndim(value) == 1
    dofs = tuple(value) if several else (value,)
    require(name, value, len(dofs) >= 1, "must name at least one DOF")
    for index, dof in enumerate(dofs):
        require(f"{name}[{index}]" if several else name, dof,
                is_integer(dof) and 0 <= dof < size, f"must be a DOF index from 0 to {size - 1}")
    require(name, value, len(set(dofs)) == len(dofs), "must name each DOF once")
    return tuple(int(dof) for dof in dofs)


def _positions(name: str, value: Any, count: int, length: float) -> tuple[float, ...]:
    """Each of ``count`` points' position (m), 0 < x <= length, all different."""
    if value is None:
        require(f"{name}.positions", value, count == 1, f"must give each of the {count} "
                "contact DOFs its position (m), which a contact names")
        return (float(length),)
    positions = _vector(f"{name}.positions", value, count)
    require(f"{name}.positions", value, bool(np.all((positions > 0) & (positions <= length))),
            f"must be > 0 and <= length = {length!r} (m)")
    require(f"{name}.positions", value, np.unique(positions).size == count,
            "must all differ (each names one contact DOF)")
    return tuple(float(x) for x in positions)


def _force_dof(name: str, value: Any, contact_dofs: tuple[int, ...],
               positions: tuple[float, ...], length: float, size: int) -> int:
    """The force DOF: ``value``, or the contact DOF at ``length``; the tip, at ``length``."""
    at_tip = [dof for dof, x in zip(contact_dofs, positions, strict=True) if x == length]
    if value is None:
        require(f"{name}.force_dof", value, bool(at_tip), "must be given: no contact DOF is "
                f"at length = {length!r} (m), the tip, where the force acts by default")
        return at_tip[0]
    require(f"{name}.force_dof", value, is_integer(value) and 0 <= value < size,
            f"must be a DOF index from 0 to {size - 1}")
    require(f"{name}.positions", positions, not at_tip or at_tip == [value],
            f"must not put contact DOF {at_tip[0] if at_tip else ''} at length = {length!r} "
            f"(m): the tip is the force DOF {value}")
    require(f"{name}.positions", positions, value not in contact_dofs or at_tip == [value],
            f"must put the force DOF {value}, a contact DOF, at length = {length!r} (m): the "
            "tip")
    return int(value)


def _points(contact_dofs: tuple[int, ...], positions: tuple[float, ...], force_dof: int,
            length: float) -> tuple[tuple[int, ...], tuple[float, ...]]:
    """The points' DOFs and positions: the contact DOFs, then the force DOF at the tip."""
    if force_dof in contact_dofs:
        return contact_dofs, positions
    return (*contact_dofs, force_dof), (*positions, float(length))


def _mode_values(name: str, value: Any, modes: int) -> np.ndarray:
    """Each mode's values at the points (kg^-1/2): a vector (one point) or modes x points."""
    array = np.asarray(value) if isinstance(value, (np.ndarray, list, tuple)) else None
    if array is None or array.ndim != 2:
        return _vector(name, value, modes)[:, None]
    require(name, f"shape {array.shape}", array.shape[0] == modes and array.shape[1] >= 1
            and np.issubdtype(array.dtype, np.number) and np.isrealobj(array),
            f"must be a real vector of {modes} values or a real matrix of {modes} rows (one "
            "column per point)")
    array = np.asarray(array, dtype=float)
    require(name, "a matrix with NaN or inf", bool(np.all(np.isfinite(array))),
            "every value must be finite")
    return array


def _point_flexibility(name: str, value: Any, values: np.ndarray,
                       frequencies: np.ndarray) -> np.ndarray:
    """The static flexibility between the points (m/N), checked against the modes' share."""
    label = f"{name}.tip_compliance"
    if values.shape[1] == 1:
        modal = float(np.sum(values[:, 0]**2 / frequencies**2))
        require(label, value, is_real(value) and np.isfinite(value)
                and value >= modal * (1 - 1e-12),
                f"must be at least the modes' flexibility sum(contact_values^2 / "
                f"frequencies^2) = {modal:.6g} m/N (the static flexibility holds every mode)")
        return np.array([[float(value)]])
    count = values.shape[1]
    matrix = _matrix(label, value, sparse=False)
    require(label, f"shape {matrix.shape}", matrix.shape == (count, count),
            f"must be {count} x {count}: the flexibility between the {count} points")
    modal = (values / frequencies[:, None]**2).T @ values
    scale = abs(matrix).max()
    residual = np.linalg.eigvalsh(matrix - modal).min()
    require(label, f"a matrix whose residual over the modes has eigenvalue {residual:.3g}",
            residual >= -1e-12 * scale and np.linalg.eigvalsh(matrix).min() > 0, "must be "
            "positive definite and at least the modes' flexibility (values^T diag(1 / "
            "frequencies^2) values): the static flexibility holds every mode")
    return matrix


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


# the arrays a .npz file may hold: a matrix structure or modal data (optional ones marked;
# its own damping: a damping matrix or modal damping ratios, at most one)
# (several contact DOFs: ``contact_dof`` a vector with ``positions``; modal data at several
# points: ``contact_values`` modes x points, ``tip_compliance`` points x points, ``positions``)
NPZ_NAMES = {
    MatrixStructure: {"mass": True, "stiffness": True, "contact_dof": True, "length": True,
                      "influence": False, "positions": False, "force_dof": False,
                      "damping": False, "damping_ratios": False},
    ModalStructure: {"frequencies": True, "contact_values": True, "tip_compliance": True,
                     "static_mass": True, "length": True, "participation": False,
                     "positions": False, "damping_ratios": False},
}
_SCALARS = ("contact_dof", "length", "tip_compliance", "static_mass", "force_dof")


def read_structure(path: str | Path, name: str = "structure1") -> MatrixStructure | ModalStructure:
    """The structure in the ``.npz`` file ``path``: the arrays of `NPZ_NAMES`.

    A sparse ``mass``, ``stiffness`` or ``damping`` is given by ``<matrix>_rows``, ``_cols``,
    ``_values`` (COO triplets) and ``size`` (N).
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
    if isinstance(values.get("contact_dof"), np.ndarray):  # several contact DOFs
        values["contact_dof"] = tuple(values["contact_dof"].tolist())
    return kind(**values, name=name, source=str(path))


def _assembled(arrays: dict[str, np.ndarray], name: str, path: Path) -> dict[str, Any]:
    """Sparse matrices given as row, column, value triplets, assembled (sizes from ``size``)."""
    import scipy.sparse

    for matrix in ("mass", "stiffness", "damping"):
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
