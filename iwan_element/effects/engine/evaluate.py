"""Fast force evaluation of an effect stack on the Iwan joint over a fixed displacement history.

Private module used by :mod:`iwan_element.diagnose`. A model is a tuple of effect names,
innermost first (``("asymmetric_slip", "viscous_damping")`` is
``ViscousDamping(AsymmetricSlip(IwanJoint))``); :func:`order_stack` puts slider-level
effects innermost. Every effect is homogeneous of degree one in the force scale: with
``Fs = 1`` and each effect parameter divided by ``Fs**fs_power`` (its
:class:`~iwan_element.effects.ParamSpec`) the force is ``Fs`` times the unit force. The unit
force is evaluated

* vectorised and exact (the Iwan joint through :class:`~iwan_element.core.history.History`,
  then each effect's ``vector_force``) when every effect of the stack has a history-free
  vectorised form (viscous damping, pinning stiffness);
* slip degradation behind a backlash (then vector forms), whose wear makes the joint's path
  depend on every commit, by the elements' per-sample rule compiled
  (:mod:`.series_kernel`) on the drive samples (the fitted samples plus every turning
  point of the record); a backlash around a joint whose state depends only on its turning
  points is found run by run instead (``Backlash.joint_path``: measured twice as fast on
  the damper records);
* otherwise by the effect elements' own ``force_history`` on the drive samples (exact for
  these rate-independent elements, whose state depends only on the turning points; a
  dashpot in such a stack sees the velocity at the drive samples).

The routes are checked against the elements in ``tests/test_diagnosis.py`` and
``tests/test_kernel.py``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...core.closed_form import slip_energy
from ...core.history import REVERSAL_TOL, History, unit_params
from ...core.joint import IwanJoint
from ...core.masing import masing_constants, masing_rows, reversal_structure
from ...core.parameters import IwanParameters
from .. import EFFECTS
from ..base import declares_vector_form
from .series_kernel import backlash_history, backlash_path

__all__: list[str] = []


def order_stack(names) -> tuple:
    """``names`` with the slider-level effects first (they wrap the joint directly)."""
    names = tuple(names)
    return tuple(n for n in names if EFFECTS[n].slider_level) + tuple(
        n for n in names if not EFFECTS[n].slider_level
    )


def stack_ok(names) -> bool:
    """Whether the slider-level effects among ``names`` may share one joint: at most one,
    since each rebuilds the joint's sliders, unless all are composable slider laws (their
    thresholds multiply).
    """
    sliders = [n for n in names if EFFECTS[n].slider_level]
    return len(sliders) <= 1 or all(EFFECTS[n].composable for n in sliders)


def _layers(names) -> tuple:
    """``(chain, series, rest)`` of a stack (innermost first): the innermost slider-level
    effects; an effect in series with the joint (``structure == "series"``, e.g. backlash)
    right around them if there is one and nothing below it depends on the rate or the
    dissipated energy; and everything else.
    """
    names = tuple(names)
    k = 0
    while k < len(names) and EFFECTS[names[k]].slider_level:
        k += 1
    chain, rest = names[:k], names[k:]
    series = ()
    if (
        rest
        and EFFECTS[rest[0]].structure == "series"
        and not any(EFFECTS[n].needs_energy for n in chain)
    ):
        series = rest[:1]
    return chain, series, rest[len(series) :]


def wear_behind_gap(names) -> bool:
    """True for slip degradation with backlash around it (then vector forms only): the
    stack :func:`backlash_history` evaluates compiled, sample by sample.
    """
    names = tuple(names)
    return names[:2] == ("slip_degradation", "backlash") and all(
        has_vector_form(n) for n in names[2:]
    )


def has_vector_form(name: str) -> bool:
    """True if the effect has a history-free vectorised force."""
    return declares_vector_form(EFFECTS[name])


def dissipation_segments(u: np.ndarray, tol: float):
    """Branch segments walked by the Iwan joint along ``u`` (the kernel's walk,
    :func:`iwan_element.core.masing.reversal_structure`).

    Returns ``(step, virgin, xa, xb)``: step index of each segment, True for a segment on the
    virgin curve (dissipation ``I_H(xb) - I_H(xa)``, clipped at 0) and False on a branch
    (``2 (I_H(xb) - I_H(xa))``), and the backbone arguments at its ends [m].
    """
    _, segs = reversal_structure(u, tol, segments=True)
    assert segs is not None  # segments=True always returns them
    step, anchor, ua, ub = segs
    virgin = anchor < 0
    ur = np.where(virgin, 0.0, u[np.maximum(anchor, 0)])
    scale = np.where(virgin, 1.0, 0.5)
    return step, virgin, scale * np.abs(ua - ur), scale * np.abs(ub - ur)


def scale_effect(name: str, values: dict, Fs: float, *, to_unit: bool) -> dict:
    """Convert effect parameters between physical and unit-``Fs`` form (``fs_power``)."""
    out = dict(values)
    for sp in EFFECTS[name].specs:
        if sp.fs_power and sp.name in out:
            f = Fs**sp.fs_power
            out[sp.name] = values[sp.name] / f if to_unit else values[sp.name] * f
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
        Displacement [m] (from the joint's rest position) and velocity [m/s] of the record.
    keep : ndarray of int
        Sample indices whose forces are wanted (sorted).
    drive_extra : ndarray of int
        Further samples (turning points) the element route must pass through.
    tol : float
        Absolute reversal tolerance [m] (the package-wide ``REVERSAL_TOL`` times the scale).
    """

    def __init__(
        self, u: np.ndarray, v: np.ndarray, keep: np.ndarray, drive_extra: np.ndarray, *, tol: float
    ):
        self.u = u
        self.v = v
        self.keep = keep
        self.hist = History(u, keep=keep, tol=tol)
        self.x_max = self.hist.x_max
        self._tol = tol
        # (step, virgin, xa, xb) of dissipation_segments, computed on first use
        self._segs: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None
        drive = np.union1d(keep, drive_extra)
        self.drive = drive
        self.drive_pos = np.searchsorted(drive, keep)
        self.uk = u[keep]
        self.vk = v[keep]
        self.n_eval = 0
        self._hist0 = self.hist
        self._starts: dict[float, History] = {}  # histories per start [m]
        self.start = 0.0
        self._ext = (u, v, drive, self.drive_pos)

    def set_start(self, start: float) -> None:
        """Drive the joint from its virgin rest to ``start`` [m] before the first sample.

        A test record begins in whatever state the previous test or the setting-up left the
        joint: a residual load, a position in a gap. The path ``0 -> start -> u[0]`` before
        the record is that unknown state's one-parameter form (``start = 0``, or any value
        between 0 and ``u[0]``, is the virgin start). Histories are cached per value.
        """
        start = float(start)
        if start == self.start:
            return
        self.start = start
        self._segs = None
        if start == 0.0:
            self.hist = self._hist0
            self._ext = (self.u, self.v, self.drive, self.drive_pos)
            return
        u = np.concatenate([[start], self.u])
        v = np.concatenate([[0.0], self.v])
        hist = self._starts.get(start)
        if hist is None:
            if len(self._starts) > 256:
                self._starts.clear()
            hist = self._starts[start] = History(u, keep=self.keep + 1, tol=self._tol)
        self.hist = hist
        self._ext = (u, v, np.concatenate([[0], self.drive + 1]), self.drive_pos + 1)

    @staticmethod
    def fast(names) -> bool:
        """True if the stack can be evaluated without running the elements step by step:
        innermost slider-level effects (one, or a chain of composable ones), whose
        corrections run on the drive samples; then optionally an effect in series with the
        joint (``joint_path``: the joint's own displacement, found run by run) around
        rate-independent ones; then vector forms.
        """
        chain, series, rest = _layers(names)
        return stack_ok(chain) and all(has_vector_form(n) for n in rest)

    def unit_dissipation(self, p1: IwanParameters) -> np.ndarray:
        """Dissipated energy of the plain unit Iwan joint after each step of the record."""
        u = self._ext[0]
        if self._segs is None:
            self._segs = dissipation_segments(u, self._tol)
        step, virgin, xa, xb = self._segs
        d = slip_energy(xb, p1) - slip_energy(xa, p1)
        d = np.where(virgin, np.maximum(d, 0.0), 2.0 * d)
        return np.cumsum(np.bincount(step, weights=d, minlength=u.size))

    def unit_force(self, shape, names, values) -> np.ndarray:
        """Force with ``Fs = 1`` at the kept samples. ``shape = (phi_max, chi, beta)``;
        ``values``: unit-``Fs`` parameter dicts, one per effect (innermost first).
        """
        self.n_eval += 1
        p1 = unit_params(*shape)
        u, v, drive, pos = self._ext
        if not self.fast(names):
            if wear_behind_gap(names):
                return self._wear_behind_gap(p1, names, values)
            el = build_element(p1, names, values)
            F = el.force_history(u[drive], v[drive])
            return F[pos]
        chain, series, rest = _layers(names)
        vals = dict(zip(names, values))
        els: list[Any] = [IwanJoint(p1)]  # the joint, then its slider-level effects
        for name in chain:
            els.append(EFFECTS[name](els[-1], **vals[name]))
        x, hist = u[drive], self.hist
        if series:  # the joint sees its own path w, not the drive
            gap = vals[series[0]]  # (Backlash.joint_path, compiled), new every call:
            x = backlash_path(
                np.ascontiguousarray(x),
                _constants(p1),
                *_laws(els[1:]),
                float(gap["gap"]),
                float(gap.get("drag", 0.0)),
            )
            C = masing_constants(p1, self._tol)[None, :]  # the kernel along it directly
            F = masing_rows(C, x[None, :])[0][0, pos]
        else:
            F = hist.forces(p1)
        for el in els[1:]:  # each adds its force over the chain below it
            D = self.unit_dissipation(p1)[drive] if el.needs_energy else None
            F = F + el.correction_history(x, D)[pos]
        for name in rest:
            F = EFFECTS[name].vector_force(F, self.uk, self.vk, **vals[name])
        return F

    def _wear_behind_gap(self, p1: IwanParameters, names, values) -> np.ndarray:
        """Unit force of ``slip_degradation, backlash[, vector forms]`` (:func:`wear_behind_gap`)
        at the kept samples: the elements' per-sample rule on the drive samples, compiled.
        """
        u, _, drive, pos = self._ext
        wear = EFFECTS["slip_degradation"](IwanJoint(p1), **values[0])
        gap = values[1]
        F = backlash_history(
            np.ascontiguousarray(u[drive]),
            _constants(p1),
            wear._k,
            wear._sign,
            wear._phi,
            wear.rate,
            *_laws([]),
            float(gap["gap"]),
            float(gap.get("drag", 0.0)),
        )[pos]
        for name, vals in zip(names[2:], values[2:]):
            F = EFFECTS[name].vector_force(F, self.uk, self.vk, **vals)
        return F


def _constants(p1: IwanParameters) -> np.ndarray:
    """Kernel constants of ``IwanJoint(p1)`` (the package's reversal tolerance)."""
    return masing_constants(p1, REVERSAL_TOL * p1.phi_max)


def _laws(els) -> tuple:
    """``(table, pm, p, C)``: the joint's slider-law state (the law effects ``els``, each
    wrapping the one before, their tables side by side; no columns for none).
    """
    if not els:
        return np.zeros((11, 0)), 1.0, 1.0, 0.0
    tables = [el._new_pieces() for el in els]
    t0 = tables[0]
    return np.concatenate([t.state for t in tables], axis=1), t0.pm, t0.p, t0.C
