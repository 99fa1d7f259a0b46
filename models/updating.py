"""Linear model updating of a specimen: the parameters, their sensitivities and the update.

Finite-element model updating by the sensitivity method (M. I. Friswell, J. E. Mottershead,
*Finite Element Model Updating in Structural Dynamics*, Kluwer 1995; J. E. Mottershead,
M. Link, M. I. Friswell, "The sensitivity method in finite element model updating: a
tutorial", MSSP 25:2275-2296, 2011; docs/linear_update.md), on the specimen's stuck-joint
linear system ``(K = K0 + G^T diag(KT) G, M)`` (the small-amplitude limit, where a test's
low-level data are linear):

* :func:`updatable` lists every linear parameter a specimen has, by group (``"material"``,
  ``"boundary"``, ``"attachments"``, ``"joint"``), with its nominal value, unit and physical
  range (the prior of the update);
* :func:`modal_sensitivities` gives the natural frequencies, the mode shapes at sensor
  positions and the drive-point modal constants with their derivatives by every parameter:
  the matrices' derivatives by central differences of the assembled system (exact to
  round-off where a matrix is linear in the parameter, as it is for all but the contact
  layout), then the eigenvalue derivative ``d lambda = phi^T (dK - lambda dM) phi`` and the
  mode-shape derivative by the expansion over every mode of the (reduced) system
  (Fox and Kapoor 1968), ``d phi_r = sum_{s != r} phi_s phi_s^T (dK - lambda_r dM) phi_r /
  (lambda_r - lambda_s) - (phi_r^T dM phi_r / 2) phi_r``, exact when every mode of the finite
  system is in the sum, as here.

:func:`~iwan_element.models.update.linear_update` runs the update on these.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg as sla

from iwan_element.base.threads import one_blas_thread

from .assembly import axis_rows, linear_system
from .interface import contact_points
from .setups import Clamp, Setup
from .solid import check_specimen

__all__ = ["Updatable", "GROUPS", "updatable", "parameter_value", "with_parameters",
           "ModalState", "modal_state", "modal_sensitivities", "pair_modes", "prior_band"]

GROUPS = ("material", "boundary", "attachments", "joint")
_RIGID_HZ = 0.5          # modes below this are not numbered (rigid-body ones), as QSMA's

#: Default physical ranges, as factors of the nominal value (when the setup gives none).
_FACTORS = {"youngs_modulus": (0.9, 1.1), "density": (0.95, 1.05),
            "stiffness_per_area": (0.1, 10.0), "normal_stiffness_per_area": (0.1, 10.0),
            "clamp.translational": (0.01, 100.0), "clamp.rotational": (0.01, 100.0),
            "shaker.stinger_stiffness": (0.1, 10.0), "shaker.suspension_stiffness": (0.1, 10.0)}
_MASS_RANGE = (0.25, 4.0)           # a mass's range as factors of its nominal
#: Ranges of values given as 0 (a mass or a suspension not known to be there).
_ZERO_RANGES = {"mass": (0.0, 0.05), "shaker.suspension_stiffness": (0.0, 2.0e4)}
_UNITS = {"youngs_modulus": "Pa", "density": "kg/m^3", "stiffness_per_area": "N/m^3",
          "normal_stiffness_per_area": "N/m^3", "clamp.translational": "N/m",
          "clamp.rotational": "N m/rad", "shaker.gauge_mass": "kg", "shaker.moving_mass": "kg",
          "shaker.stinger_stiffness": "N/m", "shaker.suspension_stiffness": "N/m"}


@dataclass(frozen=True)
class Updatable:
    """One updatable linear parameter of a specimen.

    Attributes
    ----------
    name : str
        ``"youngs_modulus"``, ``"density"``, ``"stiffness_per_area"``,
        ``"normal_stiffness_per_area"``, ``"clamp.translational"``, ``"clamp.rotational"``,
        ``"mass:<name>"`` (a setup's point mass), ``"shaker.gauge_mass"``, ...
    group : str
        One of :data:`GROUPS`.
    nominal : float
        The specimen's value [``unit``].
    unit : str
    lower, upper : float
        Physical range [``unit``]: the prior of the update (``[lower, upper]`` is taken as
        the central 95 % of a log-normal prior around the nominal, or of a normal one when
        ``lower`` is 0) and the bounds of the search.
    description : str
    """

    name: str
    group: str
    nominal: float
    unit: str
    lower: float
    upper: float
    description: str = ""

    @property
    def log(self) -> bool:
        """Updated in ``ln p`` (a range away from 0) rather than in ``p``."""
        return self.lower > 0

    def to_dict(self) -> dict:
        return {"name": self.name, "group": self.group, "nominal": self.nominal,
                "unit": self.unit, "lower": self.lower, "upper": self.upper,
                "description": self.description}


def _setup(specimen) -> Setup:
    return specimen.setup


def updatable(specimen, *, ranges: dict | None = None) -> tuple:
    """Every updatable linear parameter of ``specimen`` (module docstring).

    Parameters
    ----------
    specimen : Specimen or SolidSpecimen
    ranges : dict, optional, keyword-only
        ``{name: (lower, upper)}`` overriding the setup's ranges and the defaults.

    Returns
    -------
    tuple of Updatable
        Material (Young's modulus, density), boundary (the setup's clamp springs, when the
        specimen is clamped and the setup declares a :class:`~.setups.Clamp`), attachments
        (each point mass, the shaker's gauge mass, moving mass, stinger and suspension
        stiffness), joint (the tangential stiffness per area of the stuck interface, the
        normal contact stiffness per area).
    """
    check_specimen(specimen)
    st = _setup(specimen)
    given = {**dict(st.ranges), **dict(ranges or {})}
    rows = [("youngs_modulus", "material", specimen.youngs_modulus, "Young's modulus"),
            ("density", "material", specimen.density, "density")]
    if st.clamp is not None and specimen.boundary != "free-free":
        rows += [("clamp.translational", "boundary", st.clamp.translational,
                  "clamp's translational stiffness (axial and transverse)"),
                 ("clamp.rotational", "boundary", st.clamp.rotational,
                  "clamp's rotational stiffness")]
    rows += [(f"mass:{m.name}", "attachments", m.mass, f"point mass at {m.position:.4g} m")
             for m in st.masses]
    if st.shaker is not None:
        sh = st.shaker
        rows += [("shaker.gauge_mass", "attachments", sh.gauge_mass,
                  "mass below the force gauge's sensing element"),
                 ("shaker.moving_mass", "attachments", sh.moving_mass,
                  "shaker's moving mass (armature, stinger, upper gauge)"),
                 ("shaker.stinger_stiffness", "attachments", sh.stinger_stiffness,
                  "stinger's axial stiffness"),
                 ("shaker.suspension_stiffness", "attachments", sh.suspension_stiffness,
                  "armature's suspension")]
    itf = specimen.interface
    rows += [("stiffness_per_area", "joint", itf.stiffness_per_area,
              "tangential stiffness per area of the stuck interface"),
             ("normal_stiffness_per_area", "joint", itf.normal_stiffness_per_area,
              "normal contact stiffness per area")]
    out = []
    for name, group, nom, desc in rows:
        unit = "kg" if name.startswith("mass:") else _UNITS[name]
        if name in given:
            lo, hi = (float(v) for v in given[name])
        elif nom > 0 and unit == "kg":
            lo, hi = nom * _MASS_RANGE[0], nom * _MASS_RANGE[1]
        elif nom > 0:
            lo, hi = nom * _FACTORS[name][0], nom * _FACTORS[name][1]
        else:
            lo, hi = _ZERO_RANGES["mass" if unit == "kg" else name]
        if not (0 <= lo <= nom <= hi and lo < hi):
            raise ValueError(f"the range of {name} must hold its nominal {nom:g} {unit}, "
                             f"got ({lo:g}, {hi:g})")
        out.append(Updatable(name, group, float(nom), unit, lo, hi, desc))
    return tuple(out)


def parameter_value(specimen, name: str) -> float:
    """The value of the updatable parameter ``name`` of ``specimen``."""
    for u in updatable(specimen):
        if u.name == name:
            return u.nominal
    raise ValueError(f"name must be an updatable parameter of {specimen.name!r} "
                     f"({[u.name for u in updatable(specimen)]}), got {name!r}")


def with_parameters(specimen, values: dict):
    """A copy of ``specimen`` with the updatable parameters ``values`` ({name: value}) set
    (the same type: a solid keeps its bodies, scaled for the material)."""
    changes, st = {}, _setup(specimen)
    masses = {m.name: m for m in st.masses}
    sh, cl = st.shaker, st.clamp
    for name, v in values.items():
        v = float(v)
        if name in ("youngs_modulus", "density", "stiffness_per_area",
                    "normal_stiffness_per_area"):
            changes[name] = v
        elif name.startswith("mass:") and name[5:] in masses:
            masses[name[5:]] = replace(masses[name[5:]], mass=v)
        elif name.startswith("shaker.") and sh is not None:
            sh = replace(sh, **{name[7:]: v})
        elif name.startswith("clamp.") and cl is not None:
            cl = Clamp(**{**{"translational": cl.translational, "rotational": cl.rotational},
                          name[6:]: v})
        else:
            raise ValueError(f"values: {name!r} is not an updatable parameter of "
                             f"{specimen.name!r}")
    new_setup = replace(st, masses=tuple(masses.values()), shaker=sh, clamp=cl)
    if new_setup != st:
        changes["setup"] = new_setup
    return specimen.replace(**changes) if changes else specimen


@dataclass(frozen=True, eq=False)
class ModalState:
    """The stuck-joint modes of a specimen with what the targets read.

    Attributes
    ----------
    K, M : ndarray
        Stuck stiffness ``K0 + G^T diag(KT) G`` and mass on the free coordinates.
    lam : ndarray
        Every eigenvalue ``w^2`` [1/s^2], ascending.
    phi : ndarray
        Mass-normalised mode shapes (columns).
    n_rigid : int
        Modes below 0.5 Hz (not numbered).
    S, E : ndarray
        Sensor and excitation rows (the drive-point modal constant is ``(E phi)(S phi)``).
    """

    K: np.ndarray
    M: np.ndarray
    lam: np.ndarray
    phi: np.ndarray
    n_rigid: int
    S: np.ndarray
    E: np.ndarray

    def index(self, mode: int) -> int:
        """Column of elastic mode ``mode`` (1: lowest)."""
        k = self.n_rigid + int(mode) - 1
        if not 1 <= mode or k >= self.lam.size:
            raise ValueError(f"mode must be in [1, {self.lam.size - self.n_rigid}], got {mode}")
        return k

    def frequency(self, k: int) -> float:
        """[Hz] of column ``k``."""
        return math.sqrt(abs(self.lam[k])) / (2 * math.pi)


def _matrices(specimen):
    L = linear_system(specimen)
    pts = contact_points(specimen)
    K = L.K0 + L.G.T @ (pts.KT[:, None] * L.G)
    return 0.5 * (K + K.T), np.asarray(L.M, float), L


def modal_state(specimen) -> ModalState:
    """:class:`ModalState` of ``specimen`` (every mode of its linear system)."""
    K, M, L = _matrices(specimen)
    with one_blas_thread():
        lam, V = sla.eigh(K, M)
    V = V / np.sqrt(np.einsum("ij,ij->j", V, M @ V))[None, :]
    s = np.sign(L.S @ V)
    s[s == 0] = 1.0
    V = V * s[None, :]
    n_rigid = int(np.sum(lam < (2 * math.pi * _RIGID_HZ) ** 2))
    return ModalState(K=K, M=M, lam=lam, phi=V, n_rigid=n_rigid, S=np.asarray(L.S),
                      E=np.asarray(L.E if L.E is not None else L.S))


def _transform(u: Updatable, value: float) -> float:
    return math.log(value) if u.log else value


def _inverse(u: Updatable, theta: float) -> float:
    return math.exp(theta) if u.log else theta


def matrix_derivatives(specimen, params, *, step: float = 1e-4) -> list:
    """``[(dK, dM), ...]``: the stuck stiffness's and the mass's derivatives by each
    parameter's transformed value (``ln p``, or ``p`` for a range from 0), by central
    differences of the assembled system (one-sided where a step would leave the range: a
    mass at 0); module docstring. ``params``: Updatable rows."""
    out = []
    for u in params:
        th = _transform(u, u.nominal)
        h = step if u.log else step * max(u.upper - u.lower, 1e-30)
        hi, lo = th + h, (th - h if u.log or u.nominal - h >= u.lower else th)
        mats = [_matrices(with_parameters(specimen, {u.name: _inverse(u, x)}))[:2]
                for x in (hi, lo)]
        out.append(((mats[0][0] - mats[1][0]) / (hi - lo), (mats[0][1] - mats[1][1]) / (hi - lo)))
    return out


def modal_sensitivities(specimen, modes, params, *, positions=(), state=None) -> dict:
    """Frequencies, shapes at sensors and modal constants of ``modes`` with their
    derivatives by every parameter's transformed value (module docstring).

    Parameters
    ----------
    specimen : Specimen or SolidSpecimen
    modes : dict
        ``{target mode: column}`` of the modal state (which model mode answers each target).
    params : sequence of Updatable
    positions : sequence of float, keyword-only
        Sensor positions [m] along the axis where the shapes are read.
    state : ModalState, optional, keyword-only
        The specimen's (computed if not given).

    Returns
    -------
    dict
        ``f`` {mode: Hz}, ``df`` {mode: (n_params,)}, ``shape`` {mode: (n_pos,)},
        ``dshape`` {mode: (n_pos, n_params)}, ``c`` {mode: 1/kg}, ``dc`` {mode: (n_params,)},
        ``state``.
    """
    st = modal_state(specimen) if state is None else state
    D = matrix_derivatives(specimen, params)
    R = axis_rows(specimen, list(positions)) if len(positions) else np.zeros((0, st.M.shape[0]))
    out = {k: {} for k in ("f", "df", "shape", "dshape", "c", "dc")}
    for r, k in modes.items():
        lam, p = st.lam[k], st.phi[:, k]
        f = math.sqrt(abs(lam)) / (2 * math.pi)
        gap = lam - st.lam
        gap[k] = np.inf
        dl, dphi = np.zeros(len(params)), np.zeros((p.size, len(params)))
        for j, (dK, dM) in enumerate(D):
            A = dK - lam * dM
            dl[j] = p @ A @ p
            coef = (st.phi.T @ (A @ p)) / gap
            dphi[:, j] = st.phi @ coef - 0.5 * (p @ dM @ p) * p
        out["f"][r] = f
        out["df"][r] = dl / (8 * math.pi ** 2 * f)
        out["shape"][r] = R @ p
        out["dshape"][r] = R @ dphi
        se, ee = float(st.S @ p), float(st.E @ p)
        out["c"][r] = se * ee
        out["dc"][r] = (st.S @ dphi) * ee + se * (st.E @ dphi)
    out["state"] = st
    return out


def pair_modes(state: ModalState, reference: ModalState, modes) -> dict:
    """``{mode: column}``: each numbered elastic ``mode`` of ``reference`` followed into
    ``state`` by the largest mass-weighted MAC (modes may change order as parameters move)."""
    out = {}
    cross = np.abs(reference.phi.T @ (state.M @ state.phi))
    for r in modes:
        k_ref = reference.index(r)
        out[r] = int(np.argmax(cross[k_ref]))
    return out


def prior_band(specimen, *, parameters=("attachments", "boundary"), modes=(1, 2),
               n: int = 200, rng=None, quantiles=(0.025, 0.5, 0.975)) -> dict:
    """The natural frequencies the physical ranges of ``parameters`` allow: each parameter
    drawn from its prior (:class:`Updatable`: log-normal, or normal for a range from 0,
    clipped to the range), ``n`` draws, the ``quantiles`` of each mode's stuck frequency.

    Parameters
    ----------
    specimen : Specimen or SolidSpecimen
    parameters : sequence of str, keyword-only
        Groups of :data:`GROUPS` or parameter names (:func:`updatable`).
    modes : sequence of int, keyword-only
        Elastic modes (1: lowest).
    n : int, keyword-only
        Draws (>= 10).
    rng : numpy.random.Generator or int, optional, keyword-only
        The random source (explicit, for a repeatable band).
    quantiles : sequence of float, keyword-only
        In (0, 1).

    Returns
    -------
    dict
        ``{mode: {"nominal": Hz, "quantiles": {q: Hz}}}``.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 10:
        raise ValueError(f"n must be an integer >= 10, got {n!r}")
    names = (parameters,) if isinstance(parameters, str) else tuple(parameters)
    rows = [u for u in updatable(specimen) if u.group in names or u.name in names]
    if not rows:
        raise ValueError(f"parameters name no updatable parameter of {specimen.name!r}: "
                         f"{parameters!r}")
    gen = np.random.default_rng(rng)
    st0 = modal_state(specimen)
    out = {int(r): [] for r in modes}
    for _ in range(int(n)):
        vals = {}
        for u in rows:
            if u.log:
                s = math.log(u.upper / u.lower) / 4.0
                v = math.exp(gen.normal(math.log(u.nominal), s))
            else:
                v = gen.normal(u.nominal, (u.upper - u.lower) / 4.0)
            vals[u.name] = min(max(v, u.lower), u.upper)
        st = modal_state(with_parameters(specimen, vals))
        pairs = pair_modes(st, st0, out)
        for r, k in pairs.items():
            out[r].append(st.frequency(k))
    return {r: {"nominal": st0.frequency(st0.index(r)),
                "quantiles": {float(q): float(np.quantile(v, q)) for q in quantiles}}
            for r, v in out.items()}
