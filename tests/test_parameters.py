"""IwanParameters: derived quantities (docs/equations.md section 5), validation, JSON round trip."""

import dataclasses
import json
import math

import pytest

from iwan_element import IwanParameters

# docs/equations.md section 5: (Fs, KT, chi, beta) -> R, S, phi_max
VECTORS = [
    ((3.0, 2.0, -0.1, 0.1), 0.632339, 0.181818, 2.87615),
    ((400.0, 2.5266e5, -0.5, 1.0), 1.29619e6, 1.26330e5, 2.374733e-3),
    ((1000.0, 1e6, -0.5, 0.2), 8.784105e6, 1.666667e5, 2.25e-3),
]


@pytest.mark.parametrize("args,R,S,phi_max", VECTORS)
def test_reference_vectors(args, R, S, phi_max):
    p = IwanParameters(*args)
    assert p.R == pytest.approx(R, rel=2e-6)
    assert p.S == pytest.approx(S, rel=2e-6)
    assert p.phi_max == pytest.approx(phi_max, rel=2e-6)


@pytest.mark.parametrize(
    "args", [v[0] for v in VECTORS] + [(1.0, 1.0, 0.5, 0.0), (5.0, 3.0, -0.9, 3.0)]
)
def test_definitions_consistent(args):
    """KT and Fs are recovered from the density integrals (paper eqs. 5 and 10)."""
    p = IwanParameters(*args)
    chi = p.chi
    KT = p.R * p.phi_max ** (chi + 1) / (chi + 1) + p.S
    Fs = p.R * p.phi_max ** (chi + 2) / (chi + 2) + p.S * p.phi_max
    assert KT == pytest.approx(p.KT, rel=1e-12)
    assert Fs == pytest.approx(p.Fs, rel=1e-12)
    assert p.S / p.KT == pytest.approx(p.beta / (1 + p.beta), rel=1e-12, abs=1e-15)


@pytest.mark.parametrize(
    "kw,name",
    [
        (dict(Fs=0.0), "Fs"),
        (dict(Fs=-1.0), "Fs"),
        (dict(KT=0.0), "KT"),
        (dict(KT=-2.0), "KT"),
        (dict(chi=-1.0), "chi"),
        (dict(chi=-1.5), "chi"),
        (dict(beta=-0.1), "beta"),
        (dict(Fs=math.nan), "Fs"),
        (dict(KT=math.inf), "KT"),
        (dict(chi=math.nan), "chi"),
        (dict(beta="1"), "beta"),
        (dict(Fs=True), "Fs"),
    ],
)
def test_invalid_values_name_the_argument(kw, name):
    base = dict(Fs=1.0, KT=1.0, chi=-0.5, beta=0.1)
    base.update(kw)
    with pytest.raises(ValueError, match=name):
        IwanParameters(**base)


def test_frozen_and_hashable():
    p = IwanParameters(1.0, 2.0, -0.5, 0.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.Fs = 3.0
    assert p == IwanParameters(1, 2, -0.5, 0)
    assert hash(p) == hash(IwanParameters(1.0, 2.0, -0.5, 0.0))


def test_json_round_trip(tmp_path):
    p = IwanParameters(1234.5, 6.7e7, -0.37, 0.81)
    d = p.to_dict()
    json.dumps(d)
    assert IwanParameters.from_dict(d) == p
    path = p.save(tmp_path / "p.json")
    assert IwanParameters.load(path) == p


def test_from_dict_rejects_bad_keys_and_units():
    with pytest.raises(ValueError, match="unknown keys"):
        IwanParameters.from_dict({"Fs": 1, "KT": 1, "chi": -0.5, "beta": 0, "Kt": 3})
    with pytest.raises(ValueError, match="lacks"):
        IwanParameters.from_dict({"Fs": 1, "KT": 1, "chi": -0.5})
    with pytest.raises(ValueError, match="SI"):
        IwanParameters.from_dict({"Fs": 1, "KT": 1, "chi": -0.5, "beta": 0, "units": {"Fs": "kN"}})


def test_replace_validates():
    p = IwanParameters(1.0, 2.0, -0.5, 0.0)
    assert p.replace(beta=1.0).beta == 1.0
    with pytest.raises(ValueError, match="chi"):
        p.replace(chi=-2.0)
    with pytest.raises(ValueError, match="unknown"):
        p.replace(Kt=1.0)


def test_from_dict_units_must_be_a_dict():
    with pytest.raises(ValueError, match="units"):
        IwanParameters.from_dict({"Fs": 1, "KT": 1, "chi": -0.5, "beta": 0, "units": "SI"})
