"""The vibration effects in the joint (``InterfaceEffect``): one law at the contact points that
every route runs, mapped and fitted from an effect's modal form (docs/vibration_effects.md,
"Effects in the joint")."""

from __future__ import annotations

import math

import numpy as np
import pytest

from iwan_element import models
from iwan_element.models import InterfaceEffect, resolve_interface_effects

W1 = 2 * math.pi * 80.6  # Brake-Reuss mode 1 [rad/s]
RANGE = (2e-6, 6e-5)  # the hammer calibration's amplitudes [m]
MODAL = {
    "hardening": {"k3_per_mass": 4e-3 * W1**2 / RANGE[1] ** 2},
    "viscous_damping": {"zeta_v": 3e-4},
    "pinning_stiffness": {"k_p_per_mass": 4e-3 * W1**2, "delta": 1e-5},
    "macroslip_onset": {"kappa_2": 3e-3 * W1**2, "X_s": 1.5e-5, "shape": 0.45},
}


@pytest.fixture(scope="module")
def brb():
    return models.preset("brake-reuss")


@pytest.mark.parametrize("name", sorted(MODAL))
def test_physical_form_reproduces_the_modal_form_on_its_mode_by_qsma(brb, name):
    """Each effect fitted on mode 1 as a modal form, then given to the joint: the physical
    interface's QSMA (a law at every contact point, acting through the static solve and the
    points' own energy per cycle) against the modal form's curve at amplitudes between the
    fit's. Stated tolerance: frequency within 5 % of the effect's own frequency change (or
    5 ppm), damping within 4 % (the fit weighs 1e-4 in frequency like 3 % in damping)."""
    v = MODAL[name]
    modal = brb.with_effects({name: v}, calibrated_range=RANGE)
    phys = resolve_interface_effects(
        brb.with_effects({name: v}, calibrated_range=RANGE, form="physical")
    )
    e = phys.interface_effects[0]
    assert e.resolved and e.fitted_on.parameters == pytest.approx(v)
    X = np.geomspace(RANGE[0] * 1.1, RANGE[1] * 0.97, 17)
    c0 = models.modal_amplitude_curve(brb, amplitude=X)
    cm = models.modal_amplitude_curve(modal, amplitude=X)
    cp = models.modal_amplitude_curve(phys, amplitude=X)
    foot = float(np.max(np.abs(cm.frequency / c0.frequency - 1)))
    assert np.max(np.abs(cp.frequency / cm.frequency - 1)) <= max(0.05 * foot, 5e-6)
    assert np.max(np.abs(cp.damping_ratio / cm.damping_ratio - 1)) <= 0.04
    assert max(e.fit_misfit) <= 0.04
    # the physical form is not the modal one by another name: it acts on the other modes
    q2 = models.modal_amplitude_curve(phys, mode=2, amplitude=[2e-5])
    q2_0 = models.modal_amplitude_curve(brb, mode=2, amplitude=[2e-5])
    assert (q2.frequency[0], q2.damping_ratio[0]) != (q2_0.frequency[0], q2_0.damping_ratio[0])


def test_interface_effect_is_validated_and_shared_by_its_rule(brb):
    """Joint-level values are checked against the effect's own bounds; the shares sum to one
    (``KT``-weighted at every contact point, two points at each bolt for the pin)."""
    with pytest.raises(ValueError, match="k_p must be"):
        InterfaceEffect("pinning_stiffness", values={"k_p": -1.0})
    with pytest.raises(ValueError, match="where must be"):
        InterfaceEffect("hardening", values={"k3": 1.0}, where="edges")
    with pytest.raises(ValueError, match="give values"):
        InterfaceEffect("hardening")
    pin = InterfaceEffect("pinning_stiffness", values={"k_p": 3e6, "delta": 1e-7})
    assert pin.where == "bolts"
    w = models.modal.point_weights(brb, pin)
    assert w.sum() == pytest.approx(1.0) and np.count_nonzero(w) == 2 * len(brb.bolt_positions)
    wc = models.modal.point_weights(brb, InterfaceEffect("hardening", values={"k3": 1.0}))
    pts = models.reduced.contact_points(brb)
    np.testing.assert_allclose(wc, pts.KT / pts.KT.sum())
