"""Plausibility of measured records (issue 45, cases 1-3 and item 1): one rule, shared by every
entry that reads a measurement (:mod:`iwan_element.base.plausibility`), flags a record whose
declared quantity or unit makes the structure move faster than any vibration test of a jointed
structure; the same rule stays quiet on the real records in ``../shared/data``.

Every record here is built in closed form (a damped cosine and its exact derivatives, a
single-degree-of-freedom receptance) or by the averaging model of ``tests/_decays.py``, so the
truth (the displacement amplitude, hence its velocity and acceleration) is known apart from
the code under test.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from _decays import modal_curves, svam_decay

from iwan_element import (
    amplitude_curve,
    fit_decay,
    fit_loops,
    free_decay_modes,
    stepped_sine_curve,
    sweep_curve,
    sweep_modes,
)

F0, ZETA, X0 = 80.0, 1e-3, 1.64e-4  # the ring-down: 80 Hz, 0.1 %, 164 um


def _decay(f0=F0, zeta=ZETA, x0=X0, fs=5000.0, duration=4.0, noise=1e-4, seed=0):
    """Acceleration of a linear free decay ``x = x0 exp(-s t) cos(wd t)`` (its exact second
    derivative) with white noise of ``noise`` times its peak."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(fs * duration)) / fs
    wn = 2 * math.pi * f0
    s, wd = zeta * wn, wn * math.sqrt(1 - zeta**2)
    e, c, si = np.exp(-s * t), np.cos(wd * t), np.sin(wd * t)
    a = x0 * e * ((s * s - wd * wd) * c + 2 * s * wd * si)
    return t, a + noise * np.abs(a).max() * rng.standard_normal(t.size)


def _sweep(scale=1.0, f0=F0, zeta=2e-3, X_peak=1e-4, quantity="acceleration"):
    """Stepped-sine lines of one linear mode, receptance ``1 / (wr^2 - W^2 + 2i zeta wr W)``
    (unit modal mass), force set so the peak displacement is ``X_peak``; the response in
    ``quantity`` times ``scale`` (a unit slip) and its phase relative to the force."""
    f = np.linspace(f0 * 0.98, f0 * 1.02, 41)
    W, wr = 2 * math.pi * f, 2 * math.pi * f0
    H = 1.0 / (wr**2 - W**2 + 2j * zeta * wr * W)
    F = np.full(f.size, X_peak / np.abs(H).max())
    R = H * F * (1j * W) ** {"displacement": 0, "velocity": 1, "acceleration": 2}[quantity]
    return f, F, scale * np.abs(R), np.angle(R), H


# ------------------------------------------------------------------ the cases
def test_case_1_acceleration_declared_displacement_is_not_usable():
    t, a = _decay()
    curve = amplitude_curve(t, a, quantity="displacement", band=(60, 100))
    assert not curve.success
    why = " ".join(curve.failures)
    assert "y read as displacement" in why and "quantity='acceleration'" in why
    # the same record read as what it is passes, at its true amplitude
    ok = amplitude_curve(t, a, quantity="acceleration", band=(60, 100))
    assert ok.success and not any("vibration test" in w for w in ok.warnings)
    assert ok.amplitude.max() == pytest.approx(X0, rel=0.15)


def test_case_2_millimetres_per_s2_given_as_m_per_s2_is_not_usable():
    t, a = _decay()
    curve = amplitude_curve(t, 1000.0 * a, quantity="acceleration", band=(60, 100))
    assert not curve.success
    why = " ".join(curve.failures)
    assert "mm/s^2 given as m/s^2" in why and "divide by 1000" in why


def test_case_3_fit_decay_on_acceleration_declared_displacement_is_not_usable():
    """A microslip decay (20 Hz, 0.1 % + 0.1 % at 100 um, 0.5 % softening) recorded as
    acceleration and fitted as displacement: before, "usable" with stderr as confident as
    for the right quantity (f0 20.0079 +- 0.016 Hz, zeta0 7.5e-4 +- 5e-5); it must not be
    usable, and say why."""
    fr, dm = modal_curves(20.0, 1e-3, 1e-3, 0.005, 1e-4)
    d = svam_decay(
        fr, dm, a0=1e-4, duration=2.0, fs=2000.0, quantity="acceleration",
        noise=0.01, second=0.0, rng=np.random.default_rng(0),
    )  # fmt: skip
    fit = fit_decay(d.t, d.y, quantity="displacement", band=(15.0, 25.0))
    assert not fit.success
    assert fit.verdict().startswith("NOT usable: y read as displacement")
    assert "quantity='acceleration'" in fit.verdict()


# ------------------------------------------------------------------ the other entries
def test_sweep_curve_and_sweep_modes_flag_millimetres_with_the_right_phase():
    """Before, sweep_curve flagged only a half-period phase shift with w X > 10 m/s; a record
    in mm/s^2 with its phase right went through."""
    f, F, A, ph = (np.concatenate(v) for v in zip(_sweep()[:4], _sweep(X_peak=1.5e-4)[:4]))
    level = np.repeat([0, 1], 41)
    good = sweep_curve(f, F, A, ph, level=level, degree=1)
    assert not any("vibration test" in w for w in good.warnings)
    bad = sweep_curve(f, F, 1000 * A, ph, level=level, degree=1)
    assert not bad.success and "mm/s^2 given as m/s^2" in " ".join(bad.failures)
    modes = sweep_modes(f, F, 1000 * A, ph)
    assert not modes.success and "response read as acceleration" in modes.verdict()
    assert sweep_modes(f, F, A, ph).success


def test_stepped_sine_curve_flags_acceleration_declared_displacement():
    levels = []
    for X in (5e-5, 1e-4, 2e-4):
        f, F, _, _, H = _sweep(X_peak=X)
        acc_frf = H * (1j * 2 * math.pi * f) ** 2  # per newton, in m/s^2/N
        levels.append((f, acc_frf, F[0]))
    assert stepped_sine_curve(levels, quantity="acceleration").success
    bad = stepped_sine_curve(levels, quantity="displacement")
    assert not bad.success and "levels read as displacement" in bad.verdict()


def test_free_decay_modes_flags_a_record_declared_displacement():
    t, a = _decay(duration=2.0)
    t2, b = _decay(duration=2.0, x0=0.6 * X0, seed=1)
    recs = {"s1": (0.1, a), "s2": (0.5, b)}
    bad = free_decay_modes(t, recs, quantity="displacement", bands={"m1": (70, 90)})
    assert not bad.success and "records['s1'] read as displacement" in bad.verdict()
    good = free_decay_modes(t, recs, quantity="acceleration", bands={"m1": (70, 90)})
    assert not any("vibration test" in w for w in good.warnings)


def test_fit_loops_flags_millimetres_given_as_metres():
    """A 1 Hz loop of +-20 mm given in mm as m: 20 m at 1 Hz moves at 126 m/s."""
    t = np.arange(4000) / 1000.0
    u = 0.02 * np.sin(2 * math.pi * t)
    F = 1e3 * np.tanh(u / 0.005)
    ok = fit_loops(t, u, F, n_starts=1)
    assert not any("vibration test" in w for w in ok.warnings)
    bad = fit_loops(t, 1000 * u, F, n_starts=1)
    assert not bad.success and "u read as displacement" in " ".join(bad.failures)


# ------------------------------------------------------------------ the rule itself
def test_levels_are_the_closed_form_velocity_and_acceleration():
    """w X and w^2 X against the limits: just inside passes, just outside fails."""
    from iwan_element.base.plausibility import A_MAX, V_MAX, level_failure, record_failure

    f = np.array([100.0])
    w = 2 * math.pi * f
    X_v = 0.99 * V_MAX / w  # velocity just inside, acceleration 6.2e3 m/s^2
    assert level_failure(X_v, f, quantity="displacement", name="y") == ""
    assert level_failure(1.02 * V_MAX / w, f, quantity="displacement", name="y")
    f_hi = np.array([2000.0])
    w_hi = 2 * math.pi * f_hi
    X_a = 1.01 * A_MAX / w_hi**2  # 2 kHz: 1.6 m/s but 2.02e4 m/s^2
    assert 1.01 * A_MAX / w_hi[0] < V_MAX
    why = level_failure(X_a, f_hi, quantity="acceleration", name="y")
    assert "mm/s^2" in why
    # a micrometre record at 100 kHz with a nanometre of noise is a displacement
    rng = np.random.default_rng(0)
    t = np.arange(20000) / 1e5
    y = 1e-6 * np.sin(2 * math.pi * 500 * t) + 1e-9 * rng.standard_normal(t.size)
    assert record_failure(y, 1e-5, quantity="displacement", name="y") == ""
    assert "quantity='acceleration'" in record_failure(
        40 * np.sin(2 * math.pi * 80 * t), 1e-5, quantity="displacement", name="y"
    )


# ------------------------------------------------------------------ the real records
_SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
if not _SHARED.is_dir():
    _SHARED = Path(__file__).resolve().parents[3] / "shared" / "data"
needs_shared = pytest.mark.skipif(
    not (_SHARED / "brb-hammer").is_dir(),
    reason="../shared/data is absent (GPL-3.0 and CC BY-SA data, read from ../shared only)",
)


@needs_shared
def test_the_rule_is_quiet_on_the_real_records():
    """BRB hammer accelerations (3 channels, 72 g at the hit; the first mode's curve), the BRB
        force-controlled
    stepped sines (70 m/s^2 at 80 Hz), the ARTS damper loops (25 mm at 1 Hz): no flag."""
    from iwan_element.base.plausibility import record_failure

    recs = {}
    for i, x in ((1, 0.0254), (2, 0.5549), (3, 0.6438)):
        t, a = np.loadtxt(
            _SHARED / "brb-hammer" / f"hammer_acc{i}.csv", delimiter=",", skiprows=1
        ).T
        recs[f"acc{i}"] = (x, a)
        assert record_failure(a, t[1] - t[0], quantity="acceleration", name="y") == ""
    keep = (t >= 0.0) & (t < 2.0)
    c = amplitude_curve(t[keep], recs["acc3"][1][keep], quantity="acceleration", band=(70, 90))
    assert not any("vibration test" in w for w in c.warnings)
    lv, f, F, A, ph = np.loadtxt(
        _SHARED / "brb-steppedsine-fc" / "fc_sweeps.csv", delimiter=",", skiprows=1
    ).T
    sw = sweep_curve(f, F, A, ph, level=lv)
    assert not any("vibration test" in w for w in sw.warnings)
    for name in sorted((_SHARED / "arts-damper").glob("ds1_*.csv"))[:4]:
        t, u, F = np.loadtxt(name, delimiter=",", skiprows=1).T
        assert record_failure(u, t, quantity="displacement", name="u") == "", name
