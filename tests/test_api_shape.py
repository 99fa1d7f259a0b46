"""One API shape: plotting functions take ``ax=`` and return the artists they drew on it;
every public result class has ``report()``, a JSON-safe ``to_dict()``, ``warnings``,
``success``, ``_repr_html_()`` and ``plot(ax=None)`` returning artists, with the one axes
contract of ``iwan_element.base.result_shape``; time-series functions take time first."""

from __future__ import annotations

import functools
import html
import inspect
import json
import re
import warnings

import matplotlib

matplotlib.use("Agg")
import numpy as np
import pytest
from matplotlib.figure import Figure

import iwan_element as ie
from iwan_element import plotting
from iwan_element.base.result_shape import ResultShape

P = ie.IwanParameters(9e3, 5e7, -0.5, 0.5)


def _record():
    return ie.simulate_test(
        P, np.array([0.05, 0.1, 0.2, 0.3]) * 1e-3, cycles=3, sample_rate=4, force_noise=5.0, seed=0
    )


PLOTS = {
    "plot_normalized_loops": lambda ax: plotting.plot_normalized_loops([(0.0, 0.5)], ax=ax),
    "plot_loop": lambda ax: plotting.plot_loop(1e-4, P, ax=ax),
    "plot_fitted_loops": lambda ax: plotting.plot_fitted_loops(
        np.linspace(0, 1e-4, 50), ie.backbone(np.linspace(0, 1e-4, 50), P), P, ax=ax
    ),
    "plot_dissipation_fit": lambda ax: plotting.plot_dissipation_fit(
        ie.force_amplitude(np.geomspace(1e-5, 1e-4, 5), P),
        ie.dissipation(np.geomspace(1e-5, 1e-4, 5), P),
        P,
        ax=ax,
    ),
}


def test_every_plotting_function_is_covered():
    public = {
        n for n, f in vars(plotting).items() if n.startswith("plot_") and inspect.isfunction(f)
    }
    assert public == set(PLOTS)


@pytest.mark.parametrize("name", sorted(PLOTS))
def test_plotting_functions_take_ax_and_return_its_artists(name):
    assert "ax" in inspect.signature(getattr(plotting, name)).parameters
    assert (
        inspect.signature(getattr(plotting, name)).parameters["ax"].kind
        == inspect.Parameter.KEYWORD_ONLY
    )
    ax = Figure().add_subplot()
    artists = PLOTS[name](ax)
    twins = ax.get_shared_x_axes().get_siblings(ax)  # a twinx() of ax counts as ax
    assert len(artists) > 0 and all(a.axes is ax or a.axes in twins for a in artists)


# result objects: how to build one cheaply
def _fit():
    d = _record()
    return ie.fit_loops(d.t, d.u, d.F, n_starts=1, max_nfev=30)


def _curve():
    a = np.geomspace(1e-5, 1e-3, 8)
    return ie.AmplitudeCurve(
        a, 100 - 5 * a / a[-1], 1e-3 + 0.01 * a / a[-1], frequency_std=1e-3, damping_ratio_std=1e-5
    )


def _vib():
    c = _curve()
    return ie.diagnose_vibration(
        c.amplitude,
        c.frequency,
        c.damping_ratio,
        predicted_frequency=c.frequency + 0.01,
        predicted_damping_ratio=c.damping_ratio,
        frequency_noise=0.01,
        damping_ratio_noise=1e-4,
    )


def _diag():
    d = _record()
    return ie.diagnose(d.t, d.u, d.F, max_samples=300, max_effects=1, noise=5.0)


def _batch():
    d = _record()
    return ie.diagnose_many(
        [(d.t, d.u, d.F)], executor="serial", max_samples=300, max_effects=1, noise=5.0
    )


def _modal():
    c = _curve()
    return ie.fit_modal_iwan(c.amplitude, c.frequency, c.damping_ratio)


def _model_fit():
    d = _record()
    return ie.fit_force_model(
        d.t, d.u, d.F, lambda u, th: th[0] * u, [1e7], names=["k"], max_nfev=20
    )


def _noise():
    d = _record()
    return ie.estimate_noise(d.t, d.F)


def _square(params, rng):
    return {"y": params["x"] ** 2 + 0.01 * rng.standard_normal()}


def _ensemble():
    return ie.run_ensemble(_square, [{"x": float(x)} for x in range(5)], executor="serial", seed=1)


def _uncertainty():
    return ie.ParameterUncertainty.from_mean_cov(P, np.diag([90.0, 5e5, 0.02, 0.05]) ** 2)


def _bands():
    sys_ = ie.SingleModeSystem(mass=1.0, stiffness=4e6, zeta0=1e-3)
    return ie.propagate_uncertainty(
        _uncertainty(),
        system=sys_,
        amplitude=[1e-5, 1e-4],
        n_samples=4,
        cycles=4,
        steps_per_period=32,
        seed=0,
        executor="serial",
    )


@functools.lru_cache(maxsize=1)
def _campaign():
    """One small campaign fit, shared by its own shape test and its results' (read only)."""
    from _campaign_cases import campaign

    recs, conds = campaign(
        3, conditions=tuple({"tension": T, "frequency": 1.0} for T in (10.0, 20.0, 30.0, 40.0))
    )
    return ie.fit_campaign(
        recs, conds, effects=("backlash",), candidates=("backlash",), laws={"Fs": ("tension",)}
    )


def _targets():
    f = np.linspace(45.0, 55.0, 30)
    W = 2 * np.pi * f
    H = 0.64 / ((2 * np.pi * 50) ** 2 - W**2 + 2j * 0.008 * (2 * np.pi * 50) * W)
    return ie.frf_modes(f, H * (1 + 0.01 * np.cos(7 * f)))


def _modal_ringdown():
    return ie.modal_ringdown(
        np.arange(400) / 4000.0, ie.IwanParameters(3.0, 2.5e4, -0.5, 0.3), K_inf=2.3e5, q0=2e-4
    )


RESULTS = {
    "FitResult": _fit,
    "ModalRingdown": _modal_ringdown,
    "ModalTargets": _targets,
    "AmplitudeCurve": _curve,
    "VibrationDiagnosis": _vib,
    "Diagnosis": _diag,
    "BatchDiagnosis": _batch,
    "ModalIwanFit": _modal,
    "ModelFit": _model_fit,
    "NoiseEstimate": _noise,
    "EnsembleResult": _ensemble,
    "ParameterUncertainty": _uncertainty,
    "PredictionBands": _bands,
    "CampaignFit": _campaign,
}


def test_top_level_exports_every_closed_form():
    """The top level's ``__all__`` names each closed form (written out for static tools)."""
    from iwan_element.core import closed_form

    assert set(closed_form.__all__) <= set(ie.__all__)
    assert all(getattr(ie, n) is getattr(closed_form, n) for n in closed_form.__all__)


@functools.cache
def _built(name):
    """One result per class, built once (the parts below only read it)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # identifiability warnings of the short record
        return ALL_RESULTS[name]()


#: The parts of the one result shape every result class is checked for.
PARTS = "report html columns dataframe to_dict warnings success plot figure".split()


@pytest.mark.parametrize("name", sorted(RESULTS))
@pytest.mark.parametrize("part", PARTS)
def test_result_objects_have_one_shape(name, part):
    res = _built(name)
    if part == "report":  # opens with the verdict, usable or NOT usable and why
        assert isinstance(res.report(), str) and res.report().strip()
        assert res.report().splitlines()[0] == res.verdict()
        assert res.verdict() == "usable" if res.success else res.verdict().startswith("NOT usable")
        _check_verdict_agrees_with_table(res)
    elif part == "html":  # real tables, the verdict on top, each caption its fixed title
        page = res._repr_html_()
        assert "<pre>" not in page and page.count("<table>") == len(res._tables()) >= 1
        assert page.index(html.escape(res.verdict())) < page.index("<table>")
        captions = re.findall(r"<caption>(.*?)</caption>", page)
        assert captions == [html.escape(t) for t, _, _ in res._tables()]
        if res.warnings:
            assert page.count("<li>") >= len(res.warnings)
    elif part == "columns":  # one style: "name [unit]", SI, [-] dimensionless
        _check_column_titles(res)
    elif part == "dataframe":  # every table reaches pandas as it stands
        pd = pytest.importorskip("pandas")
        tables = res._tables()
        if len(tables) > 1:  # the main table first, the run's quantities after it
            assert tables[0][0] not in ("goodness of fit and run", "run")
        for title, cols, rows in tables:
            frame = pd.DataFrame([list(r) for r in rows], columns=list(cols))
            assert frame.shape == (len(rows), len(cols)) and all(len(r) == len(cols) for r in rows)
            assert res.to_dataframe(title).equals(frame)
        assert isinstance(res.to_dataframe(), pd.DataFrame)
        with pytest.raises(ValueError, match="table must be one of"):
            res.to_dataframe("no such table")
    elif part == "to_dict":
        d = res.to_dict()
        json.dumps(d, allow_nan=False)
        if hasattr(res, "params"):  # one layout: the ParameterTable's
            assert [p["name"] for p in d["params"]["parameters"]] == list(res.params.names)
        for pair in d.get("offsets", {}).values():
            assert set(pair) == {"value", "stderr"}
    elif part == "warnings":
        assert isinstance(res.warnings, tuple)
    elif part == "success":
        assert isinstance(res.success, bool)
    elif part == "figure":  # a figure a tester can put in a report as it stands
        _check_figure(res)
    else:  # the one axes contract (core.result_shape)
        n = res.plot_panels
        fig = Figure()
        axes = [fig.add_subplot(1, n, k + 1) for k in range(n)]
        artists = res.plot(ax=axes[0] if n == 1 else axes)
        assert len(artists) > 0 and all(a.axes in axes for a in artists)
        wrong = axes + [fig.add_subplot(1, n + 1, n + 1)]
        with pytest.raises(TypeError, match="Axes"):
            res.plot(ax=wrong)
        if "label" in inspect.signature(res.plot).parameters:  # a label draws a legend
            fig = Figure()
            axes = [fig.add_subplot(1, n, k + 1) for k in range(n)]
            artists = res.plot(ax=axes[0] if n == 1 else axes, label="this curve")
            texts = [
                t.get_text()
                for a in {a.axes for a in artists}
                if a.get_legend() is not None
                for t in a.get_legend().get_texts()
            ]
            assert any(t.startswith("this curve") for t in texts), (name, texts)


def _check_verdict_agrees_with_table(res):
    """A verdict of NOT usable names every fitted parameter its table marks not identified,
    and says nothing twice (no "misfit beyond the noise remains: misfit beyond the noise
    remains after ...")."""
    for reason in res.verdict().split("; "):
        parts = [re.findall(r"[\w.+-]+", p.lower()) for p in reason.split(": ")]
        for head, tail in zip(parts, parts[1:]):
            last = " ".join(head[-3:])
            assert len(head) < 3 or last not in " ".join(tail), reason
    params = getattr(res, "params", None)
    if res.success or not hasattr(params, "parameters"):
        return
    for p in params.parameters:
        if not (p.identified or p.fixed or p.nuisance):
            assert re.search(rf"\b{re.escape(p.name)}\b", res.verdict()), (p.name, res.verdict())


def _check_figure(res):
    """``plot()`` on a new figure: every Axes with its labels, ticks and legend inside the
    figure (no clipped y-label, no overlapping panels), every drawn Axes labelled, and no
    offset tick labels ("+7.701e1") on a linear axis."""
    import matplotlib.pyplot as plt
    from matplotlib.ticker import ScalarFormatter

    before = set(plt.get_fignums())
    artists = res.plot()
    (num,) = set(plt.get_fignums()) - before
    fig = plt.figure(num)
    try:
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        box = fig.bbox
        drawn = [a for a in fig.axes if a.get_visible() and a.axison]
        boxes = [a.get_tightbbox(renderer) for a in drawn]
        for a, b in zip(drawn, boxes):
            assert b.x0 >= box.x0 - 1 and b.y0 >= box.y0 - 1, (a.get_ylabel(), b, box)
            assert b.x1 <= box.x1 + 1 and b.y1 <= box.y1 + 1, (a.get_ylabel(), b, box)
            for axis in (a.xaxis, a.yaxis):
                fmt = axis.get_major_formatter()
                if isinstance(fmt, ScalarFormatter) and axis.get_scale() == "linear":
                    assert fmt.offset == 0, (a.get_ylabel(), axis.get_offset_text().get_text())
        for a in {x.axes for x in artists}:
            assert a.get_ylabel() or a.get_xlabel(), type(res).__name__
        # the panels' labels and ticks do not run into each other (a twin shares its panel)
        for i in range(len(drawn)):
            for j in range(i + 1, len(drawn)):
                if drawn[i].get_position().overlaps(drawn[j].get_position()):
                    continue
                bi, bj = boxes[i], boxes[j]
                w = min(bi.x1, bj.x1) - max(bi.x0, bj.x0)
                h = min(bi.y1, bj.y1) - max(bi.y0, bj.y0)
                assert w <= 2 or h <= 2, (type(res).__name__, i, j, w, h)
    finally:
        plt.close(fig)


_TITLE = re.compile(r"[^\[\]]+( \[[^\[\]]+\])?")
_SUFFIX_UNIT = re.compile(r"_(N|Hz|m|s|J|rad|Pa|per_m)$")


def _check_column_titles(res):
    """Every column and quantity title of every table: ``name [unit]`` or a bare name; no
    unit glued on with an underscore (``force_levels_N``); a title that holds non-integer
    numbers names their unit (``[-]`` dimensionless), unless the table has a unit column.
    The ensemble's rows are titled by the user's own parameter and output names."""
    own = set(getattr(res, "parameters", ())) | set(getattr(res, "outputs", ()))
    for title, cols, rows in res._tables():
        assert not re.search(r"\d+ rows", title), title
        if "unit" in cols:
            continue
        if tuple(cols) == ("quantity", "value"):
            pairs = [(q, [v]) for q, v in rows]
        else:
            pairs = [(c, [r[i] for r in rows]) for i, c in enumerate(cols)]
        for name, values in pairs:
            name = str(name)
            assert _TITLE.fullmatch(name) and not _SUFFIX_UNIT.search(name), (title, name)
            real = [
                v
                for v in values
                if isinstance(v, float | np.floating) and np.isfinite(v) and v != round(v)
            ]
            if real and name not in own:
                assert name.endswith("]"), f"{type(res).__name__} table {title!r}: {name!r}"


@pytest.mark.parametrize("fn", [ie.diagnose, ie.fit_loops, ie.split_cycles, ie.TestData])
def test_time_series_functions_take_time_first(fn):
    names = list(inspect.signature(fn).parameters)
    assert names[:3] == ["t", "u", "F"]


def _calibration():
    from iwan_element.models.calibration import calibrate

    from iwan_element import models

    s = models.preset("brake-reuss").replace(n_points=8, calibrated_range=None)
    X = np.geomspace(5e-6, 4e-5, 5)
    q = models.modal_amplitude_curve(s, amplitude=X)
    meas = ie.AmplitudeCurve(
        X,
        q.frequency * (1 + 1e-4),
        q.damping_ratio * 1.1,
        frequency_std=1e-3,
        damping_ratio_std=1e-5,
    )
    return calibrate(s, meas, fit=("chi",))


def _ringdown():
    from iwan_element import models

    s = models.preset("brake-reuss").replace(n_points=8)
    return models.ringdown(s, amplitude=30e-6, cycles=8, steps_per_period=32, record_energy=True)


def _quasi_static():
    from iwan_element import models

    return models.quasi_static_test(
        models.preset("example").replace(n_points=8), cycles=1, steps_per_cycle=40
    )


def _forced():
    from iwan_element import models

    s = models.preset("example").replace(n_points=8, damping_floor=0.05)
    return models.forced_response(
        s,
        force_levels=(1.0,),
        frequencies=[60.0, 66.6, 73.0],
        settle_cycles=5,
        measure_cycles=2,
        steps_per_period=16,
    )


@functools.lru_cache(maxsize=1)
def _coupling():
    from iwan_element import models

    s = models.preset("two-bolt-aluminium").replace(n_points=8)
    return models.mode_coupling(s, amplitude={1: 1e-4, 2: 2e-5}, duration=0.75, steps_per_period=32)


def _frequency_response():
    from iwan_element import models

    s = models.preset("brake-reuss").replace(n_points=8)
    return models.harmonic_balance(s, frequency=np.linspace(80.0, 80.8, 5), force=0.3)


def _hammer():
    from test_hammer_prediction import round_trip

    return round_trip()[1]


def _modes():
    from test_mode_diagnosis import workflow

    return workflow(True)[2]


def _linear_update():
    from iwan_element import models

    s = models.preset("example").replace(n_points=8)
    return models.linear_update(
        s, frequencies={1: 70.0, 2: 420.0}, parameters=("youngs_modulus", "stiffness_per_area")
    )


#: Results of the beam model (``iwan_element.models``), with the same shape.
MODEL_RESULTS = {
    "CalibrationResult": _calibration,
    "RingdownResult": _ringdown,
    "QuasiStaticResult": _quasi_static,
    "ForcedResponseResult": _forced,
    "ModeCouplingResult": _coupling,
    "FrequencyResponse": _frequency_response,
    "HammerPrediction": _hammer,
    "ModesDiagnosis": _modes,
    "LinearUpdateResult": _linear_update,
}


def _prediction():
    fit = _campaign()
    t = np.linspace(0.0, 2.0, 400)
    return fit.predict({"tension": 25.0, "frequency": 1.0}, t, 2e-4 * np.sin(2 * np.pi * t))


def _loo():
    return _campaign().leave_one_out()


def _averaged():
    v = _vib()
    return v.averaged_band(v.amplitude)


#: Results that public methods of other results return (the campaign's prediction and
#: leave-one-out, a diagnosis' model-averaged band), with the same shape.
METHOD_RESULTS = {"CampaignPrediction": _prediction, "LeaveOneOut": _loo, "AveragedBand": _averaged}


def _energy_balance():
    from _connector_models import Chain, settings

    from iwan_element.exudyn import record_energy

    chain = Chain([1.0], v0=[0.5])
    chain.spring(-1, 0, 1e5)
    conn = chain.joint(-1, 0, P)
    rec = record_energy(chain.mbs, conn)
    chain.solve(settings(2e-5, 200))
    return rec.balance()


#: Results of the Exudyn adapter (``iwan_element.exudyn``), with the same shape.
EXUDYN_RESULTS = {"EnergyBalance": _energy_balance}

#: The record load_test returns (a ResultShape too: its cycles are its main table).
DATA_RESULTS = {"TestData": _record}

ALL_RESULTS = {**RESULTS, **MODEL_RESULTS, **METHOD_RESULTS, **EXUDYN_RESULTS, **DATA_RESULTS}

#: Public classes with a report that are parts of results, not results: a fit's parameter
#: table (shown inside its result's tables).
NOT_RESULTS = {"ParameterTable"}


def _public_classes_with_reports():
    """Every class a module of the package (``iwan_element`` and its ``models``) names in
    its ``__all__`` that is a :class:`ResultShape` or has a ``report``: found by walking the
    package, so that a new result joins the contract without being listed here.
    """
    import importlib
    import pkgutil

    from iwan_element import models

    found = set()
    for pkg in (ie, models):
        for info in pkgutil.walk_packages(pkg.__path__, pkg.__name__ + "."):
            mod = importlib.import_module(info.name)
            for n in getattr(mod, "__all__", ()):
                obj = getattr(mod, n, None)
                if inspect.isclass(obj) and obj is not ResultShape:
                    if issubclass(obj, ResultShape) or hasattr(obj, "report"):
                        found.add(obj.__name__)
    return found


def test_every_public_result_class_is_covered():
    """The package's public result classes, found by walking it, are exactly the ones built
    here (a new result class must join ALL_RESULTS and so the contract below)."""
    assert _public_classes_with_reports() - NOT_RESULTS == set(ALL_RESULTS)


@pytest.mark.parametrize(
    "name", sorted({**MODEL_RESULTS, **METHOD_RESULTS, **EXUDYN_RESULTS, **DATA_RESULTS})
)
@pytest.mark.parametrize("part", PARTS)
def test_other_result_objects_have_the_same_shape(name, part):
    """The beam model's results and the results of public methods, by the same test."""
    test_result_objects_have_one_shape(name, part)


def test_report_tables_align_their_titles_with_their_columns():
    """table_lines: every line of a table is as wide as its header; numbers and titles are
    right-aligned unless the column's spec says left."""
    from iwan_element.base.result_shape import table_lines

    lines = table_lines(
        [("record", "<12"), ("band [N]", "9.4g"), ("ratio", "6.2f")],
        [("a", 1234.5678, 0.5), ("bb", 1e-7, 12.345)],
        indent=2,
    )
    assert len({len(s) for s in lines}) == 1
    assert lines[0] == "  record        band [N]  ratio"
    assert lines[1] == "  a                 1235   0.50"
    assert lines[2].split() == ["bb", "1e-07", "12.35"]


def test_test_data_reaches_notebooks_and_pandas():
    """The record load_test returns: an HTML table of its cycles, a JSON-safe dict and a
    data frame in SI units, one row per cycle."""
    pd = pytest.importorskip("pandas")
    d = _record()
    frame = d.to_dataframe()
    assert isinstance(frame, pd.DataFrame) and len(frame) == len(d.cycles)
    assert frame["u0 [m]"].tolist() == [c.u0 for c in d.cycles]
    assert d.to_dataframe("cycles").equals(frame)
    json.dumps(d.to_dict(), allow_nan=False)
    cycles = d._repr_html_().split("<caption>cycles</caption>")[1].split("</table>")[0]
    assert cycles.count("<tr>") == len(d.cycles) + 1
    assert d.report().splitlines()[0] == "usable" and not hasattr(d, "summary")


def test_a_fit_verdict_names_every_parameter_its_table_marks():
    """beta, not required when its range reaches 0, is still NOT identified in the table: the
    verdict that names KT and chi names it too (it said "KT and chi are not identified")."""
    from iwan_element.identify.loops.joint_verdict import failure_list

    ident = {"Fs": True, "KT": False, "chi": False, "beta": False}
    common = dict(converged=True, message="", explains=True, noise_text="", ident=ident)
    (reason,) = failure_list(**common, required=["Fs", "KT", "chi"], microslip=False)
    assert reason.startswith("KT, chi and beta are not identified")
    # a given beta is not fitted: not named
    (reason,) = failure_list(
        **common, required=["Fs", "KT", "chi"], microslip=False, fixed=("beta",)
    )
    assert reason.startswith("KT and chi are not identified")


def test_iwan_parameters_have_an_html_view():
    """A notebook shows IwanParameters as a table: the four parameters and the derived ones
    with their SI units, the values as the object holds them."""
    page = P._repr_html_()
    cells = re.findall(r"<tr><td>(\w+)</td><td[^>]*>([^<]+)</td><td>([^<]+)</td>", page)
    got = {n: (float(v), u) for n, v, u in cells}
    assert got["Fs"] == (P.Fs, "N") and got["KT"] == (P.KT, "N/m") and got["chi"][1] == "-"
    assert got["phi_max"][0] == pytest.approx(P.phi_max, rel=1e-5) and got["phi_max"][1] == "m"
    assert set(got) == {"Fs", "KT", "chi", "beta", "phi_max", "R", "S"}


def test_ringdown_plot_reads_alone_with_modes_far_apart():
    """Two modes at 21 and 133 Hz: the time panel has its y-label and a legend naming each
    mode, the frequency axis is logarithmic (one linear axis squashed each curve flat), and
    no tick label carries an offset ("+7.701e1")."""
    import dataclasses

    import matplotlib.pyplot as plt

    rd = _built("RingdownResult")
    a = np.geomspace(1e-6, 1e-5, 6)
    curves = tuple(
        ie.AmplitudeCurve(a, f * (1 - 1e-4 * a / a[-1]), 1e-3 + 0 * a) for f in (21.0, 133.0)
    )
    two = dataclasses.replace(
        rd, modes=(1, 2), curves=curves, modal_responses=np.vstack([rd.modal, 0.3 * rd.modal])
    )
    two.plot()
    fig = plt.gcf()
    try:
        fig.canvas.draw()
        ax_t, ax_f, ax_z = fig.axes[:3]
        assert ax_t.get_ylabel().endswith("[m]") and ax_t.get_xlabel() == "time [s]"
        texts = [t.get_text() for t in ax_t.get_legend().get_texts()]
        assert any("mode 1" in t for t in texts) and any("mode 2" in t for t in texts)
        assert ax_f.get_yscale() == "log" and ax_z.get_yscale() == "linear"
        assert ax_z.yaxis.get_major_formatter().offset == 0
    finally:
        plt.close(fig)


def test_cli_fit_plot_is_the_python_plot_with_its_dissipation_panel():
    """``iwan-element fit --plot`` draws the loops with FitResult.plot (the fitted force
    offset removed: the CLI's own copy drew the model 1.1 kN off the data of ARTS
    ds1_0p5Hz_25lb), beside the dissipation panel."""
    import matplotlib.pyplot as plt

    from iwan_element.plotting import fit_figure

    d = _record()
    off = ie.TestData.from_arrays(d.t, d.u, d.F + 300.0)  # a 300 N force-sensor offset
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ie.IdentifiabilityWarning)  # microslip: Fs, beta
        res = ie.fit_loops(off.t, off.u, off.F, n_starts=1, max_nfev=60)
    assert abs(res.offsets["force"][0] - 300.0) < 10.0
    fig, notes = fit_figure(off, res)
    ax1, ax2 = fig.axes[:2]
    ref = Figure().add_subplot()
    res.plot(ax=ref)
    for mine, python in zip(ax1.get_lines(), ref.get_lines(), strict=True):
        np.testing.assert_array_equal(mine.get_ydata(), python.get_ydata())
    measured, model = ax1.get_lines()[:2]
    gap = np.mean(measured.get_ydata() - model.get_ydata()) * 1e3  # kN -> N
    assert abs(gap) < 5.0  # the offset (300 N) is not between data and model
    assert notes == [] and ax2.get_xscale() == "log" and len(ax2.get_lines()) >= 2
    plt.close("all")


@pytest.mark.parametrize("name", ["Diagnosis", "VibrationDiagnosis"])
def test_step_tables_keep_their_columns_with_long_names(name):
    """A pair's long name ("slip_degradation + asymmetric_slip") does not push its row's
    numbers out of their columns: every candidate's verdict starts in one column."""
    import dataclasses

    d = _built(name)
    st = d.steps[0]
    long = dict(st["candidates"][0], name="slip_degradation + asymmetric_slip")
    cands = [long] + list(st["candidates"])
    rep = dataclasses.replace(d, steps=[dict(st, candidates=cands)] + list(d.steps[1:])).report()
    lines = rep.splitlines()
    start = next(i for i, s in enumerate(lines) if s.strip().startswith(long["name"]))
    rows = lines[start : start + len(cands)]
    assert [r.split()[0] for r in rows] == [c["name"].split()[0] for c in cands]
    assert len({r.index(c["verdict"]) for r, c in zip(rows, cands)}) == 1, rows


def test_a_long_html_table_keeps_its_caption_and_counts_what_it_leaves_out():
    """The caption is the table's title whatever its length (it said "data (41 rows)");
    the rows left out are counted in the gap row."""
    from iwan_element.base.result_shape import HTML_ROWS, html_table

    page = html_table("response", ("f [Hz]",), [(float(k),) for k in range(100)])
    assert "<caption>response</caption>" in page
    assert page.count("<tr>") == 1 + HTML_ROWS + 1
    assert f"... {100 - HTML_ROWS} rows more in to_dataframe()" in page
    shown = [float(x) for x in re.findall(r'text-align:right">([\d.]+)<', page)]
    assert len(shown) == HTML_ROWS and 100 - HTML_ROWS == 100 - len(set(shown))
