"""Unit mistakes refused by every vibration function: damping in percent, frequency in
rad/s where a second frequency tells it, phase in degrees.

The data are the modal Iwan closed forms (``modal_iwan_curve``) of a joint whose damping
ratio stays below 1 % (so ``100 * zeta`` is below 1, which a plain "> 1" test accepts).
"""

import math

import numpy as np
import pytest

from iwan_element import (
    AmplitudeCurve,
    IwanParameters,
    diagnose_vibration,
    fit_modal_iwan,
    modal_iwan_curve,
    sweep_curve,
)

W02 = (2 * math.pi * 80.0) ** 2
_KT = 0.02 * W02
P = IwanParameters(_KT * (0.5 + 0.5 / 1.5) * 2e-4 / 1.5, _KT, -0.5, 0.5)
X = np.geomspace(2e-6, 6e-5, 12)
F, Z = modal_iwan_curve(X, P, K_inf=W02 - _KT, zeta0=1e-3, stiffness="harmonic", floor="dashpot")


def test_data_are_lightly_damped():
    assert Z.max() < 0.01 and (100 * Z).max() < 1.0  # percent values pass a "> 1" check


def test_fit_modal_iwan_refuses_percent():
    fit_modal_iwan(X, F, Z)  # the ratio is accepted
    with pytest.raises(ValueError, match="damping_ratio .*percent"):
        fit_modal_iwan(X, F, 100 * Z)


def test_diagnose_vibration_refuses_percent_and_rad_s():
    kw = dict(predicted_frequency=F * 1.0001, predicted_damping_ratio=Z * 0.9)
    diagnose_vibration(X, F, Z, **kw)
    with pytest.raises(ValueError, match="damping .*percent"):
        diagnose_vibration(X, F, 100 * Z, **kw)
    with pytest.raises(ValueError, match="predicted_damping_ratio .*percent"):
        diagnose_vibration(X, F, Z, predicted_frequency=F, predicted_damping_ratio=100 * Z)
    with pytest.raises(ValueError, match="frequency .*rad/s"):
        diagnose_vibration(X, 2 * math.pi * F, Z, **kw)


def test_curves_in_percent_cannot_be_made_for_the_vibration_functions():
    curve = AmplitudeCurve(X, F, 100 * Z)  # the container itself allows < 1
    with pytest.raises(ValueError, match="percent"):
        fit_modal_iwan(curve)
    with pytest.raises(ValueError, match="percent"):
        diagnose_vibration(curve, predicted_frequency=F, predicted_damping_ratio=Z)


def test_diagnose_vibration_takes_an_amplitude_curve():
    std = AmplitudeCurve(X, F, Z, frequency_std=1e-5 * F, damping_ratio_std=0.02 * Z)
    kw = dict(predicted_frequency=F, predicted_damping_ratio=Z)
    a = diagnose_vibration(std, **kw)
    b = diagnose_vibration(
        X, F, Z, frequency_uncertainty=1e-5, damping_ratio_uncertainty=0.02, **kw
    )
    assert a.effect == b.effect and a.details["noise_from"] == b.details["noise_from"]
    assert a.frequency_noise == pytest.approx(b.frequency_noise)
    with pytest.raises(ValueError, match="not both"):
        diagnose_vibration(std, F, Z, **kw)
    with pytest.raises(ValueError, match="frequency and damping_ratio are required"):
        diagnose_vibration(X, **kw)


def test_sweep_curve_refuses_phase_in_degrees():
    f = np.linspace(79.0, 81.0, 21)
    W, wr = 2 * math.pi * f, 2 * math.pi * 80.0
    H = 0.5 / (wr**2 - W**2 + 2j * 0.002 * wr * W)
    with pytest.raises(ValueError, match="phase must be in radians .*degrees"):
        sweep_curve(f, np.ones_like(f), np.abs(H) * W**2, np.degrees(np.angle(-H)))
