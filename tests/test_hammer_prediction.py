"""models.calibration.hammer: the pieces of a hammer test's prediction from one mode.

The full route (calibration, multi-mode ring-down, every curve against the record) runs in
``examples/brb_every_mode.py`` and ``benchmarks/bench_every_mode.py`` (about 25 s); here the
release read-out against an analytic two-mode decay, the bands, and the input guards.
"""

import functools
import math
from pathlib import Path

import numpy as np
import pytest
from iwan_element.models.calibration import mode_bands, release_amplitudes

from iwan_element import models

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "brb-hammer"
needs_data = pytest.mark.skipif(
    not DATA.is_dir(),
    reason="the measured Brake-Reuss hammer record (GPL-3.0) is read from "
    "../shared only and is absent here",
)

FS = 12800.0


def _two_mode_record(X, f, zeta, *, t_end=2.0, pre=0.01):
    """Acceleration of two decaying modes released at t = 0 with displacement amplitudes X."""
    t = np.arange(-pre, t_end, 1.0 / FS)
    tt = np.clip(t, 0.0, None)
    a = np.zeros_like(t)
    for x, fr, z in zip(X, f, zeta):
        w = 2 * math.pi * fr
        a -= w * w * x * np.exp(-z * w * tt) * np.cos(w * np.sqrt(1 - z * z) * tt)
    return t, a * (t >= 0)


def test_release_amplitudes_read_each_mode_of_an_analytic_decay():
    X, f, zeta = (70e-6, 3e-6), (80.4, 297.7), (2e-3, 1e-3)
    t, a = _two_mode_record(X, f, zeta)
    for t_r in (0.05, 0.2):
        got = release_amplitudes(t, a, {1: (60.0, 120.0), 2: (270.0, 325.0)}, release_time=t_r)
        for r, (x, fr, z) in enumerate(zip(X, f, zeta), start=1):
            truth = x * math.exp(-z * 2 * math.pi * fr * t_r)
            # the band's centre (90 Hz for mode 1) would read it 20 % low
            assert got[r] == pytest.approx(truth, rel=5e-3), (t_r, r)


def test_release_amplitudes_refuse_a_span_beyond_the_record():
    t, a = _two_mode_record((1e-5, 1e-6), (80.0, 300.0), (1e-3, 1e-3), t_end=0.2)
    with pytest.raises(ValueError, match="release_time"):
        release_amplitudes(t, a, {1: (60.0, 120.0)}, release_time=0.1, fit_span=0.3)
    with pytest.raises(ValueError, match="finite"):
        release_amplitudes(t, np.where(t > 0.1, np.nan, a), {1: (60.0, 120.0)})
    with pytest.raises(ValueError, match="uniformly"):
        release_amplitudes(np.where(t > 0.1, t + 0.01, t), a, {1: (60.0, 120.0)})  # a gap
    with pytest.raises(ValueError, match="strictly increasing"):
        release_amplitudes(t[::-1], a, {1: (60.0, 120.0)})


def test_mode_bands_hold_each_stuck_frequency_and_do_not_overlap():
    spec = models.preset("two-bolt-aluminium").replace(n_points=12)
    f = [models.modal.linear_modes(spec, mode=r)[0] / (2 * math.pi) for r in (1, 2, 3, 4)]
    bands = mode_bands(spec, (1, 2, 3), band_width=0.4)
    for r in (1, 2, 3):
        lo, hi = bands[r]
        assert lo < f[r - 1] < hi
        assert hi <= math.sqrt(f[r - 1] * f[r]) * (1 + 1e-12)
    assert bands[1][1] <= bands[2][0] * (1 + 1e-12) and bands[2][1] <= bands[3][0] * (1 + 1e-12)
    assert mode_bands(spec, (2,), band_width=0.05)[2] == pytest.approx((0.95 * f[1], 1.05 * f[1]))


def test_predict_hammer_test_guards_its_inputs():
    spec = models.preset("two-bolt-aluminium").replace(n_points=12)
    t, a = _two_mode_record((1e-4, 1e-5), (30.0, 200.0), (1e-3, 1e-3), t_end=1.0)
    far = {"tip": (spec.sensor_position - 0.01, t, a)}
    with pytest.raises(ValueError, match="sensor position"):
        models.predict_hammer_test(spec, far)
    ok = {"tip": (spec.sensor_position, t, a)}
    with pytest.raises(ValueError, match="calibration_mode"):
        models.predict_hammer_test(spec, ok, modes=(2, 3))
    with pytest.raises(ValueError, match="modes"):
        models.predict_hammer_test(spec, ok, modes=(1, 1))
    with pytest.raises(ValueError, match="bands"):
        models.predict_hammer_test(spec, ok, bands={1: (50.0, 20.0), 2: (150.0, 250.0)})
    with pytest.raises(ValueError, match=r"records\['tip'\]"):
        models.predict_hammer_test(spec, {"tip": (spec.sensor_position, t, a[:-1])})
    with pytest.raises(ValueError, match="position"):
        models.predict_hammer_test(spec, {"tip": (5.0, t, a)})


@functools.lru_cache(maxsize=1)
def round_trip():
    """A two-mode "hammer test" made by the beam model itself (modes 1 and 2 released from
    60 and 3 um at acc3, records at acc3 and acc2), predicted from a start whose chi is
    wrong (-0.3 for -0.4687), calibrating chi only: ``(truth specimen, HammerPrediction)``."""
    s = models.preset("brake-reuss").replace(
        n_points=8, modal_damping=(1.3e-3, 1e-3), calibrated_range=None
    )
    x2 = 0.72 - 0.1651
    rd = models.ringdown(
        s,
        amplitude={1: 60e-6, 2: 3e-6},
        sensors=(s.sensor_position, x2),
        duration=0.8,
        steps_per_period=64,
    )
    recs = {
        "acc3": (s.sensor_position, rd.t, rd.sensor_acceleration[0]),
        "acc2": (x2, rd.t, rd.sensor_acceleration[1]),
    }
    # the 0.8 s records hold no low-amplitude (linear) window for a linear update; the truth's
    # linear structure is the start's
    return s, models.predict_hammer_test(
        s.replace(chi=-0.3),
        recs,
        fit=("chi",),
        release_time=0.02,
        fit_span=0.2,
        duration=0.6,
        calibration_periods=10,
        update=None,
    )


def test_a_hammer_test_made_by_the_model_is_predicted_back():
    """Round trip: the calibration finds chi, each mode's floor comes back, and the
    prediction meets every record. Independent routes inside: the calibration is QSMA, the
    records and the prediction are Exudyn ring-downs read by amplitude_curve. Tolerances:
    the synthetic records keep the trapezoidal rule's period error (w h)^2 / 12 = 0.08 % at
    64 steps per period of mode 2, which the prediction's read-out removes; QSMA against a
    transient differs by about 2 % in damping (docs/multi_mode.md section 1)."""
    truth, p = round_trip()
    assert p.calibration.params.values["chi"] == pytest.approx(truth.interface.chi, rel=0.05)
    assert p.calibration.specimen.floor(2) == pytest.approx(1e-3, rel=0.02)
    summary = p.summary()
    for (r, name), s in summary.items():
        assert s["points"] >= 2, (r, name)
        assert s["max_frequency_error"] < 1e-3, (r, name, s)
        assert s["max_damping_error"] < 0.06, (r, name, s)
    for (r, name), (m, q) in p.ratios.items():
        assert q == pytest.approx(m, rel=0.02), (r, name)
    assert p.release[2] == pytest.approx(3e-6, rel=0.1)  # read 20 ms after the largest sample
    assert "Hammer test predicted from mode 1" in p.report()
    assert set(p.to_dict()["summary"]) == {
        "mode 1 at acc3",
        "mode 2 at acc3",
        "mode 1 at acc2",
        "mode 2 at acc2",
    }


@needs_data
def test_the_hammer_route_updates_the_linear_structure_on_the_low_amplitude_windows():
    """Step 1a on the Brake-Reuss record: both bending modes' frequencies from their latest
    linear windows of the three accelerometers, Young's modulus and the stuck interface's
    stiffness updated on them; the preset already carries that update (it moves < 2 stderr)
    and the second mode is met within its error after it."""
    from iwan_element.models.calibration import mode_bands
    from iwan_element.models.calibration.hammer import _linear_update

    spec = models.preset("brake-reuss")
    recs = {}
    for name, x in (("acc1", 0.0254), ("acc2", 0.5549), ("acc3", 0.6438)):
        d = np.loadtxt(DATA / f"hammer_{name}.csv", delimiter=",", skiprows=1)
        recs[name] = (x, d[:, 0], d[:, 1])
    upd = _linear_update(
        spec, recs, "acc3", mode_bands(spec, (1, 2)), ("youngs_modulus", "stiffness_per_area")
    )
    for n, p in upd.params.items():
        assert p.identified and abs(p.value - upd.nominal[n]) < 2 * p.stderr, (n, upd.report())
    f2 = next(r for r in upd.residuals if r["target"] == "f2")
    assert abs(f2["residual_after"]) < 1.0 and f2["measured"] == pytest.approx(297.78, abs=0.1)


def test_predict_with_the_calibrated_joint_gives_the_prediction_back():
    """The same release on the same specimen, read the same way: the route's own curves."""
    _, p = round_trip()
    again = p.predict_with(p.calibration.specimen)
    assert set(again) == set(p.predicted)
    for k, c in p.predicted.items():
        np.testing.assert_allclose(again[k].amplitude, c.amplitude, rtol=1e-9)
        np.testing.assert_allclose(again[k].damping_ratio, c.damping_ratio, rtol=1e-9)


def test_a_test_the_model_made_without_a_hidden_effect_has_nothing_named():
    """The workflow across modes on the round trip: QSMA against the model's own ring-down
    within the two routes' agreement (1e-4 in frequency, 2 % in damping) names nothing.
    """
    _, p = round_trip()
    r = models.diagnose_hammer_test(p, frequency_noise=1e-4, damping_ratio_noise=0.02)
    assert r.named is None and r.success, r.report()
    assert set(r.curves) == {1, 2}
    with pytest.raises(ValueError, match="HammerPrediction"):
        models.diagnose_hammer_test(r)
    with pytest.raises(ValueError, match="top"):
        models.diagnose_hammer_test(p, top=0)
