"""From a modal fit to the joint: an effect found on one mode's curve, mapped to the contact
points and fitted so that the physical interface reproduces that curve by QSMA.

Mapping (``docs/vibration_effects.md``, "Effects in the joint"). On mode ``m`` (stuck shape
``phi``, mass-normalised, ``a_i = (G phi)_i`` the slip of point ``i`` per unit modal
coordinate, ``s = S phi`` the sensor's) a slip ``u_i = a_i X / s`` goes with the sensor
amplitude ``X``, and a force ``f_i`` at the points loads the mode, in sensor units, with
``s sum_i a_i f_i``. With the shares ``w_i`` of the effect's points
(:func:`~iwan_element.models.modal.interface.point_weights`) and ``A_2 = sum_i w_i a_i^2``:

* ``k_p = kappa / A_2``, ``k_2 = kappa_2 / A_2``, ``c = 2 zeta_v omega_0 / A_2`` (a spring
  or dashpot ``k_i`` adds ``sum_i k_i a_i^2`` to the mode's stiffness or damping per unit
  modal mass), ``k3 = kappa_3 s^2 / sum_i w_i a_i^4``;
* a length (``delta``, ``u_s``) is the modal one times ``r = sum_i w_i a_i^2 |a_i| / (s
  A_2)``, the slip per sensor amplitude averaged with the points' shares of the mode's
  added stiffness.

Exact for a mode whose shape does not change and whose points all slip alike. Neither holds
(the interface's slips redistribute as it softens, and a length shared by points of
different slip engages them one after another), so the physical form's scalars (the shared
value's scale and the length's) are then fitted: least squares on the log of frequency and
damping of the physical interface's QSMA against the modal form's curve over the
calibrated range (each normalised by the effect's own change there), started from the
mapping. The misfit left is stated on the effect (``fit_misfit``).
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from iwan_element.effects import EFFECTS

from ..reduced.model import reduced_model
from ..specimens.effects import SHARED, InterfaceEffect, SpecimenEffect
from .interface import point_weights, stiffness_cap

__all__ = ["map_modal_effect", "fit_interface_effects", "FIT_POINTS"]

log = logging.getLogger(__name__)

#: Amplitudes (log-spaced over the calibrated range) the physical form is fitted on.
FIT_POINTS = 12
_LENGTHS = ("delta", "u_s")
#: How far [log factor] the fit may move each scalar from the mapping.
FIT_BOUND = 3.0

#: Where an effect sits at the bolts (the pin), the least slip its points must have in the
#: mode it was found on, as a fraction of the interface's (``r`` of the mapping): below it
#: (a bolt at the lap's centre, where a bending mode's slip changes sign) a pin there could
#: stiffen that mode only with an absurd stiffness, and the effect goes to every contact
#: point instead (logged; the result's ``where`` says so).
BOLT_SLIP_SHARE = 0.25

#: ``(frequency, damping ratio)``: the relative misfits [-] the fit weighs alike, a test's
#: precision (the Brake-Reuss sweeps: 1e-4 in frequency, 3.7 % in damping per point).
#: A stiffness effect in the joint carries load the joint's points then do not, lowering
#: their slip and damping where its modal form keeps the dissipation: the fit then keeps the
#: frequency and lets the damping go by up to a few percent (stated in ``fit_misfit``).
PRECISION = (1e-4, 3e-2)


def _mode_slips(specimen, mode: int):
    """``(a, s, omega0)``: slips per unit modal coordinate at the contact points, the
    sensor's, and the stuck circular frequency [rad/s] of elastic mode ``mode``.
    """
    red = reduced_model(specimen, n_modes=max(8, mode))
    sysm = red.system
    r = red.mode_index(mode)
    nj = len(sysm.joints)
    return sysm.modes[:nj, r].copy(), float(sysm.modes[sysm.n_z, r]), float(sysm.omega[r])


def _slip_scale(specimen, effect, a, s) -> tuple[float, float]:
    """``(A_2, r)`` of the mapping (module docstring) for the points where ``effect`` sits."""
    w = point_weights(specimen, effect)
    A2 = float(np.sum(w * a * a))
    return A2, float(np.sum(w * a * a * np.abs(a)) / (abs(s) * A2))


def map_modal_effect(specimen, effect: SpecimenEffect, *, where: str = "") -> InterfaceEffect:
    """The joint-level form of a modal effect by the closed-form mapping (module docstring)
    on the effect's mode of ``specimen``; ``where`` as :class:`InterfaceEffect` (default the
    effect's own). Not yet fitted.
    """
    probe = InterfaceEffect(effect.name, fitted_on=effect, where=where)
    a, s, w0 = _mode_slips(specimen, effect.mode)
    if probe.where != "contact":
        rb = _slip_scale(specimen, probe, a, s)[1]
        rc = _slip_scale(specimen, replace(probe, where="contact"), a, s)[1]
        if rb < BOLT_SLIP_SHARE * rc:
            log.warning(
                "%s: the bolts' points slip %.2g of the interface's in mode %d (below %g: "
                "the mode barely moves the shanks); placed at every contact point instead",
                effect.name,
                rb / rc,
                effect.mode,
                BOLT_SLIP_SHARE,
            )
            probe = replace(probe, where="contact")
    w = point_weights(specimen, probe)
    A2, r = _slip_scale(specimen, probe, a, s)
    mv = effect.parameters
    if effect.name == "pinning_stiffness":
        vals = {"k_p": mv["k_p_per_mass"] / A2, "delta": mv["delta"] * r}
    elif effect.name == "macroslip_onset":
        vals = {"k_2": mv["kappa_2"] / A2, "u_s": mv["X_s"] * r, "shape": mv["shape"]}
    elif effect.name == "hardening":
        vals = {"k3": mv["k3_per_mass"] * s * s / float(np.sum(w * a**4))}
    elif effect.name == "viscous_damping":
        vals = {"c": 2.0 * mv["zeta_v"] * w0 / A2}
    else:  # every effect with a modal form has a mapping above
        raise ValueError(f"no joint mapping for {effect.name!r}")
    return InterfaceEffect(
        effect.name, values=tuple(vals.items()), where=probe.where, fitted_on=effect
    )


def _target(curve, base, effects, mode, X):
    """The modal form's curve: the base specimen's QSMA with each effect's modal form on
    top, in order (as :func:`~iwan_element.models.modal.modal_amplitude_curve` applies them).
    """
    f0, z0 = curve(base, mode, X)
    f, z = f0, z0
    floor = base.floor(mode)
    for e in effects:
        f, z = EFFECTS[e.name].modal_form(X, f, z, floor, **e.parameters)
    return f0, z0, f, z


def _scaled(effects, p, slots):
    """The effects with the fitted log-scales ``p`` applied to their values ``slots``
    (``(effect index, value name)``).
    """
    vals = [e.parameters for e in effects]
    for x, (k, key) in zip(p, slots):
        vals[k][key] *= float(np.exp(x))
    return [replace(e, values=tuple(v.items())) for e, v in zip(effects, vals)]


def _bounds(base, mapped, slots) -> tuple:
    """``(lower, upper, start)`` of the fitted log-scales: ``FIT_BOUND`` either way, a
    macroslip-onset patch's ``k_2`` at most its placement's :func:`stiffness_cap` (the
    mapping's value clipped below it to start). ValueError when even ``e^-FIT_BOUND`` of
    the mapping is above the cap: the placement cannot hold the mode's patch.
    """
    lb = np.full(len(slots), -FIT_BOUND)
    ub = np.full(len(slots), FIT_BOUND)
    for j, (k, key) in enumerate(slots):
        if key != "k_2":
            continue
        cap = stiffness_cap(base, mapped[k]) * (1.0 - 1e-6)
        top = math.log(cap / mapped[k].parameters["k_2"])
        if top <= -FIT_BOUND + 0.1:
            raise ValueError(
                f"{mapped[k].name} at {mapped[k].where}: the patch the mode asks for holds "
                f"{math.exp(-top):.3g} times the stiffness of the points there "
                f"(stiffness_cap {cap:.3g} N/m)"
            )
        ub[j] = min(ub[j], top)
    return lb, ub, np.minimum(0.0, ub - 0.05)


def _fit_mode(specimen, pending, curve):
    """The pending effects of one mode mapped and fitted (module docstring); returns them
    resolved.
    """
    mode = pending[0].fitted_on.mode
    cr = pending[0].fitted_on.calibrated_range or specimen.calibrated_range
    lo, hi = cr or specimen.amplitude_range
    X = np.geomspace(lo, hi, FIT_POINTS)
    names = {e.name for e in pending}
    base = specimen.replace(
        interface_effects=tuple(e for e in specimen.interface_effects if e.name not in names)
    )
    f0, z0, ft, zt = _target(curve, base, [e.fitted_on for e in pending], mode, X)
    mapped = [map_modal_effect(base, e.fitted_on, where=e.where) for e in pending]
    slots = [
        (k, key)
        for k, e in enumerate(mapped)
        for key, v in e.parameters.items()
        if (key in SHARED or key in _LENGTHS) and v > 0
    ]
    sf, sz = PRECISION
    lb, ub, p0 = _bounds(base, mapped, slots)

    def model(p):
        trial = base.replace(
            interface_effects=base.interface_effects + tuple(_scaled(mapped, p, slots))
        )
        return curve(trial, mode, X)

    def resid(p):
        try:
            f, z = model(p)
        except ValueError:  # the static solve lost the interface: far off
            return np.full(2 * X.size, 1e3)
        return np.concatenate([np.log(f / ft) / sf, np.log(z / zt) / sz])

    p = p0
    if slots:
        fit = least_squares(resid, p, bounds=(lb, ub), x_scale=1.0, diff_step=1e-3, xtol=1e-4)
        p = fit.x
        log.debug("interface fit: %d residual evaluations", fit.nfev)
    if np.any(np.abs(p) >= 0.99 * FIT_BOUND) or np.any(p >= ub - 1e-9):
        log.warning(
            "interface effects %s on mode %d: the fit reached a factor e^%g from the mapping "
            "(the joint cannot reproduce the modal form well; see fit_misfit)",
            sorted(names),
            mode,
            FIT_BOUND,
        )
    f, z = model(p)
    mis = (float(np.max(np.abs(f / ft - 1))), float(np.max(np.abs(z / zt - 1))))
    if mis[0] > 10 * PRECISION[0] or mis[1] > 3 * PRECISION[1]:
        log.warning(
            "interface effects %s on mode %d miss their modal form by up to %.2g in frequency "
            "and %.2g in damping after the fit: the effect found on the curve does not act "
            "through the joint's slip as its modal form assumes (augment(..., form='modal') "
            "keeps the curve on that mode alone)",
            sorted(names),
            mode,
            *mis,
        )
    log.info(
        "interface effects %s on mode %d fitted: misfit %.2e (frequency), %.2e (damping)",
        sorted(names),
        mode,
        *mis,
    )
    return [replace(e, fit_misfit=mis) for e in _scaled(mapped, p, slots)]


def fit_interface_effects(specimen, *, curve) -> Any:
    """``specimen`` with every interface effect that has no joint values yet mapped from
    its modal fit and fitted (module docstring), the effects of one mode together, modes in
    the order they first appear. ``curve(specimen, mode, X) -> (frequency [Hz], damping
    ratio [-])`` is the QSMA the fit matches (a specimen whose effects all have values).
    """
    done = specimen
    modes = []
    for e in specimen.interface_effects:
        if not e.resolved and e.fitted_on.mode not in modes:
            modes.append(e.fitted_on.mode)
    for m in modes:
        pending = [e for e in done.interface_effects if not e.resolved and e.fitted_on.mode == m]
        rest = tuple(e for e in done.interface_effects if e.resolved)
        fitted = _fit_mode(done.replace(interface_effects=rest + tuple(pending)), pending, curve)
        by_name = {e.name: e for e in fitted}
        done = done.replace(
            interface_effects=tuple(by_name.get(e.name, e) for e in done.interface_effects)
        )
    return done
