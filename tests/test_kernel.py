"""The compiled Masing kernel (``iwan_element.core.masing``) against an independent
plain-Python reference, the package's elements, the closed forms and energy balance."""

from __future__ import annotations

import os

import numpy as np
import pytest
from _helpers import params_strategy
from _masing_reference import reference_history
from hypothesis import given
from hypothesis import strategies as st
from iwan_element.models.modal.qsma import _interface_law

from iwan_element import IwanJoint, IwanJointBank, IwanParameters, dissipation
from iwan_element.core.history import History
from iwan_element.core.masing import (
    constants_from_arrays,
    masing_constants,
    masing_history,
    masing_rows,
    reversal_structure,
)


@st.composite
def histories(draw):
    """(params, u): random reversal points (fractions of phi_max, large and tiny excursions,
    nested loops), each leg sampled at a few points, some samples repeated (no motion)."""
    p = draw(params_strategy)
    pts = [0.0]
    for _ in range(draw(st.integers(1, 14))):
        if draw(st.booleans()):
            pts.append(pts[-1] + draw(st.floats(-1e-3, 1e-3)))
        else:
            pts.append(draw(st.floats(-3.0, 3.0)))
    legs = [np.linspace(a, b, draw(st.integers(2, 6)))[1:] for a, b in zip(pts[:-1], pts[1:])]
    u = np.concatenate(legs)
    if draw(st.booleans()):
        u = np.repeat(u, 2)
    return p, p.phi_max * u


def _element(p, u, tol):
    j = IwanJoint(p, reversal_tol=tol)
    out = np.empty((4, len(u)))
    for i, x in enumerate(u.tolist()):
        F, K = j.trial(x)
        j.commit()
        out[:, i] = F, K, j.work, j.dissipated_energy
    return out


@given(histories(), st.sampled_from([0.0, 1e-12, 1e-9]))
def test_kernel_equals_the_reference_and_the_elements(case, rtol):
    p, u = case
    F, K, W, D = masing_history(u, p, reversal_tol=rtol)
    Fr, Kr, anchor = reference_history(u, p, rtol * p.phi_max)
    assert np.max(np.abs(F - Fr)) <= 1e-12 * p.Fs
    assert np.max(np.abs(K - Kr)) <= 1e-12 * p.KT
    assert np.array_equal(reversal_structure(u, rtol * p.phi_max)[0], anchor)
    el = _element(p, u, rtol)
    assert np.array_equal(el, np.array([F, K, W, D]))  # IwanJoint: bit for bit
    bank = IwanJointBank([p, p], reversal_tol=rtol).force_history(np.column_stack([u, -u]))
    assert np.max(np.abs(bank[:, 0] - F)) <= 1e-12 * p.Fs
    assert np.max(np.abs(bank[:, 1] + F)) <= 1e-12 * p.Fs  # odd in u
    hist = History(u, tol=rtol * p.phi_max).forces(p)
    assert np.max(np.abs(hist - F)) <= 1e-12 * p.Fs


@given(histories())
def test_work_is_the_integral_of_the_force_and_dissipation_never_decreases(case):
    """Energy balance on an independent route: the kernel's closed-form work equals the
    trapezoidal integral of the reference force along the path, each step refined into 128
    sub-steps graded towards its ends (where a branch starts and its curvature is largest).
    Measured worst error 1.3e-4 Fs x travel on 200 random cases; a factor wrong by 2.5 % in
    the branch work exceeds the bound."""
    p, u = case
    g = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, 129)[1:]))
    fine = np.concatenate([a + (b - a) * g for a, b in zip(np.r_[0.0, u[:-1]], u)])
    _, _, W, D = masing_history(fine, p, reversal_tol=0.0)
    Fr, _, _ = reference_history(fine, p)
    x = np.r_[0.0, fine]
    f = np.r_[0.0, Fr]
    W_trap = np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(x))
    travel = np.cumsum(np.abs(np.diff(x)))
    assert np.all(np.abs(W - W_trap) <= 1e-3 * p.Fs * travel + 1e-12 * p.Fs * p.phi_max)
    assert np.all(np.diff(D) >= -1e-12 * p.Fs * p.phi_max)
    assert np.all(W - D >= -1e-9 * p.Fs * p.phi_max)  # stored energy >= 0


@pytest.mark.parametrize("chi, beta", [(-0.5, 0.2), (0.0, 0.0), (-0.9, 3.0), (1.5, 1.0)])
@pytest.mark.parametrize("amp", [0.05, 0.6, 1.0, 2.5])
def test_a_closed_cycle_dissipates_the_closed_form_energy(chi, beta, amp):
    """Loop area = dissipation formula (Segalman 2005 eq. 20 and its macroslip form): after
    the first loading to u0 the cycle u0 -> -u0 -> u0 does work = dissipation = D(u0) and
    restores the force."""
    p = IwanParameters(2e3, 5e6, chi, beta)
    u0 = amp * p.phi_max
    s = np.linspace(0.0, 1.0, 200)[1:]
    u = np.concatenate([u0 * s, u0 * (1 - 2 * s), -u0 * (1 - 2 * s)])
    F, _, W, D = masing_history(u, p)
    k = 198  # the sample at the first u0
    expected = dissipation(u0, p)
    assert W[-1] - W[k] == pytest.approx(expected, rel=1e-11)
    assert D[-1] - D[k] == pytest.approx(expected, rel=1e-11)
    assert F[-1] == pytest.approx(F[k], abs=1e-12 * p.Fs)


def test_a_batch_of_parameter_sets_is_each_row_alone():
    rng = np.random.default_rng(3)
    ps = [
        IwanParameters(
            10 ** rng.uniform(0, 4),
            10 ** rng.uniform(4, 8),
            rng.uniform(-0.9, 1),
            rng.uniform(0, 2),
        )
        for _ in range(6)
    ]
    u = np.cumsum(rng.normal(size=(6, 400)), axis=1) * 1e-5
    F, K, W, D = masing_history(u, ps)
    for k, p in enumerate(ps):
        one = masing_history(u[k], p)
        for a, b in zip((F[k], K[k], W[k], D[k]), one):
            assert np.array_equal(a, b)
    shared = masing_history(u[0], ps)[0]  # one history, every parameter set
    assert np.array_equal(shared[2], masing_history(u[0], ps[2])[0])
    C = constants_from_arrays(
        [p.Fs for p in ps], [p.KT for p in ps], [p.chi for p in ps], [p.beta for p in ps], 1e-12
    )
    C1 = np.array([masing_constants(p, 1e-12 * p.phi_max) for p in ps])
    np.testing.assert_allclose(C, C1, rtol=1e-14)
    np.testing.assert_allclose(masing_rows(C, u)[0], F, rtol=0, atol=1e-12 * max(p.Fs for p in ps))


def test_the_qsma_interface_law_is_the_virgin_curve():
    p = IwanParameters(300.0, 2e7, -0.4, 0.3)
    u = np.linspace(-2, 2, 41)[None, :] * p.phi_max * np.array([[1.0], [0.5]])
    F, K = _interface_law(
        u, np.full(41, p.Fs), np.full(41, p.KT), np.full(41, p.phi_max), p.chi, p.beta
    )
    Fr = np.array([reference_history([x], p)[0][0] for x in u.ravel()]).reshape(u.shape)
    Kr = np.array([reference_history([x], p)[1][0] for x in u.ravel()]).reshape(u.shape)
    assert np.max(np.abs(F - Fr)) <= 1e-12 * p.Fs
    assert np.max(np.abs(K - Kr)) <= 1e-12 * p.KT


def test_segments_tile_the_path():
    """The recorded branch segments of each step run from the previous sample to this one,
    end to end (the dissipation of the evaluator is summed over them)."""
    rng = np.random.default_rng(8)
    u = np.cumsum(rng.normal(size=3000))
    anchor, (step, anc, ua, ub) = reversal_structure(u, 0.0, segments=True)
    for i in (0, 1, 17, 1500, 2999):
        sel = step == i
        assert ua[sel][0] == (u[i - 1] if i else 0.0)
        assert ub[sel][-1] == u[i]
        assert np.array_equal(ua[sel][1:], ub[sel][:-1])
        assert anc[sel][-1] == anchor[i]


@pytest.mark.parametrize(
    "u, params, match",
    [
        (np.array([0.0, np.nan]), IwanParameters(1.0, 1.0, 0.0, 0.0), "u"),
        (np.zeros((2, 2, 2)), IwanParameters(1.0, 1.0, 0.0, 0.0), "u"),
        (np.zeros((3, 5)), [IwanParameters(1.0, 1.0, 0.0, 0.0)] * 2, "rows"),
        (np.zeros(4), [], "params"),
        (np.zeros(4), "joint", "params"),
    ],
)
def test_bad_input_is_refused(u, params, match):
    with pytest.raises(ValueError, match=match):
        masing_history(u, params)
    with pytest.raises(ValueError, match="reversal_tol"):
        masing_history(np.zeros(3), IwanParameters(1.0, 1.0, 0.0, 0.0), reversal_tol=1e-3)


def test_input_is_not_mutated():
    u = np.linspace(0, 1e-3, 50)
    keep = u.copy()
    masing_history(u, IwanParameters(1.0, 1e3, 0.0, 0.0))
    reversal_structure(u, 0.0, segments=True)
    assert np.array_equal(u, keep)


def test_compiled_routes_work_in_either_order_in_a_fresh_process():
    """Every compiled entry point is called from Python after the whole-history routes have
    loaded the functions they share (numba once failed to return arrays to Python from a
    cached function first compiled inside another one: 'descr is NULL')."""
    import subprocess
    import sys
    from pathlib import Path

    code = """
import numpy as np
from iwan_element import IwanJoint, IwanParameters, SlipDegradation, BreakAway, Backlash
from iwan_element.effects.engine.evaluate import Evaluator
p = IwanParameters(1.0, 100.0, -0.5, 0.2)
u = 0.02 * np.sin(np.linspace(0, 12, 400))
ev = Evaluator(u, np.zeros(400), np.arange(400), np.arange(400), tol=0.0)
ev.unit_force((0.01, -0.5, 0.2), ("slip_degradation", "backlash"),
              [{"rate": 0.5}, {"gap": 1e-3, "drag": 0.05}])
d = SlipDegradation(IwanJoint(p), rate=0.5)
d.correction_history(u, np.linspace(0, 1e-3, 400))
b = BreakAway(IwanJoint(p), ratio=1.5)
b.correction_history(u)
Backlash(d, gap=1e-3, drag=0.05).force_history(u[:50])
Backlash(b, gap=1e-3, drag=0.05).force_history(u[:50])
print("ok")
"""
    root = Path(__file__).resolve().parents[1]
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        cwd=root,
        env={**os.environ, "PYTHONPATH": str(root)},
        timeout=600,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "ok"


def test_the_warm_up_reaches_every_compiled_kernel(tmp_path):
    """tests/_warm_kernels.py (run by tests/conftest.py before the xdist workers start)
    compiles every kernel of the package: in a fresh process, after :func:`warm`, each
    ``@njit`` function of the package holds a compiled signature, or is called by one that
    does (a caller loaded from the cache carries its callees' code)."""
    import subprocess
    import sys
    from pathlib import Path

    code = """
import importlib, sys
from pathlib import Path
from numba.core.dispatcher import Dispatcher
import iwan_element
sys.path.insert(0, sys.argv[1])
from _warm_kernels import warm
root = Path(iwan_element.__file__).resolve().parent
kernels = {}
for f in sorted(root.rglob("*.py")):
    if "@njit" in f.read_text(encoding="utf-8"):
        mod = importlib.import_module(
            "iwan_element." + ".".join(f.relative_to(root).with_suffix("").parts)
        )
        for name, obj in vars(mod).items():
            if isinstance(obj, Dispatcher) and obj.py_func.__module__ == mod.__name__:
                kernels[mod.__name__ + "." + name] = obj
warm()
reached = {k for k, d in kernels.items() if d.signatures}
grew = True
while grew:
    callees = {
        k
        for k, d in kernels.items()
        for c in reached
        if any(
            kernels[c].py_func.__globals__.get(n) is d
            for n in kernels[c].py_func.__code__.co_names
        )
    }
    grew = not callees <= reached
    reached |= callees
print(len(kernels), sorted(set(kernels) - reached))
"""
    out = subprocess.run(
        [sys.executable, "-c", code, str(Path(__file__).resolve().parent)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    n, missing = out.stdout.strip().split(" ", 1)
    assert int(n) >= 30 and missing == "[]", out.stdout


@pytest.mark.parametrize("drag", [0.0, 0.05, 0.3])
def test_compiled_wear_behind_a_gap_equals_the_elements(drag):
    """The diagnosis evaluates slip degradation inside backlash (then a spring and a dashpot)
    with the elements' per-sample rule compiled; it must give their forces."""
    from iwan_element.core.history import unit_params
    from iwan_element.effects.engine.evaluate import Evaluator, build_element

    rng = np.random.default_rng(int(drag * 100) + 4)
    t = np.linspace(0.0, 6.0, 600)
    u = 0.02 * np.sin(2 * np.pi * t) + 2e-4 * rng.normal(size=t.size)
    v = np.gradient(u, t)
    shape = (0.01, -0.5, 0.2)
    names = ("slip_degradation", "backlash", "pinning_stiffness", "viscous_damping")
    keep = np.arange(0, u.size, 3)
    ev = Evaluator(u, v, keep, np.arange(u.size), tol=1e-12 * 0.02)
    assert not ev.fast(names)  # the route below, not the run-by-run one
    for rate, gap in [(0.0, 0.0), (0.8, 0.002), (3.0, 0.006)]:
        vals = [
            {"rate": rate},
            {"gap": gap, "drag": drag},
            {"k_p": 2.0, "delta": 0.01},
            {"c": 0.01},
        ]
        F = ev.unit_force(shape, names, vals)
        ref = build_element(unit_params(*shape), names, vals).force_history(u, v)[keep]
        assert np.max(np.abs(F - ref)) <= 1e-12


@pytest.mark.parametrize("drag", [0.0, 0.05, 0.3])
def test_compiled_joint_path_behind_a_gap_equals_the_element(drag):
    """The diagnosis finds the joint's own path behind a backlash run by run, compiled
    (``_series_kernel.backlash_path``): it must be ``Backlash.joint_path`` (itself checked
    against the per-sample elements in ``tests/test_effects.py``), with and without slider
    laws, through a pause and a rest at the start."""
    from iwan_element import AsymmetricSlip, Backlash, BreakAway
    from iwan_element.core.history import unit_params
    from iwan_element.effects.engine.evaluate import _constants, _laws
    from iwan_element.effects.engine.series_kernel import backlash_path

    rng = np.random.default_rng(int(drag * 100) + 9)
    p1 = unit_params(0.01, -0.5, 0.2)
    t = np.linspace(0.0, 6.0, 700)
    u = 0.02 * np.sin(2 * np.pi * t) + 3e-4 * rng.normal(size=t.size)
    u[:5] = 0.0
    u[300:310] = u[300]
    for make in (
        lambda j: [j],
        lambda j: [j, BreakAway(j, ratio=1.6)],
        lambda j: [j, AsymmetricSlip(j, asymmetry=0.2)],
    ):
        els = make(IwanJoint(p1))
        if len(els) == 2 and isinstance(els[1], AsymmetricSlip):
            els.append(BreakAway(els[1], ratio=1.3))
        for gap in (0.0, 0.002, 0.006):
            ref = Backlash(els[-1], gap=gap, drag=drag).joint_path(u)
            new = backlash_path(u, _constants(p1), *_laws(els[1:]), gap, drag)
            assert np.max(np.abs(new - ref)) <= 1e-12 * 0.02


def test_one_blas_thread_limits_and_restores():
    """The fits' BLAS limit (core.threads): one thread inside, the previous limits after."""
    from threadpoolctl import threadpool_info

    from iwan_element.base.threads import one_blas_thread

    np.linalg.svd(np.ones((4, 2)))  # a BLAS is loaded by now
    before = [
        (p["filepath"], p["num_threads"]) for p in threadpool_info() if p["user_api"] == "blas"
    ]
    assert before, "numpy's BLAS is not visible to threadpoolctl"
    with one_blas_thread():
        inside = [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]
    after = [
        (p["filepath"], p["num_threads"]) for p in threadpool_info() if p["user_api"] == "blas"
    ]
    assert inside == [1] * len(before)
    assert after == before
