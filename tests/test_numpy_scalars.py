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
