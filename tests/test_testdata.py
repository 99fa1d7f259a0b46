"""Test data in, clean cycles out: CSV reading, units, reversal finding, cycle splitting.

Independent routes: the loop area of a simulated cycle (trapezoids over the IwanJoint force
history) is checked against the closed-form dissipation (docs/equations.md section 2), its force
amplitude against the backbone and its secant stiffness against paper eq. 24.
"""

from __future__ import annotations

import numpy as np
import pytest

from iwan_element import IwanJoint, IwanParameters, dissipation, force_amplitude, secant_stiffness
from iwan_element.identify.files.csv_input import load_test
from iwan_element.identify.loops.cycles import find_reversals, split_cycles
from iwan_element.identify.loops.testdata import TestData, simulate_test

P = IwanParameters(Fs=9e3, KT=5e7, chi=-0.5, beta=0.5)  # phi_max = 0.324 mm


def _write_csv(
    path,
    t,
    u_mm,
    F_kN,
    *,
    header="time [s],displacement [mm],force [kN]",
    comment="# synthetic test record\n",
    sep=",",
):
    rows = "\n".join(f"{a:.6f}{sep}{b:.9g}{sep}{c:.9g}" for a, b, c in zip(t, u_mm, F_kN))
    path.write_text(comment + (header + "\n" if header else "") + rows + "\n")
    return path


@pytest.fixture(scope="module")
def clean():
    return simulate_test(P, np.array([0.1, 0.4, 0.8, 1.5]) * P.phi_max, cycles=3)


def test_cycle_quantities_match_closed_forms(clean):
    usable = clean.usable_cycles()
    assert len(usable) == 8  # 3 per amplitude, the transition one flagged
    for c in usable:
        # loop area (trapezoids) against the closed form of D (docs/equations.md section 2)
        assert c.D == pytest.approx(dissipation(c.u0, P), rel=2e-4)
        assert c.F0 == pytest.approx(force_amplitude(c.u0, P), rel=2e-3)
        assert c.k_sec == pytest.approx(secant_stiffness(c.u0, P), rel=2e-3)
    amps = sorted({round(c.u0 / P.phi_max, 3) for c in usable})
    assert amps == [0.1, 0.4, 0.8, 1.5]


def test_amplitude_transitions_are_flagged_not_closed(clean):
    flagged = [c for c in clean.cycles if not c.closed]
    assert len(flagged) == 3  # one per amplitude change
    assert all("does not close" in c.flags[0] for c in flagged)


def test_reversals_robust_to_noise():
    rng = np.random.default_rng(3)
    n = np.arange(5000)
    u = 1e-4 * np.sin(2 * np.pi * n / 1000) + rng.normal(0, 2e-7, n.size)  # 5 periods
    rev = find_reversals(u)
    assert len(rev) == 10
    assert np.allclose(u[rev[::2]], 1e-4, atol=2e-6) and np.allclose(u[rev[1::2]], -1e-4, atol=2e-6)
    # a dead band below the noise would see many spurious reversals
    assert len(find_reversals(u, hysteresis=1e-7)) > 100


def test_noisy_cycles_keep_amplitudes_unbiased():
    sim = simulate_test(
        P,
        np.array([0.3, 0.6]) * P.phi_max,
        cycles=4,
        force_noise=40.0,
        displacement_noise=2e-7,
        seed=11,
    )
    tab = sim.amplitude_table()
    assert len(tab["u0"]) == 6  # 4 periods: 3 closed cycles per amplitude
    # force amplitude from the noisy peaks: unbiased within a few tenths of a percent
    ratio = tab["F0"] / force_amplitude(tab["u0"], P)
    assert abs(np.mean(ratio) - 1) < 3e-3
    assert np.allclose(tab["D"], dissipation(tab["u0"], P), rtol=0.05)


def test_drift_is_flagged():
    t = np.arange(4001) / 20.0
    u = 1e-4 * np.sin(2 * np.pi * 0.02 * t)
    F = IwanJoint(P).force_history(u)
    F = F + np.where(t > 100.0, 0.3 * np.abs(F).max(), 0.0) * np.clip((t - 100) / 50, 0, 1)
    cyc = split_cycles(t, u, F)
    assert not cyc[0].drifting and cyc[-1].drifting
    assert "centre drifts" in cyc[-1].flags


def test_load_test_converts_units_and_records_them(tmp_path, clean):
    path = _write_csv(tmp_path / "a.csv", clean.t, clean.u * 1e3, clean.F * 1e-3)
    data = load_test(path)
    assert data.units == {"time": "s", "displacement": "mm", "force": "kN"}
    assert np.allclose(data.u, clean.u, rtol=1e-8, atol=1e-15)
    assert np.allclose(data.F, clean.F, rtol=1e-8, atol=1e-9)
    assert len(data.cycles) == len(clean.cycles)
    assert data.source == str(path)
    assert not data.u.flags.writeable  # results are read-only
    assert "usable" in data.report()


def test_load_test_columns_by_index_and_other_units(tmp_path, clean):
    # no header, semicolons, columns reordered, displacement in micrometres, force in N
    rows = np.column_stack([clean.F, clean.t, clean.u * 1e6])
    path = tmp_path / "b.csv"
    path.write_text("\n".join(";".join(f"{x:.10g}" for x in r) for r in rows))
    data = load_test(path, displacement_unit="um", force_unit="N", time_unit="s", columns=(1, 2, 0))
    assert np.allclose(data.u, clean.u, rtol=1e-8, atol=1e-15)
    assert np.allclose(data.F, clean.F, rtol=1e-8)


def test_load_test_accepts_a_byte_order_mark(tmp_path, clean):
    path = _write_csv(tmp_path / "bom.csv", clean.t, clean.u * 1e3, clean.F * 1e-3, comment="")
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    assert len(load_test(path).cycles) == len(clean.cycles)


def test_load_test_columns_by_name(tmp_path, clean):
    path = _write_csv(
        tmp_path / "c.csv", clean.t, clean.u * 1e3, clean.F * 1e-3, header="seconds,ext_mm,load_kN"
    )
    with pytest.raises(ValueError, match="cannot tell which column"):
        load_test(path)
    with pytest.raises(
        ValueError,
        match=r"unit of the time, displacement, force column\(s\) "
        r"is not stated: the header names the columns \['seconds'",
    ):
        load_test(path, columns=("seconds", "ext_mm", "load_kN"))
    data = load_test(
        path,
        columns=("seconds", "ext_mm", "load_kN"),
        time_unit="s",
        displacement_unit="mm",
        force_unit="kN",
    )
    assert len(data.cycles) == len(clean.cycles)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"displacement_unit": ""}, "displacement_unit is missing"),
        ({"force_unit": ""}, "force_unit is missing"),
        ({"force_unit": "tonne"}, "not a known unit"),
        ({"time_unit": "h"}, "not a known unit"),
        ({"displacement_unit": "m"}, "labelled in 'mm'"),
    ],
)
def test_load_test_unit_errors(tmp_path, clean, kwargs, match):
    path = _write_csv(tmp_path / "d.csv", clean.t, clean.u * 1e3, clean.F * 1e-3)
    with pytest.raises(ValueError, match=match):
        load_test(path, **kwargs)


def test_load_test_bad_content(tmp_path, clean):
    t, u, F = clean.t.copy(), clean.u * 1e3, clean.F * 1e-3
    u_nan = u.copy()
    u_nan[50] = np.nan
    with pytest.raises(ValueError, match="displacement column contains NaN.*line 53"):
        load_test(_write_csv(tmp_path / "nan.csv", t, u_nan, F))
    t_bad = t.copy()
    t_bad[100] = t_bad[99]
    with pytest.raises(ValueError, match="strictly increasing.*samples 99..100"):
        load_test(_write_csv(tmp_path / "time.csv", t_bad, u, F))
    with pytest.raises(ValueError, match="force column .* is all zero"):
        load_test(_write_csv(tmp_path / "zero.csv", t, u, 0 * F))
    n = 1500  # one and a half periods: one cycle only
    with pytest.raises(ValueError, match="found 1 complete cycle"):
        load_test(_write_csv(tmp_path / "short.csv", t[:n], u[:n], F[:n]))
    (tmp_path / "text.csv").write_text("time [s],displacement [mm],force [kN]\n0,0,0\n0.1,abc,1\n")
    with pytest.raises(ValueError, match="line 3 .* displacement value 'abc' is not a number"):
        load_test(tmp_path / "text.csv")
    with pytest.raises(ValueError, match="cannot read"):
        load_test(tmp_path / "missing.csv")


def test_unclosed_loops_give_a_clear_error():
    # a ratcheting record: every loop ends higher than it started
    t = np.arange(8001) / 20.0
    u = 1e-4 * np.sin(2 * np.pi * 0.02 * t) + 2e-5 * t / 50.0
    F = IwanJoint(P).force_history(u)
    data = TestData.from_arrays(t, u, F)
    assert not any(c.closed for c in data.cycles)
    with pytest.raises(ValueError, match="only 0 of .* cycles close without drift.*does not close"):
        data.amplitude_table()


def test_inputs_are_not_modified(clean):
    t, u, F = clean.t.copy(), clean.u.copy(), clean.F.copy()
    t0, u0, F0 = t.copy(), u.copy(), F.copy()
    split_cycles(t, u, F)
    data = TestData.from_arrays(t, u, F)
    assert np.array_equal(t, t0) and np.array_equal(u, u0) and np.array_equal(F, F0)
    assert u.flags.writeable and data.u is not u
    tab = data.amplitude_table()
    tab["u0"][:] = 0.0  # the table is a copy
    assert data.cycles[0].u0 > 0


def test_simulate_test_validates():
    with pytest.raises(ValueError, match="amplitude must all be > 0"):
        simulate_test(P, [1e-4, -1e-4])
    with pytest.raises(ValueError, match="sample_rate"):
        simulate_test(P, [1e-4], sample_rate=0.1)
    with pytest.raises(ValueError, match="cycles must be an integer"):
        simulate_test(P, [1e-4], cycles=0)


def test_all_zero_displacement_says_it_does_not_vary():
    """Issue 14: was "hysteresis must be in (0, inf), got 0.0"."""
    from iwan_element import find_reversals

    z = np.zeros(200)
    F = np.sin(np.arange(200) / 5.0)
    for call in (
        lambda: split_cycles(None, z, F),
        lambda: find_reversals(z),
        lambda: TestData.from_arrays(np.arange(200.0), z, F),
    ):
        with pytest.raises(ValueError, match=r"u \(displacement\) does not vary"):
            call()


def test_clean_coarsely_sampled_record_shows_no_displacement_noise(tmp_path):
    """Issue 14: the curvature of a clean record sampled 50 times a period was taken for
    displacement noise (second differences), and the fit warned about it."""
    import warnings as _w

    from iwan_element import fit_loops

    p = IwanParameters(9e3, 5e7, -0.5, 0.5)
    d = simulate_test(p, np.array([0.2, 0.5, 1.0, 1.5]) * p.phi_max, cycles=2, sample_rate=1.0)
    path = tmp_path / "clean.csv"
    np.savetxt(
        path,
        np.c_[d.t, d.u * 1e3, d.F * 1e-3],
        delimiter=",",
        header="time [s],displacement [mm],force [kN]",
        comments="",
    )
    with _w.catch_warnings(record=True) as caught:
        _w.simplefilter("always")
        data = load_test(path)
        r = fit_loops(data.t, data.u, data.F, smooth=0)
    assert not any("noise" in str(c.message) for c in caught)
    assert r.noise["displacement"] < 1e-4 * data.cycles[0].u0
    assert r.details["smooth"] == 0
