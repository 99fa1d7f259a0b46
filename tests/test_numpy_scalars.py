"""Numbers from numpy count as numbers: a mode given as ``np.int64`` or an amplitude as
``np.float32`` (what indexing an array or reading a file gives) is taken as its Python
equivalent, not refused with "must be > 0" / "a mode >= 1" when it is."""

from __future__ import annotations

import numpy as np
import pytest
from iwan_element.models.calibration.vibration import _fit_points

from iwan_element import AmplitudeCurve, models


def test_a_float32_release_amplitude_is_the_same_release():
    p = models.preset("brake-reuss")
    X = np.float32(2e-4)
    a = models.ringdown(p, amplitude={1: X}, cycles=8)
    b = models.ringdown(p, amplitude={1: float(X)}, cycles=8)
    np.testing.assert_array_equal(a.curve.amplitude, b.curve.amplitude)
    np.testing.assert_array_equal(a.curve.damping_ratio, b.curve.damping_ratio)


def test_a_numpy_integer_mode_keys_a_floor_curve():
    p = models.preset("brake-reuss")
    X = np.geomspace(*p.amplitude_range, 6)
    curve = AmplitudeCurve(amplitude=X, frequency=np.full(6, 297.7), damping_ratio=np.full(6, 1e-3))
    floors, *_ = _fit_points(p, curve, {np.int64(2): curve}, ("friction",), 1)
    assert list(floors) == [2] and type(next(iter(floors))) is int
    for bad in ({True: curve}, {np.int64(1): curve}, {np.int64(0): curve}, {2.0: curve}):
        with pytest.raises(ValueError, match="floors must map modes"):
            _fit_points(p, curve, bad, ("friction",), 1)


# ------------------------------------------------------------------ the sweep over entries
_B = models.preset("brake-reuss")


def _plain(v):
    """The Python number a numpy scalar stands for (the reference call's argument)."""
    return int(v) if isinstance(v, np.integer) else float(v)


#: (entry, call with the scalar, its value, the numpy types it is tried as)
_FLOATS = (np.float32, np.float64, np.int64)
_INTS = (np.int64, np.int32, np.uint8)
_ENTRIES = [
    (
        "Specimen.replace(damping_floor)",
        lambda v: _B.replace(damping_floor=v).floor(1),
        2e-3,
        _FLOATS[:2],
    ),
    (
        "Specimen.replace(modal_damping)",
        lambda v: _B.replace(modal_damping=(v,)).floor(1),
        3e-3,
        _FLOATS[:2],
    ),
    ("Specimen.replace(beta)", lambda v: _B.replace(beta=v).interface.beta, 0.25, _FLOATS[:2]),
    ("Specimen.replace(n_points)", lambda v: _B.replace(n_points=v).interface.n_points, 5, _INTS),
    ("Specimen.floor(mode)", lambda v: _B.floor(v), 2, _INTS),
    (
        "Impact(position)",
        lambda v: models.Impact(position=v, peak_force=100.0, contact_time=1e-4).position,
        0.3,
        _FLOATS,
    ),
    ("natural_frequencies(n_modes)", lambda v: models.natural_frequencies(_B, n_modes=v), 3, _INTS),
    (
        "modal_amplitude_curve(mode)",
        lambda v: models.modal_amplitude_curve(_B, mode=v, amplitude=[1e-5, 2e-5]).frequency,
        1,
        _INTS,
    ),
    ("reduced_model(n_modes)", lambda v: models.reduced_model(_B, n_modes=v).omega_all, 4, _INTS),
]


@pytest.mark.parametrize(
    "entry, typ",
    [(e, t) for e in _ENTRIES for t in e[3]],
    ids=[f"{e[0]}-{t.__name__}" for e in _ENTRIES for t in e[3]],
)
def test_numpy_scalars_give_the_python_numbers_result(entry, typ):
    """Each entry called with a numpy scalar gives what it gives with the same value as a
    Python number (refusals before: np.float32 damping floors, modal damping and impact
    positions; np.int64 interface points and modes)."""
    name, call, value, _ = entry
    arg = typ(value)
    got, want = call(arg), call(_plain(arg))
    np.testing.assert_array_equal(np.asarray(got, dtype=float), np.asarray(want, dtype=float))
    assert type(got) is type(want) or isinstance(got, np.ndarray)


def test_numpy_scalars_fields_are_stored_as_python_numbers():
    """A specimen built from numpy scalars holds Python numbers (its to_dict and JSON are
    those of the float specimen)."""
    s = _B.replace(damping_floor=np.float32(2e-3), n_points=np.int64(5))
    assert type(s.interface.damping_floor) is float and type(s.interface.n_points) is int
    # and numpy booleans or non-integral floats for integers are still refused
    for bad in (np.bool_(True), np.float64(5.5)):
        with pytest.raises(ValueError, match="n_points"):
            _B.replace(n_points=bad)


def test_a_numpy_integer_step_count_is_the_same_ringdown():
    a = models.ringdown(_B, amplitude=2e-4, cycles=8, steps_per_period=np.int64(32))
    b = models.ringdown(_B, amplitude=2e-4, cycles=8, steps_per_period=32)
    np.testing.assert_array_equal(a.curve.amplitude, b.curve.amplitude)
