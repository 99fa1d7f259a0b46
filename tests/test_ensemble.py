"""Ensemble runner: reproducibility across executors (serial, processes, Dask), failures,
validation, the tidy table; uncertainty propagation and sweeps."""

from __future__ import annotations

import concurrent.futures as cf
import csv
import math
import os
import warnings

import numpy as np
import pytest

import iwan_element as ie
from iwan_element.ensemble import (
    ParameterUncertainty,
    SingleModeSystem,
    modal_curve,
    parameter_grid,
    parameter_samples,
    peak_response,
    propagate_uncertainty,
    run_ensemble,
)
from iwan_element.ensemble.oscillator import _integrate


def ring_down(joint, system, *, x0, cycles, steps_per_period):
    h = 1.0 / (system.linear_frequency(joint) * steps_per_period)
    return _integrate(joint, system, h=h, n=cycles * steps_per_period, load=lambda t: 0.0, x0=x0)


JOINT = ie.IwanParameters(Fs=9e3, KT=5e7, chi=-0.5, beta=0.5)
SYSTEM = SingleModeSystem(mass=10.0, stiffness=2.5e7, zeta0=1e-3)


# ------------------------------------------------------------------ task functions (importable)
def physics_task(params, rng):
    """A short transient run plus random draws: exercises floats and the per-task rng."""
    p = JOINT.replace(Fs=params["Fs"])
    peak = peak_response(p, SYSTEM, force=params["force"], cycles=4, steps_per_period=32)
    return {"peak": peak, "noise": rng.normal(size=3), "u": float(rng.uniform())}


def failing_task(params, rng):
    if params["x"] == 3:
        raise ZeroDivisionError("task three always fails")
    return {"y": params["x"] ** 2 + rng.uniform()}


def kill_once_task(params, rng):
    """Kills its own worker process the first time task 2 runs (a marker file remembers)."""
    if params["i"] == 2 and not os.path.exists(params["marker"]):
        with open(params["marker"], "w") as fh:
            fh.write(str(os.getpid()))
        os._exit(1)
    return {"y": params["i"] + rng.uniform(), "pid": os.getpid()}


def bad_output_task(params, rng):
    return {"x": 1.0} if params["k"] == 0 else ({"y": object()} if params["k"] == 1 else [1.0])


SETS = [{"Fs": 9e3 * (1 + 0.05 * i), "force": 200.0 + 50 * i} for i in range(6)]


def _same(a, b):
    assert len(a.rows) == len(b.rows)
    for ra, rb in zip(a.rows, b.rows):
        assert ra.keys() == rb.keys()
        for k in ra:
            np.testing.assert_allclose(ra[k], rb[k], rtol=1e-12, atol=0)


@pytest.fixture(scope="module")
def dask_client():
    distributed = pytest.importorskip("distributed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cluster = distributed.LocalCluster(
            n_workers=2,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=40,
        )
        client = distributed.Client(cluster)
    yield client
    client.close()
    cluster.close()


# ------------------------------------------------------------------ reproducibility
def test_serial_processes_and_dask_give_identical_results(dask_client):
    serial = run_ensemble(physics_task, SETS, executor="serial", seed=7)
    procs = run_ensemble(physics_task, SETS, seed=7)
    dask = run_ensemble(physics_task, SETS, executor=dask_client, seed=7)
    assert not serial.errors and not procs.errors and not dask.errors
    assert "processes" in procs.executor and dask.executor.startswith("dask (2 workers")
    _same(serial, procs)
    _same(serial, dask)
    # the rows are in input order and carry their parameters
    assert [r["Fs"] for r in dask.rows] == [s["Fs"] for s in SETS]
    # the per-task generators are independent and follow the seed
    noise = serial.column("noise")
    assert noise.shape == (6, 3) and len({tuple(r) for r in noise}) == 6
    other = run_ensemble(physics_task, SETS[:2], executor="serial", seed=8)
    assert not np.array_equal(other.column("noise"), noise[:2])
    # a larger peak for a larger force (the physics ran, not a constant)
    assert np.all(np.diff(serial.column("peak")) > 0)


def test_task_seeds_do_not_depend_on_the_other_tasks():
    a = run_ensemble(physics_task, SETS, executor="serial", seed=3)
    b = run_ensemble(physics_task, SETS[:3], executor="serial", seed=3)
    np.testing.assert_array_equal(a.column("noise")[:3], b.column("noise"))
    expected = np.random.default_rng(np.random.SeedSequence(3).spawn(6)[4])
    np.testing.assert_array_equal(a.rows[4]["noise"], expected.normal(size=3))


def test_a_killed_dask_worker_loses_no_result(dask_client, tmp_path):
    marker = tmp_path / "killed.txt"
    sets = [{"i": i, "marker": str(marker)} for i in range(6)]
    res = run_ensemble(kill_once_task, sets, executor=dask_client, seed=11)
    assert marker.exists(), "the task did not kill its worker: the test proves nothing"
    assert not res.errors and len(res.rows) == 6
    killed_pid = int(marker.read_text())
    assert res.rows[2]["pid"] != killed_pid  # re-run on a live worker
    ref = run_ensemble(
        kill_once_task, [dict(s, marker=str(marker)) for s in sets], executor="serial", seed=11
    )
    np.testing.assert_array_equal(res.column("y"), ref.column("y"))


# ------------------------------------------------------------------ failures
@pytest.mark.parametrize("executor", ["serial", None])
def test_a_failing_task_is_reported_and_the_others_kept(executor):
    sets = [{"x": i} for i in range(6)]
    res = run_ensemble(failing_task, sets, executor=executor, seed=1)
    assert len(res.errors) == 1
    err = res.errors[0]
    assert err.index == 3 and err.params == {"x": 3}
    assert "ZeroDivisionError" in err.message and "task three" in err.message
    assert "failing_task" in err.traceback
    assert res.ok.tolist() == [True, True, True, False, True, True]
    y = res.column("y")
    assert math.isnan(y[3]) and np.all(np.isfinite(np.delete(y, 3)))
    np.testing.assert_allclose(np.delete(y, 3), np.array([0, 1, 4, 16, 25]), atol=1.0)
    assert any("1 of 6 tasks failed" in w for w in res.warnings)
    assert "FAILED task 3" in res.report()
    assert res.to_dict()["errors"][0]["index"] == 3


def test_bad_outputs_are_task_errors_with_a_reason():
    res = run_ensemble(
        bad_output_task, [{"k": 0, "x": 1}, {"k": 1}, {"k": 2}], executor="serial", seed=0
    )
    msgs = {e.index: e.message for e in res.errors}
    assert "name of a parameter" in msgs[0]
    assert "'y' must be a number" in msgs[1]
    assert "must return a dict" in msgs[2]


# ------------------------------------------------------------------ validation
def test_inputs_are_validated():
    with pytest.raises(ValueError, match="callable"):
        run_ensemble(3, [{}])
    with pytest.raises(ValueError, match="sequence"):
        run_ensemble(failing_task, {"x": 1})
    with pytest.raises(ValueError, match="empty"):
        run_ensemble(failing_task, [])
    with pytest.raises(ValueError, match=r"parameter_sets\[1\] must be a dict"):
        run_ensemble(failing_task, [{"x": 1}, 2])
    with pytest.raises(ValueError, match="seed"):
        run_ensemble(failing_task, [{"x": 1}], seed=-1)
    with pytest.raises(ValueError, match="executor"):
        run_ensemble(failing_task, [{"x": 1}], executor="threads")
    with pytest.raises(ValueError, match="executor"):
        run_ensemble(failing_task, [{"x": 1}], executor=object())
    with pytest.raises(ValueError, match="module level"):
        run_ensemble(lambda p, r: {"y": 1.0}, [{"x": 1}])


def test_nothing_given_is_mutated_and_any_executor_works():
    sets = [{"x": i} for i in range(4)]
    copy = [dict(s) for s in sets]
    with cf.ThreadPoolExecutor(2) as pool:
        res = run_ensemble(lambda p, r: {"y": p["x"] + 0.5}, sets, executor=pool, seed=2)
    assert sets == copy and res.executor == "ThreadPoolExecutor"
    assert res.column("y").tolist() == [0.5, 1.5, 2.5, 3.5]
    with pytest.raises(ValueError, match="unknown column"):
        res.column("z")


def test_csv_is_a_tidy_table(tmp_path):
    res = run_ensemble(physics_task, SETS[:3], executor="serial", seed=5)
    path = res.to_csv(tmp_path / "ens.csv")
    with open(path, newline="") as fh:
        table = list(csv.DictReader(fh))
    assert len(table) == 3
    assert list(table[0])[:4] == ["index", "ok", "Fs", "force"]
    for i, row in enumerate(table):
        assert float(row["peak"]) == res.rows[i]["peak"]
        assert float(row["noise[2]"]) == res.rows[i]["noise"][2]
        assert row["ok"] == "True"


def test_progress_bar_runs(capsys, monkeypatch):
    pytest.importorskip("tqdm")
    monkeypatch.delenv("CI", raising=False)  # bars are silent under CI
    res = run_ensemble(failing_task, [{"x": 1}, {"x": 2}], executor="serial", progress=True)
    assert res.ok.all() and "2/2" in capsys.readouterr().err


# ------------------------------------------------------------------ the single-mode structure
def test_closed_form_curve_matches_a_transient_ring_down():
    """Independent route: frequency and decay per cycle of the exact time simulation.

    The closed form is the single-mode equivalent linearisation (zeta = D / (4 pi E) with
    E the peak secant energy, docs/equations.md section 7). The exact ring-down decays a little
    faster because a slipped Iwan joint stores less than the secant energy at a turning
    point; that bias (here 2-9 %) shrinks with the amplitude, which is checked too.
    """
    t, x = ring_down(JOINT, SYSTEM, x0=1e-4, cycles=25, steps_per_period=256)
    from scipy.signal import find_peaks

    pk, _ = find_peaks(x)
    # refine the peak times by a parabola through the three samples
    y0, y1, y2 = x[pk - 1], x[pk], x[pk + 1]
    d = 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2)
    h = t[1] - t[0]
    tp, amp = t[pk] + d * h, y1 - 0.25 * (y0 - y2) * d
    bias = []
    for i in range(0, len(pk) - 1, 3):
        A = math.sqrt(amp[i] * amp[i + 1])
        f, z = modal_curve(JOINT, SYSTEM, [A])
        assert 1.0 / (tp[i + 1] - tp[i]) == pytest.approx(f[0], rel=3e-3)
        zeta_measured = math.log(amp[i] / amp[i + 1]) / (2 * math.pi)
        assert zeta_measured == pytest.approx(z[0], rel=0.10)
        bias.append(zeta_measured / z[0] - 1.0)
    assert len(bias) >= 6 and np.all(np.diff(bias) < 0) and bias[-1] < 0.035


def test_transient_integrator_matches_an_independent_one():
    """Newmark + Newton (this module) against central differences (iwan_element.modal_ringdown)."""
    t, x = ring_down(JOINT, SYSTEM, x0=1e-4, cycles=12, steps_per_period=400)
    q = ie.modal_ringdown(
        t,
        JOINT,
        K_inf=SYSTEM.stiffness,
        q0=1e-4,
        zeta0=SYSTEM.zeta0,
        mass=SYSTEM.mass,
        max_phase_step=0.005,
    ).displacement
    assert x.min() < -0.3e-4  # it swung: a real nonlinear decay
    np.testing.assert_allclose(x, q, atol=2e-3 * 1e-4)


def test_peak_response_matches_the_linear_solution_at_small_force():
    from scipy.integrate import solve_ivp

    m, k, KT = SYSTEM.mass, SYSTEM.stiffness, JOINT.KT
    c = 2 * SYSTEM.zeta0 * math.sqrt((k + KT) * m)
    f0 = SYSTEM.linear_frequency(JOINT)
    w = 2 * math.pi * f0
    F0 = 1e-4  # amplitudes ~1e-10 m: the joint is linear
    peak = peak_response(JOINT, SYSTEM, force=F0, cycles=10, steps_per_period=256)
    sol = solve_ivp(
        lambda t, y: [y[1], (F0 * math.sin(w * t) - c * y[1] - (k + KT) * y[0]) / m],
        (0, 10 / f0),
        [0, 0],
        rtol=1e-10,
        atol=1e-18,
        max_step=1 / (400 * f0),
    )
    assert peak == pytest.approx(np.abs(sol.y[0]).max(), rel=2e-3)


def test_system_and_curve_inputs_are_checked():
    with pytest.raises(ValueError, match="mass"):
        SingleModeSystem(mass=0.0, stiffness=1.0)
    with pytest.raises(ValueError, match="zeta0"):
        SingleModeSystem(mass=1.0, stiffness=1.0, zeta0=1.5)
    with pytest.raises(ValueError, match="amplitude"):
        modal_curve(JOINT, SYSTEM, [1e-5, -1e-5])
    # in macroslip the joint keeps its secant Fs / X > 0: the curve goes on without K_inf
    f, _ = modal_curve(JOINT, SingleModeSystem(mass=1.0, stiffness=0.0), [1e-2])
    assert f[0] == pytest.approx(math.sqrt(JOINT.Fs / 1e-2) / (2 * math.pi), rel=1e-12)
    with pytest.raises(ValueError, match="force"):
        peak_response(JOINT, SYSTEM, force=0.0)


# ------------------------------------------------------------------ uncertainty
def test_samples_follow_the_covariance_in_transformed_coordinates():
    cov = np.diag([90.0**2, (0.02 * 5e7) ** 2, 0.02**2, 0.03**2])
    cov[0, 1] = cov[1, 0] = 0.6 * 90.0 * 0.02 * 5e7
    unc = ParameterUncertainty.from_mean_cov(JOINT, cov)
    sets, rejected = unc.sample(4000, rng=np.random.default_rng(0))
    assert rejected == 0.0
    th = np.array(
        [[math.log(s["Fs"]), math.log(s["KT"]), s["chi"], math.log1p(s["beta"])] for s in sets]
    )
    # delta method: std of ln Fs = std Fs / Fs, etc.
    expected = np.sqrt(np.diag(cov)) / np.array([9e3, 5e7, 1.0, 1.5])
    np.testing.assert_allclose(th.std(axis=0), expected, rtol=0.05)
    assert np.corrcoef(th[:, 0], th[:, 1])[0, 1] == pytest.approx(0.6, abs=0.04)


def test_bounds_are_kept_by_rejection():
    p = JOINT.replace(beta=0.0)
    unc = ParameterUncertainty.from_mean_cov(p, [[0.05**2]], names=["beta"])
    sets, rejected = unc.sample(500, rng=np.random.default_rng(1))
    assert min(s["beta"] for s in sets) >= 0.0
    assert rejected == pytest.approx(0.5, abs=0.08)
    assert all(s["Fs"] == p.Fs for s in sets)
    with pytest.raises(ValueError, match="positive semi-definite"):
        ParameterUncertainty.from_mean_cov(JOINT, [[1.0, 2.0], [2.0, 1.0]], names=["Fs", "KT"])
    with pytest.raises(ValueError, match="shape"):
        ParameterUncertainty.from_mean_cov(JOINT, np.eye(3))


def test_from_fit_uses_the_fit_covariance():
    data = ie.simulate_test(
        JOINT, [5e-5, 1e-4, 2e-4, 4e-4, 6e-4], cycles=2, sample_rate=2.0, force_noise=20.0, seed=3
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = ie.fit_loops(t=data.t, u=data.u, F=data.F)
    assert all(fit.identified.values())
    unc = ParameterUncertainty.from_fit(fit)
    assert unc.names == ("Fs", "KT", "chi", "beta")
    scale = np.array([fit.joint.Fs, fit.joint.KT, 1.0, 1.0 + fit.joint.beta])
    se = np.array([fit.stderr[k] for k in ("Fs", "KT", "chi", "beta")]) / scale
    np.testing.assert_allclose(np.sqrt(np.diag(unc.cov)), se, rtol=1e-9)
    np.testing.assert_allclose(unc.cov[1, 2] / (se[1] * se[2]), fit.correlation[1, 2], rtol=1e-9)


def test_microslip_fit_samples_the_kt_chi_r_family():
    data = ie.simulate_test(
        JOINT, [2e-5, 4e-5, 8e-5], cycles=2, sample_rate=2.0, force_noise=5.0, seed=4
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = ie.fit_loops(t=data.t, u=data.u, F=data.F)
    assert not fit.identified["Fs"]
    unc = ParameterUncertainty.from_fit(fit)
    assert unc.names == ("KT", "chi", "R") and unc.valid_amplitude < 1e-4
    sets, _ = unc.sample(300, rng=np.random.default_rng(2))
    assert all(s["beta"] == 0.0 for s in sets)
    R = np.array([ie.IwanParameters(**s).R for s in sets])
    assert np.log(R).std() == pytest.approx(math.sqrt(unc.cov[2, 2]), rel=0.15)
    bands = propagate_uncertainty(
        unc, system=SYSTEM, amplitude=[1e-5, 2e-4], n_samples=20, seed=0, executor="serial"
    )
    assert any("beyond the tested range" in w for w in bands.warnings)


def test_band_width_matches_the_delta_method():
    """Independent route: the linearised std of f(X), zeta(X), sqrt(g^T C g)."""
    cov = np.diag([(0.03 * 9e3) ** 2, (0.03 * 5e7) ** 2, 0.01**2, 0.02**2])
    unc = ParameterUncertainty.from_mean_cov(JOINT, cov)
    X = np.array([1e-5, 1e-4])
    bands = propagate_uncertainty(
        unc, system=SYSTEM, amplitude=X, n_samples=600, seed=5, executor="serial", level=0.6827
    )
    names = ("Fs", "KT", "chi", "beta")
    for which, col in (("frequency", 0), ("damping_ratio", 1)):
        g = []
        for n in names:
            h = 1e-6 * max(abs(getattr(JOINT, n)), 1.0)
            up = modal_curve(JOINT.replace(**{n: getattr(JOINT, n) + h}), SYSTEM, X)[col]
            dn = modal_curve(JOINT.replace(**{n: getattr(JOINT, n) - h}), SYSTEM, X)[col]
            g.append((up - dn) / (2 * h))
        g = np.array(g)
        std_lin = np.sqrt(np.einsum("ia,ij,ja->a", g, cov, g))
        lo, med, hi = bands.band(which)
        np.testing.assert_allclose((hi - lo) / 2, std_lin, rtol=0.15)
        np.testing.assert_allclose(med, bands.nominal[which], rtol=0.02)


def test_prediction_bands_result_object(tmp_path):
    cov = np.diag([(0.05 * 9e3) ** 2, (0.05 * 5e7) ** 2])
    unc = ParameterUncertainty.from_mean_cov(JOINT, cov, names=["Fs", "KT"])
    bands = propagate_uncertainty(
        unc,
        system=SYSTEM,
        amplitude=np.geomspace(1e-6, 3e-4, 5),
        n_samples=16,
        force=300.0,
        cycles=6,
        seed=1,
        executor="serial",
    )
    lo, _, hi = bands.band("peak")
    assert lo < bands.nominal["peak"] < hi
    d = bands.to_dict()
    assert d["samples"] == 16 and len(d["bands"]["damping_ratio"]["low"]) == 5
    assert "peak displacement" in bands.report()
    import matplotlib

    matplotlib.use("Agg")
    artists = bands.plot()
    assert len(artists) >= 7
    bands.ensemble.to_csv(tmp_path / "samples.csv")
    with pytest.raises(ValueError, match="SingleModeSystem"):
        propagate_uncertainty(unc, system=None, amplitude=[1e-5])


# ------------------------------------------------------------------ sweeps
def test_parameter_grid_and_samples():
    g = parameter_grid(preload=[1e4, 2e4], mu=[0.2, 0.3, 0.4])
    assert len(g) == 6 and g[1] == {"preload": 1e4, "mu": 0.3}
    with pytest.raises(ValueError, match="non-empty"):
        parameter_grid(preload=[])
    s = parameter_samples(10, seed=0, preload=(1e4, 4e4), mu=(0.1, 0.5), log=["preload"])
    assert len(s) == 10
    pre = np.array([x["preload"] for x in s])
    assert pre.min() >= 1e4 and pre.max() <= 4e4
    # Latin hypercube: exactly one sample in each of the 10 equal strata (of log preload)
    strata = np.floor((np.log(pre) - np.log(1e4)) / (np.log(4e4) - np.log(1e4)) * 10)
    assert sorted(strata.astype(int).tolist()) == list(range(10))
    with pytest.raises(ValueError, match="low must be < high"):
        parameter_samples(3, mu=(0.5, 0.1))
    with pytest.raises(ValueError, match="method"):
        parameter_samples(3, method="grid", mu=(0.1, 0.5))


def test_modal_fit_is_propagated_in_its_own_coordinates():
    p = ie.IwanParameters(Fs=0.6, KT=1.2e5, chi=-0.4, beta=0.8)  # unit modal mass
    X = np.geomspace(0.05, 3, 14) * p.phi_max
    f, z = ie.modal_iwan_curve(
        X, p, K_inf=2.8e5, zeta0=0.002, stiffness="harmonic", floor="dashpot"
    )
    rng = np.random.default_rng(0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = ie.fit_modal_iwan(
            X, f * (1 + 2e-5 * rng.normal(size=14)), z * (1 + 2e-3 * rng.normal(size=14))
        )
    assert fit.regime == "macroslip"
    Xb = X[::3]
    bands = propagate_uncertainty(
        fit, amplitude=Xb, n_samples=200, seed=2, executor="serial", force=5.0, cycles=4, level=0.9
    )
    assert bands.system is None and "modal fit" in bands.report()
    f_fit, z_fit, fb, zb = fit.predict(Xb, band=0.9)
    np.testing.assert_allclose(bands.nominal["frequency"], f_fit, rtol=1e-12)
    np.testing.assert_allclose(bands.nominal["damping_ratio"], z_fit, rtol=1e-12)
    lo, _, hi = bands.band("damping_ratio")
    assert np.all(lo < z_fit) and np.all(z_fit < hi)
    # sampling and the fit's own delta-method band agree to first order for the damping
    ratio = (zb[1] - zb[0]) / (hi - lo)
    assert np.all((ratio > 0.8) & (ratio < 1.25)), ratio
    assert bands.peak.shape == (200,) and np.all(bands.peak > 0)


def echo_task(params, rng):
    return {"y": params["x"] * 2.0, "r": rng.uniform()}


def test_rows_follow_the_input_order_on_any_executor():
    from hypothesis import given, settings
    from hypothesis import strategies as st

    @settings(max_examples=25, deadline=None)
    @given(st.lists(st.floats(-1e6, 1e6), min_size=1, max_size=12), st.integers(0, 2**32))
    def check(xs, seed):
        sets = [{"x": x} for x in xs]
        with cf.ThreadPoolExecutor(3) as pool:
            threaded = run_ensemble(echo_task, sets, executor=pool, seed=seed)
        serial = run_ensemble(echo_task, sets, executor="serial", seed=seed)
        assert [r["x"] for r in threaded.rows] == xs
        assert threaded.column("y").tolist() == [2.0 * x for x in xs]
        assert threaded.column("r").tolist() == serial.column("r").tolist()

    check()


def test_dissipation_fits_are_propagated_and_a_given_fs_is_held():
    data = ie.simulate_test(
        JOINT,
        [5e-5, 1e-4, 2e-4, 3e-4, 4e-4, 6e-4],
        cycles=2,
        sample_rate=2.0,
        force_noise=10.0,
        seed=5,
    )
    table = data.amplitude_table()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lsq = ie.fit_dissipation(table["u0"], table["F0"], table["D"])
        seed = ie.fit_dissipation(table["u0"], table["F0"], table["D"], method="seed", Fs=9e3)
    unc = ParameterUncertainty.from_fit(lsq)
    assert unc.source == "fit (least_squares)" and "KT" in unc.names
    unc_seed = ParameterUncertainty.from_fit(seed)
    assert "Fs" not in unc_seed.names
    assert any("Fs" in w and "held" in w for w in unc_seed.warnings)
    sets, _ = unc_seed.sample(50, rng=np.random.default_rng(0))
    assert all(s["Fs"] == seed.joint.Fs for s in sets)
    assert len({s["KT"] for s in sets}) == 50
