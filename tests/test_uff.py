"""UFF dataset 58 and stepped-sine CSV input: units from the file, to SI.

The UFF files are written by pyuff itself (an independent writer) in a temporary directory
and read back; the signals are analytic (a decaying sinusoid, a single-mode FRF), so what
is read is checked against the values written, scaled by the units' definitions.
"""

import math
from pathlib import Path

import numpy as np
import pytest

from iwan_element import (
    UffRecord,
    amplitude_curve,
    read_sweep_csv,
    read_uff,
    stepped_sine_curve,
    sweep_curve,
)

pyuff = pytest.importorskip("pyuff", reason="pyuff is the optional 'uff' extra")

G = 9.80665
SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "brb-steppedsine-fc"
if not SHARED.is_dir():
    SHARED = Path("/work/shared/data/brb-steppedsine-fc")


def _write(path, sets):
    uff = pyuff.UFF(str(path))
    uff.write_sets(sets, mode="overwrite")
    return path


def _time_set(t, y, unit, spec=12, xunit="s"):
    return pyuff.prepare_58(
        func_type=1,
        id1="ringdown acc3",
        rsp_node=3,
        rsp_dir=2,
        ref_node=3,
        ref_dir=2,
        data=y,
        x=t,
        abscissa_axis_units_lab=xunit,
        abscissa_spec_data_type=17,
        ordinate_axis_units_lab=unit,
        ordinate_spec_data_type=spec,
        orddenom_axis_units_lab="NONE",
        orddenom_spec_data_type=0,
        binary=0,
    )


def _frf_set(f, H, num, den, spec=12, xunit="Hz"):
    return pyuff.prepare_58(
        func_type=4,
        id1="frf 3:+Y/3:+Y",
        rsp_node=3,
        rsp_dir=2,
        ref_node=3,
        ref_dir=2,
        data=H,
        x=f,
        abscissa_axis_units_lab=xunit,
        abscissa_spec_data_type=18,
        ordinate_axis_units_lab=num,
        ordinate_spec_data_type=spec,
        orddenom_axis_units_lab=den,
        orddenom_spec_data_type=13,
        binary=0,
    )


def _ringdown(fs=2000.0, T=4.0, f0=40.0, zeta=0.004, a0=50.0):
    t = np.arange(int(fs * T)) / fs
    w = 2 * math.pi * f0
    return t, a0 * np.exp(-zeta * w * t) * np.cos(w * math.sqrt(1 - zeta**2) * t)


def test_time_series_in_g_is_read_in_si_and_feeds_amplitude_curve(tmp_path):
    t, a = _ringdown()
    path = _write(tmp_path / "ringdown.uff", [_time_set(t, a / G, "g")])
    (r,) = read_uff(path)
    assert isinstance(r, UffRecord) and r.kind == "time" and r.quantity == "acceleration"
    assert r.response == (3, 2) and r.name == "ringdown acc3"
    np.testing.assert_allclose(r.x, t, atol=1e-9)
    np.testing.assert_allclose(r.y, a, rtol=1e-6, atol=1e-9 * np.abs(a).max())
    c = amplitude_curve(r.x, r.y, quantity=r.quantity, band=(30.0, 50.0))
    np.testing.assert_allclose(c.damping_ratio, 0.004, rtol=0.02)
    assert np.all(np.abs(c.frequency / 40.0 - 1) < 1e-4)


def test_frf_in_mm_s2_per_kN_feeds_stepped_sine_curve(tmp_path):
    f = np.linspace(45.0, 55.0, 41)
    w, wr, zeta, c = 2 * np.pi * f, 2 * np.pi * 50.0, 0.01, 0.5
    H_si = -(w**2) * c / (wr**2 - w**2 + 2j * zeta * wr * wr)  # [m/s^2/N]
    path = _write(
        tmp_path / "frf.uff",
        [_frf_set(f, H_si * 1e3 * 1e3, "mm/s^2", "kN"), _time_set(*_ringdown(), "m/s^2")],
    )
    (frf,) = read_uff(path, kind="frf")
    assert frf.quantity == "acceleration" and frf.units == "Hz; mm/s^2; kN"
    np.testing.assert_allclose(frf.y, H_si, rtol=1e-6)
    curve = stepped_sine_curve([(frf.x, frf.y, 1.0)], quantity=frf.quantity)
    assert curve.frequency[0] == pytest.approx(50.0, rel=1e-6)
    assert curve.damping_ratio[0] == pytest.approx(zeta, rel=1e-4)
    assert [r.kind for r in read_uff(path)] == ["frf", "time"]


def test_frf_with_unit_in_one_label_and_rad_s_abscissa(tmp_path):
    f = np.linspace(45.0, 55.0, 11)
    H = 1e-3 / (1 + 1j * (f - 50.0))
    path = _write(tmp_path / "frf.uff", [_frf_set(2 * np.pi * f, H / G, "g/N", "", xunit="rad/s")])
    (r,) = read_uff(path)
    np.testing.assert_allclose(r.x, f, rtol=1e-5)  # pyuff writes 6 digits
    np.testing.assert_allclose(r.y, H, rtol=1e-6)


def test_unknown_or_contradicting_units_are_refused(tmp_path):
    t, a = _ringdown(T=0.5)
    with pytest.raises(ValueError, match="ordinate unit 'furlong/s' is not known"):
        read_uff(_write(tmp_path / "a.uff", [_time_set(t, a, "furlong/s")]))
    with pytest.raises(ValueError, match="specific data type 8 says displacement"):
        read_uff(_write(tmp_path / "b.uff", [_time_set(t, a, "m/s^2", spec=8)]))
    with pytest.raises(ValueError, match="abscissa unit 'fortnight'"):
        read_uff(_write(tmp_path / "c.uff", [_time_set(t, a, "m/s^2", xunit="fortnight")]))
    with pytest.raises(ValueError, match="names no force"):
        read_uff(_write(tmp_path / "d.uff", [_frf_set(t[1:20] + 1, a[1:20] + 0j, "m/s^2", "")]))
    with pytest.raises(ValueError, match="kind must be"):
        read_uff(tmp_path / "a.uff", kind="modes")
    with pytest.raises(ValueError, match="not a file"):
        read_uff(tmp_path / "missing.uff")


# ---------------------------------------------------------------- sweep CSV
def _sweep_rows():
    f = np.tile(np.linspace(48.0, 52.0, 17), 2)
    lev = np.repeat([1, 2], 17)
    w, wr = 2 * np.pi * f, 2 * np.pi * 50.0 * (1 - 0.004 * (lev - 1))
    F = lev * (1 - 0.3 * np.exp(-((f - 50.0) ** 2)))
    H = -(w**2) * 0.5 / (wr**2 - w**2 + 2j * 0.01 * (1 + 0.3 * (lev - 1)) * wr * w)
    return lev, f, F, np.abs(H) * F, np.angle(H)


def test_sweep_csv_columns_found_by_unit_and_converted(tmp_path):
    lev, f, F, A, ph = _sweep_rows()
    p = tmp_path / "sweeps.csv"
    rows = ["phase [deg],F [kN],sweep,A [mm/s^2],f [rad/s]"] + [
        f"{float(math.degrees(a))!r},{float(b / 1e3)!r},{int(c)},{float(d * 1e3)!r},"
        f"{float(2 * math.pi * e)!r}"
        for a, b, c, d, e in zip(ph, F, lev, A, f)
    ]
    p.write_text("\n".join(rows) + "\n")
    d = read_sweep_csv(p)
    assert d["quantity"] == "acceleration"
    for key, ref in (("f", f), ("F", F), ("response", A), ("phase", ph), ("level", lev)):
        np.testing.assert_allclose(d[key], ref, rtol=1e-12)
    ref_curve = sweep_curve(f, F, A, ph, level=lev)
    np.testing.assert_allclose(sweep_curve(**d).damping_ratio, ref_curve.damping_ratio, rtol=1e-9)


def test_sweep_csv_bad_headers(tmp_path):
    p = tmp_path / "bad.csv"
    p.write_text("f [Hz],F [N],A [furlong],phase [rad]\n1,1,1,1\n")
    with pytest.raises(ValueError, match="unit 'furlong' is not known"):
        read_sweep_csv(p)
    p.write_text("f [Hz],F [N],A [m/s^2]\n1,1,1\n")
    with pytest.raises(ValueError, match=r"no column for \['phase'\]"):
        read_sweep_csv(p)
    p.write_text("f [Hz],f [rad/s],F [N],A [m],phase [rad]\n1,1,1,1,1\n")
    with pytest.raises(ValueError, match="two f columns"):
        read_sweep_csv(p)
    p.write_text("freq,F [N],A [m],phase [rad]\n1,1,1,1\n")
    with pytest.raises(ValueError, match="no unit in brackets"):
        read_sweep_csv(p)


@pytest.mark.skipif(
    not (SHARED / "fc_sweeps.csv").is_file(),
    reason="GPL-3.0 BRB sweeps are read from ../shared only; not present here",
)
def test_shared_brb_sweep_file_reads_by_its_header():
    d = read_sweep_csv(SHARED / "fc_sweeps.csv")
    assert d["quantity"] == "acceleration" and d["f"].size == 164
    assert set(np.unique(d["level"])) == {1.0, 2.0, 3.0, 4.0}
    assert 79.1 < d["f"].min() < d["f"].max() < 81.3


def test_a_kind_the_file_does_not_hold_is_refused_not_an_empty_list(tmp_path):
    """Issue 34: read_uff(kind="frf") on a file of time series returned [] with no word."""
    path = _write(tmp_path / "ringdown.uff", [_time_set(*_ringdown(), "m/s^2")])
    with pytest.raises(
        ValueError,
        match=r"no dataset 58 of kind='frf'.*1 record\(s\) of kind "
        r"\['time'\]",
    ):
        read_uff(path, kind="frf")
    assert len(read_uff(path, kind="time")) == 1


def test_a_ragged_sweep_csv_row_is_named_by_its_line(tmp_path):
    """Issue 34: a row with a missing field surfaced numpy's 'inhomogeneous shape' message."""
    path = tmp_path / "ragged.csv"
    path.write_text("f [Hz],F [N],a [m/s^2],phase [rad]\n49,1,2,0.1\n50,1,2\n51,1,2,0.2\n")
    with pytest.raises(ValueError, match="line 3 has 3 fields where the header has 4"):
        read_sweep_csv(path)
