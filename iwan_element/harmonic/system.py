"""A linear structure in modal form with Iwan joints on some of its coordinates.

The frequency-domain routes (:mod:`.balance`, :mod:`.continuation`, :mod:`.nlmode`) read one
object, :class:`ModalSystem`: the structure with its joints *stuck* (each joint's stiffness
``KT`` in the linear part), described at a few *ports* (``docs/harmonic_balance.md``
section 1):

* ``n_j`` joint coordinates ``z = T x`` (the slips of the contact points), on which each
  joint acts with its force deficit ``g(z) = F_iwan(z) - KT z`` (zero while stuck);
* ``n_e`` element ports (:class:`ElementPort`): a history-dependent element of the package's
  protocol (``trial``/``commit``/``reset``, e.g. a vibration effect in its modal form) on a
  port coordinate ``y``, the structure loaded by ``-gain F(y, y')`` at it;
* the sensor ``s = S x`` (the displacement a test reads) and the excitation ``e = b^T x``
  (the point and direction of the applied force; its work is ``f de``).

Between ports ``i`` and ``j`` the receptance at circular frequency ``w`` is::

    H_ij(w) = sum_r Y_ir Y_jr / (w_r^2 - w^2 + i w c_r)  +  R_ij,    c_r = 2 zeta_r w_r

over the kept modes ``r`` (mass-normalised, ``Y = [T; S; b^T] Phi``; rigid-body modes have
``w_r = 0`` and are left out at ``w = 0``, where the self-equilibrated joint forces do not
excite them), plus the residual flexibility ``R`` of the modes not kept (static: the
MacNeal / Rubin residual-flexibility correction; exact at ``w = 0`` and in the stuck limit's
statics). A single-degree-of-freedom oscillator with one joint is the smallest such system
(:meth:`ModalSystem.oscillator`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..base.validation import check_scalar, plain_number
from ..core.masing import TOL, constants_from_arrays
from ..core.parameters import IwanParameters
from ..core.periodic import PeriodicForm

__all__ = ["ModalSystem", "ElementPort"]


def _array(name, v, shape):
    a = np.array(v, dtype=float)
    if a.shape != shape or not np.all(np.isfinite(a)):
        raise ValueError(
            f"{name} must be a finite array of shape {shape}, got {getattr(a, 'shape', None)}"
        )
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class ElementPort:
    """A history-dependent element on one port of a :class:`ModalSystem`.

    Parameters
    ----------
    element : object
        An element of the package's protocol (``trial(u, v) -> (F, K)``, ``commit()``,
        ``reset()``, ``dissipated_energy``), driven by the port coordinate ``y`` [port
        units] and its rate. When it states its force in the compiled kernel's terms
        (``periodic_form()`` returning a :class:`~iwan_element.core.periodic.PeriodicForm`,
        as an effect stack around a zero or Jenkins-bank base does) the AFT evaluates that
        form, compiled and with its exact Jacobian (:attr:`form`); otherwise it steps the
        element sample by sample with a finite-difference Jacobian.
    gain : float
        The structure's generalized force at the port is ``-gain F`` (``gain = 1/s^2`` for a
        modal effect read at the sensor, ``y = s q``).
    label : str
    """

    element: object
    gain: float
    label: str = ""
    form: PeriodicForm | None = field(init=False, repr=False)

    def __post_init__(self):
        for m in ("trial", "commit", "reset"):
            if not callable(getattr(self.element, m, None)):
                raise TypeError(
                    f"element must have trial/commit/reset methods (the package's "
                    f"element protocol), missing {m!r}"
                )
        try:
            object.__setattr__(self, "gain", check_scalar("gain", self.gain))
        except ValueError:
            raise ValueError(f"gain must be a finite number, got {self.gain!r}") from None
        declared = getattr(self.element, "periodic_form", None)
        form = declared() if callable(declared) else None
        if form is not None and not isinstance(form, PeriodicForm):
            raise TypeError(
                f"element.periodic_form() must return a PeriodicForm or None, got "
                f"{type(form).__name__}"
            )
        object.__setattr__(self, "form", form)


def _groups(groups, n_j: int) -> tuple:
    """Validated joint groups ``((label, (indices...)), ...)``, each index in ``[0, n_j)``."""
    out = []
    for g in groups:
        try:
            label, idx = g
            idx = tuple(int(i) for i in idx)
        except (TypeError, ValueError):
            raise ValueError(
                f"joint_groups must hold (label, joint indices) pairs, got {g!r}"
            ) from None
        if not idx or min(idx) < 0 or max(idx) >= n_j:
            raise ValueError(
                f"joint_groups: group {label!r} must hold joint indices in [0, {n_j}), got {idx}"
            )
        out.append((str(label), idx))
    return tuple(out)


def _form_batch(forms) -> tuple | None:
    """The joints' forms batched for one evaluation: ``(joints, C, owner, shift, laws)``:
    the joints that carry a form, every Masing row of theirs stacked (``C``) with the index
    among ``joints`` of the one it belongs to (``owner``), each one's shift [N/m], and the
    laws ``(index, law)``; None without forms or when the rows' reversal tolerances differ
    (then each form is evaluated on its own).
    """
    idx = [i for i, f in enumerate(forms) if f is not None]
    if not idx:
        return None
    rows = [forms[i].constants for i in idx]
    C = np.vstack(rows)
    if C.shape[0] and np.any(C[:, TOL] != C[0, TOL]):
        return None
    owner = np.concatenate([np.full(r.shape[0], k) for k, r in enumerate(rows)]).astype(np.int64)
    shift = np.array([forms[i].shift for i in idx])
    laws = tuple((k, law) for k, i in enumerate(idx) for law in forms[i].laws)
    return np.array(idx), C, owner, shift, laws


@dataclass(frozen=True, eq=False)
class ModalSystem:
    """A stuck-joint linear structure in modal form, seen at its ports (module docstring).

    Parameters
    ----------
    omega : array_like, shape (n_m,)
        Kept modes' circular frequencies [rad/s] with the joints stuck (0: rigid body).
    zeta : array_like, shape (n_m,)
        Their linear (floor) damping ratios [-], in ``[0, 1)``.
    modes : array_like, shape (n_z + 2, n_m)
        Mass-normalised mode shapes at the ports: rows ``0..n_j-1`` the joint coordinates
        [m per unit modal coordinate], then the ``n_e`` element ports, then the sensor, then
        the excitation (``n_z = n_j + n_e``).
    joints : sequence of IwanParameters, length n_j
        The joint on each joint coordinate.
    residual : array_like, shape (n_z + 2, n_z + 2), optional
        Residual (static) flexibility between the ports [m/N] of the modes not kept
        (default: none).
    n_full : int, optional
        Coordinates of the model the modes come from (reported).
    notes : str, optional
    ports : sequence of ElementPort, optional
        The element ports (default none).
    joint_groups : sequence of (str, sequence of int), optional
        Named groups of joints (e.g. the contact points around one bolt): the results say
        when a whole group is fully slipped (:func:`~iwan_element.harmonic.result.macroslip_lines`);
        default each joint on its own.
    joint_forms : sequence of PeriodicForm or None, optional
        A force beside each joint on its own coordinate (length ``n_j``, None where there is
        none; default none): e.g. the vibration effects a contact point carries, stated in
        the compiled kernel's terms, evaluated with the joint's exact steady loop and exact
        Jacobian on the same slip (:meth:`.basis.Harmonics.nonlinear_forces`).
    """

    omega: np.ndarray
    zeta: np.ndarray
    modes: np.ndarray
    joints: tuple
    residual: np.ndarray | None = None
    n_full: int | None = None
    notes: str = ""
    ports: tuple = ()
    joint_groups: tuple = ()
    joint_forms: tuple = ()
    constants: np.ndarray = field(init=False, repr=False)
    form_batch: tuple | None = field(init=False, repr=False)

    def __post_init__(self):
        om = np.array(self.omega, dtype=float).ravel()
        if om.size == 0 or not np.all(np.isfinite(om)) or np.any(om < 0):
            raise ValueError("omega must be a non-empty array of finite frequencies >= 0 [rad/s]")
        n_m = om.size
        js = tuple(self.joints)
        if not js or not all(isinstance(j, IwanParameters) for j in js):
            raise ValueError("joints must be a non-empty sequence of IwanParameters")
        ps = tuple(self.ports)
        if not all(isinstance(p, ElementPort) for p in ps):
            raise ValueError("ports must be a sequence of ElementPort")
        n_z = len(js) + len(ps)
        z = _array("zeta", np.ravel(self.zeta), (n_m,))
        if np.any(z < 0) or np.any(z >= 1):
            raise ValueError("zeta must be damping ratios in [0, 1)")
        Y = _array("modes", self.modes, (n_z + 2, n_m))
        R = (
            np.zeros((n_z + 2, n_z + 2))
            if self.residual is None
            else _array("residual", self.residual, (n_z + 2, n_z + 2))
        )
        om.setflags(write=False)
        object.__setattr__(self, "omega", om)
        object.__setattr__(self, "zeta", z)
        object.__setattr__(self, "modes", Y)
        object.__setattr__(self, "joints", js)
        object.__setattr__(self, "ports", ps)
        object.__setattr__(self, "residual", R)
        object.__setattr__(self, "joint_groups", _groups(self.joint_groups, len(js)))
        jf = tuple(self.joint_forms)
        if jf and (
            len(jf) != len(js) or not all(f is None or isinstance(f, PeriodicForm) for f in jf)
        ):
            raise ValueError(
                f"joint_forms must hold a PeriodicForm or None for each of the {len(js)} joints"
            )
        object.__setattr__(self, "joint_forms", jf if any(f is not None for f in jf) else ())
        object.__setattr__(self, "form_batch", _form_batch(self.joint_forms))
        c = constants_from_arrays(
            [j.Fs for j in js], [j.KT for j in js], [j.chi for j in js], [j.beta for j in js]
        )
        c.setflags(write=False)
        object.__setattr__(self, "constants", c)

    @classmethod
    def oscillator(
        cls, mass: float, stiffness: float, damping: float, joint: IwanParameters
    ) -> ModalSystem:
        """``m x'' + c x' + k x + F_iwan(x) = f``: one mass [kg] on a spring [N/m] and a
        dashpot [N s/m] in parallel with one joint; the slip, the sensor and the excitation
        are all ``x``.
        """
        mass, stiffness, damping = (plain_number(v) for v in (mass, stiffness, damping))
        for n, v in (("mass", mass), ("stiffness", stiffness), ("damping", damping)):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0) or (
                n == "mass" and v == 0
            ):
                raise ValueError(f"{n} must be a finite number >= 0 (mass > 0), got {v!r}")
        if not isinstance(joint, IwanParameters):
            raise ValueError(f"joint must be an IwanParameters, got {type(joint).__name__}")
        w = math.sqrt((stiffness + joint.KT) / mass)
        phi = 1.0 / math.sqrt(mass)
        return cls(
            omega=np.array([w]),
            zeta=np.array([damping / (2.0 * mass * w)]),
            modes=np.full((3, 1), phi),
            joints=(joint,),
            n_full=1,
            notes="single-degree-of-freedom oscillator",
        )

    @property
    def n_z(self) -> int:
        """Nonlinear coordinates: the joints, then the element ports."""
        return len(self.joints) + len(self.ports)

    @property
    def KT(self) -> np.ndarray:
        """Each joint's stuck stiffness [N/m]."""
        return self.constants[:, 0]

    def with_ports(self, ports, rows) -> ModalSystem:
        """A copy with element ``ports`` added, ``rows`` (n_e, n_m) their mode shapes (no
        residual flexibility: ports on kept modes).
        """
        rows = np.atleast_2d(np.asarray(rows, float))
        nj = self.n_z
        Y = np.vstack([self.modes[:nj], rows, self.modes[nj:]])
        ne = rows.shape[0]
        R = np.zeros((nj + ne + 2,) * 2)
        keep = list(range(nj)) + [nj + ne, nj + ne + 1]
        R[np.ix_(keep, keep)] = self.residual
        return ModalSystem(
            omega=self.omega,
            zeta=self.zeta,
            modes=Y,
            joints=self.joints,
            residual=R,
            n_full=self.n_full,
            notes=self.notes,
            ports=self.ports + tuple(ports),
            joint_groups=self.joint_groups,
            joint_forms=self.joint_forms,
        )

    def denominators(self, w: float, *, xi: float = 0.0) -> np.ndarray:
        """``w_r^2 - w^2 + i w (2 zeta_r w_r - xi)`` of every kept mode at ``w`` [rad/s];
        ``xi`` [1/s] is a mass-proportional negative damping (the extended periodic motion
        concept's self-excitation, :mod:`.nlmode`).
        """
        om = self.omega
        return om * om - w * w + 1j * w * (2.0 * self.zeta * om - xi)

    def receptance(self, w: float, *, xi: float = 0.0, exclude=None) -> np.ndarray:
        """Port receptance matrix ``H(w)`` [m/N], shape ``(n_z + 2, n_z + 2)`` (module
        docstring); at ``w = 0`` the rigid-body modes are left out. ``exclude``: a kept mode
        index whose term is left out (the nonlinear mode's own fundamental).
        """
        d = self.denominators(w, xi=xi)
        inv = np.zeros_like(d)
        keep = (self.omega > 0) if w == 0.0 else np.ones(d.size, bool)
        if exclude is not None:
            keep[exclude] = False
        inv[keep] = 1.0 / d[keep]
        return (self.modes * inv) @ self.modes.T + self.residual

    def receptance_rate(
        self, w: float, h: int, *, xi: float = 0.0, exclude=None
    ) -> tuple[NDArray[np.complex128], NDArray[np.complex128]]:
        """``(dH/dW, dH/dxi)`` of the receptance at the ``h``-th harmonic ``w = h W`` with
        respect to the fundamental ``W`` [rad/s] and to ``xi``.
        """
        d = self.denominators(h * w, xi=xi)
        keep = np.ones(d.size, bool)
        if exclude is not None:
            keep[exclude] = False
        dd_dW = -2.0 * h * h * w + 1j * h * (2.0 * self.zeta * self.omega - xi)
        dd_dxi = -1j * h * w * np.ones(d.size)
        out = []
        for dd in (dd_dW, dd_dxi):
            g = np.zeros(d.size, complex)
            g[keep] = -dd[keep] / d[keep] ** 2
            out.append((self.modes * g) @ self.modes.T)
        return out[0], out[1]
