"""Effects declare what they are (structure, data needs); the declarations are checked
against what the elements do, and the diagnosis takes its untestable reasons from them."""

import numpy as np
import pytest

from iwan_element import IwanJoint, IwanParameters
from iwan_element.diagnose.loops.prepare import check_record, prepare_record, untestable
from iwan_element.effects import EFFECTS, ViscousDamping, make_effect
from iwan_element.effects.base import NEEDS, STRUCTURES

P = IwanParameters(Fs=1000.0, KT=1e6, chi=-0.5, beta=0.2)
Q = IwanParameters(Fs=600.0, KT=2.5e6, chi=-0.2, beta=1.0)


#: Parameters of each effect that change the force of joint P by a visible amount on
#: :func:`_history` (2 mm); a new effect adds its own.
VALUES = {
    "asymmetric_slip": {"asymmetry": 0.2},
    "backlash": {"gap": 3e-4, "drag": 5.0},
    "breakaway": {"ratio": 1.3},
    "hardening": {"k3": 6e10},
    "macroslip_onset": {"k_2": 2e5, "u_s": 3e-4, "shape": 0.3},
    "pinning_stiffness": {"k_p": 3e5, "delta": 5e-4},
    "slip_degradation": {"rate": 1e-2},
    "viscous_damping": {"c": 1e4},
}


def _history(x=2e-3, n=600):
    t = np.linspace(0.0, 3.0, n)
    return t, x * np.sin(2 * np.pi * t) * (0.4 + 0.2 * t)


#: What each shipped effect is, from its physics (module docstrings): a new effect adds its
#: own line, and a changed declaration must change this table too.
KINDS = {
    "viscous_damping": ("parallel", ("rate",)),
    "hardening": ("parallel", ()),
    "pinning_stiffness": ("parallel", ()),
    "macroslip_onset": ("parallel", ()),
    "backlash": ("series", ()),
    "asymmetric_slip": ("slider", ()),
    "breakaway": ("slider", ()),
    "slip_degradation": ("energy", ()),
}


def test_each_effect_declares_what_its_physics_is():
    assert {n: (c.structure, tuple(c.needs)) for n, c in EFFECTS.items()} == KINDS
    assert {s for s, _ in KINDS.values()} == set(STRUCTURES)


@pytest.mark.parametrize("name", sorted(n for n in EFFECTS if EFFECTS[n].structure == "parallel"))
def test_a_parallel_effect_adds_a_force_that_does_not_depend_on_the_joint(name):
    """Parallel: F = F_joint(u) + f(u, v, own history); the added force is the same whatever
    joint is wrapped (two joints of other strength, stiffness and shape)."""
    t, u = _history()
    v = np.gradient(u, t)
    vals = VALUES[name]
    added = []
    for p in (P, Q):
        el = make_effect(name, IwanJoint(p), **vals)
        added.append(el.force_history(u, v) - IwanJoint(p).force_history(u, v))
    assert np.max(np.abs(added[0])) > 10.0  # newtons: the effect acts
    # the joint forces (up to 1 kN) cancel to round-off in the differences
    np.testing.assert_allclose(added[0], added[1], rtol=1e-9, atol=1e-12 * P.Fs)


@pytest.mark.parametrize("name", sorted(n for n in EFFECTS if EFFECTS[n].slider_level))
def test_a_slider_law_wraps_the_plain_joint_only(name):
    inner = make_effect("viscous_damping", IwanJoint(P), c=10.0)
    with pytest.raises(ValueError, match="plain Iwan joint"):
        make_effect(name, inner, **VALUES[name])


@pytest.mark.parametrize("name", sorted(n for n in EFFECTS if EFFECTS[n].structure == "series"))
def test_a_series_effect_gives_the_joints_own_displacement(name):
    """Series: the joint sees its own displacement (``joint_path``), and the force is the
    plain joint's force along that path."""
    t, u = _history()
    el = make_effect(name, IwanJoint(P), **VALUES[name])
    uj = el.joint_path(u)
    np.testing.assert_allclose(
        el.force_history(u, np.gradient(u, t)),
        IwanJoint(P).force_history(uj, np.zeros_like(uj)),
        rtol=1e-9,
        atol=1e-9 * P.Fs,
    )


def test_an_inconsistent_declaration_is_refused_when_the_class_is_made():
    with pytest.raises(TypeError, match="structure"):
        type("Odd", (ViscousDamping,), {"effect": "", "structure": "beside"})
    with pytest.raises(TypeError, match="needs"):
        type("Odd", (ViscousDamping,), {"effect": "", "needs": ("temperature",)})
    with pytest.raises(TypeError, match="declare structure instead"):
        type("Odd", (ViscousDamping,), {"effect": "", "slider_level": True})
    with pytest.raises(TypeError, match="must define joint_path"):
        type("Odd", (ViscousDamping,), {"effect": "", "structure": "series"})
    assert set(NEEDS) == {"rate"}


def _record(t):
    tt, u = _history()
    F = IwanJoint(P).force_history(u)
    return prepare_record(*check_record(t if t is None else tt, u, F, None, None)[:4], None, 400)


def test_untestable_reasons_come_from_the_declared_needs():
    """An effect that declares the rate need is untestable without a time vector, whatever its
    name; one that declares nothing is testable."""
    rate_probe = type("RateProbe", (ViscousDamping,), {"effect": "", "needs": ("rate",)})
    plain_probe = type("PlainProbe", (ViscousDamping,), {"effect": "", "needs": ()})
    saved = dict(EFFECTS)
    try:
        EFFECTS["rate_probe"], EFFECTS["plain_probe"] = rate_probe, plain_probe
        no_time = untestable(_record(None), ("rate_probe", "plain_probe", "backlash"))
        timed = untestable(_record("t"), ("rate_probe", "plain_probe"))
    finally:
        EFFECTS.clear()
        EFFECTS.update(saved)
    assert set(no_time) == {"rate_probe"} and "velocity is unknown" in no_time["rate_probe"]
    assert timed == {}
