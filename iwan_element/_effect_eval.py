"""Fast force evaluation of a stack of effects on the Iwan joint over a fixed displacement history.

Private module used by :mod:`iwan_element.diagnose`. A model is a tuple of effect names,
innermost first (``("viscous_damping", "asymmetric_slip")`` is
``AsymmetricSlip(ViscousDamping(IwanJoint))``). Every model in the library is homogeneous of
degree one in the force scale: with ``Fs = 1`` and the effect parameters scaled to it
(``c/Fs``, ``k_p/Fs``, ``rate Fs``; ``gap``, ``delta``, ``asymmetry`` unchanged) the force is
``Fs`` times the unit force. The unit force is evaluated

* vectorised (exact, via :class:`~iwan_element.core._history.History`) when the stack contains no
  ``backlash`` and no ``asymmetric_slip`` below a ``slip_degradation``. The slip-degradation
  factor needs the dissipated energy of the wrapped element after every committed step; for the
  Iwan joint it is a sum of closed-form terms ``2 (I_H(x_b) - I_H(x_a))`` over branch segments
  whose end points depend only on the displacements (:func:`dissipation_segments` mirrors
  ``IwanJoint._walk`` to find them once);
* otherwise by the effect elements' own ``force_history`` on a drive decimated to the fitted
  samples plus the turning points of the displacement (exact for a drive whose turning points
  are all kept; approximate only for sub-dead-band jitter of a noisy displacement).

Both routes are checked against the elements in ``tests/test_diagnosis.py``.
"""
from __future__ import annotations

import numpy as np

from .core._history import History, unit_params, walk
from .core.closed_form import _slip_energy
from .effects import EFFECTS
from .core.joint import IwanJoint
from .core.parameters import IwanParameters

__all__: list[str] = []

#: Parameters of each effect in the order used by the optimiser.
EFFECT_PARAMS = {name: cls.parameter_names for name, cls in EFFECTS.items()}


def dissipation_segments(u: np.ndarray, tol: float):
    """Branch segments walked by the Iwan joint along ``u`` (the walk of
    :func:`iwan_element.core._history.walk`, which mirrors ``IwanJoint._walk``).

    Returns ``(step, virgin, xa, xb)``: step index of each segment, True for a segment on the
    virgin curve (dissipation ``I_H(xb) - I_H(xa)``, clipped at 0) and False on a branch
    (``2 (I_H(xb) - I_H(xa))``), and the backbone arguments at its ends [m].
    """
    _, (step, anchor, ua, ub) = walk(u, tol, segments=True)
    virgin = anchor < 0
    ur = np.where(virgin, 0.0, u[np.maximum(anchor, 0)])
    scale = np.where(virgin, 1.0, 0.5)
    return step, virgin, scale * np.abs(ua - ur), scale * np.abs(ub - ur)


def scale_effect(name: str, values: dict, Fs: float, *, to_unit: bool) -> dict:
    """Convert effect parameters between physical and unit-``Fs`` form."""
    out = dict(values)
    f = 1.0 / Fs if to_unit else Fs
    if name == "viscous_damping":
        out["c"] = values["c"] * f
    elif name == "pinning_stiffness":
        out["k_p"] = values["k_p"] * f
    elif name == "slip_degradation":
        out["rate"] = values["rate"] / f
    return out


def build_element(params: IwanParameters, names, values):
    """The effect stack ``names`` (innermost first) on ``IwanJoint(params)``."""
    el = IwanJoint(params)
    for name, vals in zip(names, values):
        el = EFFECTS[name](el, **vals)
    return el


class Evaluator:
    """Unit forces of effect stacks on one record at the samples ``keep``.

    Parameters
    ----------
    u, v : ndarray, shape (n,)
        Displacement [m] and velocity [m/s] of the whole record.
    keep : ndarray of int
        Sample indices whose forces are wanted (sorted).
    drive_extra : ndarray of int
        Further samples (turning points) the element route must pass through.
    """

    def __init__(self, u: np.ndarray, v: np.ndarray, keep: np.ndarray, drive_extra: np.ndarray):
        self.u = u
        self.v = v
        self.keep = keep
        tol = 1e-12 * float(np.abs(u).max())
        self.hist = History(u, keep=keep, tol=tol)
        self.x_max = self.hist.x_max
        self._tol = tol
        self._segs = None
        drive = np.union1d(keep, drive_extra)
        self.drive = drive
        self.drive_pos = np.searchsorted(drive, keep)
        self.uk = u[keep]
        self.vk = v[keep]
        self.n_eval = 0

    def fast(self, names) -> bool:
        """True if the stack can be evaluated vectorised."""
        if "backlash" in names:
            return False
        if "slip_degradation" in names:
            below = names[:names.index("slip_degradation")]
            if "asymmetric_slip" in below:
                return False
        return True

    def _unit_dissipation(self, p1: IwanParameters) -> np.ndarray:
        """Dissipated energy of the unit Iwan joint after each step of the whole record."""
        if self._segs is None:
            self._segs = dissipation_segments(self.u, self._tol)
        step, virgin, xa, xb = self._segs
        d = _slip_energy(xb, p1) - _slip_energy(xa, p1)
        d = np.where(virgin, np.maximum(d, 0.0), 2.0 * d)
        per_step = np.bincount(step, weights=d, minlength=self.u.size)
        return np.cumsum(per_step)

    def unit_force(self, shape, names, values) -> np.ndarray:
        """Force with ``Fs = 1`` at the kept samples. ``shape = (phi_max, chi, beta)``;
        ``values``: unit-``Fs`` parameter dicts, one per effect."""
        self.n_eval += 1
        p1 = unit_params(*shape)
        if not self.fast(names):
            el = build_element(p1, names, values)
            F = el.force_history(self.u[self.drive], self.v[self.drive])
            return F[self.drive_pos]
        F = self.hist.forces(p1)
        D = None
        for name, vals in zip(names, values):
            if name == "viscous_damping":
                F = F + vals["c"] * self.vk
            elif name == "pinning_stiffness":
                e = np.maximum(np.abs(self.uk) - vals["delta"], 0.0)
                F = F + vals["k_p"] * np.sign(self.uk) * e
            elif name == "asymmetric_slip":
                F = F + vals["asymmetry"] * np.abs(F)
            elif name == "slip_degradation":
                if D is None:
                    D = self._unit_dissipation(p1)
                    for inner_name, inner_vals in zip(names, values):
                        if inner_name == "slip_degradation":
                            break
                        if inner_name == "viscous_damping":
                            D = D + self._dashpot_dissipation(inner_vals["c"])
                prev = np.concatenate([[0.0], D[:-1]])[self.keep]
                F = F * np.exp(-vals["rate"] * prev)
        return F

    def _dashpot_dissipation(self, c: float) -> np.ndarray:
        u0 = np.concatenate([[0.0], self.u[:-1]])
        v0 = np.concatenate([[0.0], self.v[:-1]])
        return np.cumsum(c * 0.5 * (v0 + self.v) * (self.u - u0))
