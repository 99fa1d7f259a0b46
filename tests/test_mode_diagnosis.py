"""models.diagnose_modes: the discrepancy workflow across modes, first on generated two-mode
curves with a hidden interface effect of the test's own making.

The hidden effect: a patch under the middle bolt of the Brake-Reuss lap that starts to slide
at 20 nm (``macroslip_onset`` at ``"bolt2"``, holding 0.8 of those points' stuck
stiffness). Mode 2 slips there 33 times more per sensor amplitude than mode 1 (the middle
bolt sits at mode 1's slip node), so mode 2 gains up to 27 % damping over 0.3-5 um while
mode 1 over 2-40 um changes by 0.02 %. The start is the
beam without the patch and with a wrong chi, calibrated on mode 1 alone; the workflow must
name the patch and its bolt from the two modes' curves, close mode 2's gap and leave mode
1's. A beam without a hidden effect must have nothing named.
"""

import functools

import numpy as np
import pytest
from iwan_element.models.calibration import calibrate, default_placements
from iwan_element.models.modal import modal_amplitude_curve, point_weights, stiffness_cap
from iwan_element.models.specimens.contact import beam_contact_points
from iwan_element.models.specimens.effects import InterfaceEffect

from iwan_element import AmplitudeCurve, models
from iwan_element.effects.macroslip_onset import patch_cumulative

HIDDEN = {"k_2": 1.1e8, "u_s": 2.0e-8, "shape": 0.25}
X1 = np.geomspace(2e-6, 40e-6, 14)
X2 = np.geomspace(0.3e-6, 5e-6, 14)
NOISE = (2e-5, 0.01)  # relative: frequency, damping ratio


def _beam():
    return models.preset("brake-reuss").replace(
        n_points=16, modal_damping=(1.3e-3, 1e-3), calibrated_range=None
    )


def _curves(spec, rng) -> dict:
    """Each mode's QSMA curve with relative noise, as a measured AmplitudeCurve."""
    out = {}
    for m, X in ((1, X1), (2, X2)):
        c = modal_amplitude_curve(spec, mode=m, amplitude=X)
        f = np.asarray(c.frequency) * (1 + NOISE[0] * rng.standard_normal(X.size))
        z = np.asarray(c.damping_ratio) * (1 + NOISE[1] * rng.standard_normal(X.size))
        out[m] = AmplitudeCurve(
            amplitude=X,
            frequency=f,
            damping_ratio=z,
            frequency_std=NOISE[0] * f,
            damping_ratio_std=NOISE[1] * z,
        )
    return out


@functools.lru_cache(maxsize=2)
def workflow(hidden: bool):
    """``(truth, calibrated start, ModesDiagnosis)``."""
    truth = _beam()
    if hidden:
        effect = InterfaceEffect("macroslip_onset", values=HIDDEN, where="bolt2")
        truth = truth.replace(interface_effects=(effect,))
    measured = _curves(truth, np.random.default_rng(11))
    start = _beam().replace(chi=-0.3)
    cal = calibrate(start, measured[1], fit=("chi",), floors={2: measured[2]})
    return truth, cal.specimen, models.diagnose_modes(cal.specimen, measured)


def test_the_hidden_patch_under_one_bolt_is_named_with_its_bolt():
    truth, start, r = workflow(True)
    # mode 1 never saw the patch: its calibration finds chi
    assert start.interface.chi == pytest.approx(truth.interface.chi, rel=0.05)
    assert r.success, r.report()
    assert r.named is not None and r.named.effects == ("macroslip_onset",)
    assert r.named.placed == ("bolt2",), r.report()
    assert r.named.probability > 0.99 and not r.named.capped
    # every placement was tried; the same law on every contact point is worse
    tried = {c.where for c in r.candidates if c.mode == 2}
    assert tried == set(default_placements(start))
    contact = next(c for c in r.candidates if c.mode == 2 and c.where == "contact")
    assert contact.ic > r.named.ic
    got = r.named.values["macroslip_onset"]
    assert got["u_s"] == pytest.approx(HIDDEN["u_s"], rel=0.35)
    assert got["k_2"] == pytest.approx(HIDDEN["k_2"], rel=0.6)


def test_the_named_patch_closes_mode_2_and_leaves_mode_1():
    _, _, r = workflow(True)
    g = r.gaps()
    assert g[2]["before"]["damping_error"] > 0.12
    assert g[2]["after"]["damping_error"] < 0.06
    assert g[2]["after"]["rms"] < 0.25 * g[2]["before"]["rms"]
    assert g[1]["after"]["rms"] <= g[1]["before"]["rms"] + 0.2
    assert any("fit, not a prediction" in w for w in r.warnings)
    assert "named: macroslip_onset (mode 2) at bolt2" in r.report()
    d = r.to_dict()
    assert d["named"] == r.named.label and len(d["rows"]) == 1 + len(r.candidates)
    df = r.to_dataframe()
    assert "probability [-]" in df.columns


def test_a_beam_without_a_hidden_effect_has_nothing_named():
    _, _, r = workflow(False)
    assert r.named is None and not r.candidates, r.report()
    assert r.success
    assert r.specimen is r.plain.specimen


def test_one_bolt_placement_is_checked():
    spec = _beam()
    w = point_weights(spec, InterfaceEffect("hardening", values={"k3": 1.0}, where="bolt2"))
    assert w.sum() == pytest.approx(1.0) and np.count_nonzero(w) == 2
    with pytest.raises(ValueError, match="3 bolt"):
        point_weights(spec, InterfaceEffect("hardening", values={"k3": 1.0}, where="bolt4"))
    u = point_weights(spec, InterfaceEffect("hardening", values={"k3": 1.0}, where="under2"))
    kt = beam_contact_points(spec).KT
    on = u > 0
    assert u.sum() == pytest.approx(1.0) and on.sum() > 2 and np.all(on[w > 0])
    np.testing.assert_allclose(u[on] / kt[on], u[on][0] / kt[on][0], rtol=1e-12)
    for bad in ("bolt0", "rim", "bolt", "under0", "under"):
        with pytest.raises(ValueError, match="where"):
            InterfaceEffect("hardening", values={"k3": 1.0}, where=bad)
    curves = {1: object()}
    with pytest.raises(ValueError, match="placements"):
        models.diagnose_modes(spec, curves, placements=("bolt7",))
    with pytest.raises(ValueError, match=r"measured\[1\]"):
        models.diagnose_modes(spec, curves)
    with pytest.raises(ValueError, match="measured"):
        models.diagnose_modes(spec, {})


def test_a_patch_holding_more_than_its_points_stiffness_is_refused():
    """A macroslip-onset patch replaces part of the stuck stiffness it sits in: past that
    point's stiffness the sliding point would give way under load (a negative tangent).
    """
    spec = _beam()
    e = InterfaceEffect("macroslip_onset", values=HIDDEN, where="bolt2")
    cap = stiffness_cap(spec, e)
    # the bank's total over [u_s, 8 u_s] is k_2 times its cumulative fraction at 8 u_s; at
    # the cap the more loaded of bolt 2's two points holds exactly its stuck stiffness
    held = patch_cumulative(8 * HIDDEN["u_s"], HIDDEN["u_s"], HIDDEN["shape"])
    kt = beam_contact_points(spec).KT[point_weights(spec, e) > 0]
    assert cap * held / 2 == pytest.approx(kt.min(), rel=1e-12)
    assert HIDDEN["k_2"] < cap  # the hidden patch is a physical one
    over = InterfaceEffect("macroslip_onset", values={**HIDDEN, "k_2": 1.01 * cap}, where="bolt2")
    with pytest.raises(ValueError, match="stuck stiffness"):
        modal_amplitude_curve(spec.replace(interface_effects=(over,)), mode=2, amplitude=X2)
    _, start, r = workflow(True)
    for c in r.candidates:  # every fitted patch stays within its placement's cap
        if c.values:
            placed = InterfaceEffect(
                "macroslip_onset", values=c.values["macroslip_onset"], where=c.placed[0]
            )
            assert c.values["macroslip_onset"]["k_2"] <= stiffness_cap(start, placed)
