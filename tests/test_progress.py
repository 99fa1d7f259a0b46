"""Progress bars (``iwan_element.base.progress``): a total and so an ETA on every long call,
off by default, silent under CI, a clear error without tqdm or for a non-bool."""

from __future__ import annotations

import inspect
import re
import warnings

import numpy as np
import pytest
from iwan_element.models.calibration import calibrate

import iwan_element as ie
from iwan_element import models
from iwan_element.base import progress as pg

LONG_CALLS = [
    ie.fit_decay,
    ie.diagnose,
    ie.diagnose_many,
    ie.fit_campaign,
    ie.run_ensemble,
    ie.propagate_uncertainty,
    calibrate,
    models.ringdown,
    models.forced_response,
]


@pytest.mark.parametrize("fn", LONG_CALLS, ids=lambda f: f.__name__)
def test_every_long_call_takes_progress_off_by_default(fn):
    p = inspect.signature(fn).parameters["progress"]
    assert p.kind == inspect.Parameter.KEYWORD_ONLY and p.default is False


def test_bar_keeps_its_total_from_start_to_end(monkeypatch):
    monkeypatch.delenv("CI", raising=False)
    bar = pg.progress_bar(True, total=3, desc="x", unit="step")
    pg.tick(bar, text="a")
    pg.tick(bar, 3)  # more than announced: the count stops at the total, which stays
    assert bar.n == 3 and bar.total == 3
    bar2 = pg.progress_bar(True, total=10, desc="x", unit="step")
    pg.tick(bar2, 2)
    pg.complete(bar2)  # a budget: the steps not needed are counted done
    assert bar2.total == 10 and bar2.n == 10
    bar3 = pg.progress_bar(True, total=10, desc="x", unit="step")
    pg.tick(bar3, 4)
    pg.finish(bar3)  # a call that failed: the bar shows how far it came, total unchanged
    assert bar3.total == 10 and bar3.n == 4


def _totals(err: str, desc: str) -> set[str]:
    """The totals a tqdm bar ``desc`` showed in its refreshes ("k/N" -> N)."""
    lines = [ln for ln in err.replace("\r", "\n").splitlines() if ln.startswith(desc)]
    assert lines, err
    return {m.split("/")[1] for ln in lines for m in re.findall(r"\b\d+/\d+\b", ln)}


def test_diagnose_bar_shows_one_total_from_its_first_refresh_to_its_end(monkeypatch, capsys):
    """The ETA means something only with the total known from the start (it was shown
    without one, then 25, then lowered to 13 at the end)."""
    monkeypatch.delenv("CI", raising=False)
    joint = ie.IwanJoint(ie.IwanParameters(Fs=9e3, KT=5e7, chi=-0.5, beta=0.5))
    rec = ie.simulate_element_test(
        ie.Backlash(joint, gap=2e-5), [1e-4, 3e-4], cycles=2, force_noise=20.0, seed=1
    )
    ie.diagnose(
        rec.t,
        rec.u,
        rec.F,
        candidates=("backlash", "viscous_damping"),
        max_effects=1,
        probabilities=False,
        max_samples=300,
        progress=True,
    )
    err = capsys.readouterr().err
    lines = [ln for ln in err.replace("\r", "\n").splitlines() if ln.startswith("diagnose")]
    assert all(re.search(r"\b\d+/\d+\b", ln) for ln in lines), lines  # a total on each
    (total,) = _totals(err, "diagnose")
    assert f"{total}/{total}" in lines[-1]


def test_fit_warnings_reach_stderr_one_per_line():
    """Each warning of a fit is one Python warning (one line on stderr), not one line of
    them all joined."""
    from iwan_element.identify.loops.result import IdentifiabilityWarning

    p = ie.IwanParameters(Fs=9e3, KT=5e7, chi=-0.5, beta=0.5)
    # microslip loops with unsmoothed displacement noise: three warnings
    amplitudes = np.array([0.025, 0.05, 0.1]) * 1e-3
    d = ie.simulate_test(
        p, amplitudes, cycles=2, sample_rate=10, force_noise=15.0, displacement_noise=1e-6, seed=0
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fit = ie.fit_loops(d.t, d.u, d.F, smooth=0)
    mine = [str(w.message) for w in caught if issubclass(w.category, IdentifiabilityWarning)]
    assert len(fit.warnings) >= 2, fit.warnings
    assert len(mine) == len(fit.warnings)
    assert all(" | " not in m and "\n" not in m for m in mine)


def test_off_by_default_silent_under_ci_and_checked(monkeypatch):
    assert pg.progress_bar(False, total=3, desc="x", unit="s") is None
    monkeypatch.setenv("CI", "true")
    assert pg.progress_bar(True, total=3, desc="x", unit="s") is None
    pg.tick(None)
    pg.finish(None)
    with pytest.raises(ValueError, match="progress must be True or False"):
        pg.progress_bar("yes", desc="x", unit="s")


def test_forced_response_shows_every_point_with_a_total(monkeypatch, capsys):
    monkeypatch.delenv("CI", raising=False)
    s = models.preset("example").replace(n_points=8, damping_floor=0.05)
    models.forced_response(
        s,
        force_levels=(1.0,),
        frequencies=[60.0, 66.6, 73.0],
        settle_cycles=1,
        measure_cycles=1,
        steps_per_period=16,
        progress=True,
    )
    err = capsys.readouterr().err
    assert "forced_response" in err and "3/3" in err


def test_fit_decay_shows_its_stages(monkeypatch, capsys):
    monkeypatch.delenv("CI", raising=False)
    rng = np.random.default_rng(0)
    t = np.arange(4000) / 2000.0
    y = np.exp(-2 * np.pi * 80 * 0.004 * t) * np.sin(2 * np.pi * 80 * t)
    y += 1e-3 * rng.standard_normal(t.size)
    ie.fit_decay(t, y, quantity="displacement", band=(60.0, 100.0), progress=True)
    err = capsys.readouterr().err
    assert "fit_decay" in err and "stage" in err
