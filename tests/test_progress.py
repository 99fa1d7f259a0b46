"""Progress bars (``iwan_element.base.progress``): a total and so an ETA on every long call,
off by default, silent under CI, a clear error without tqdm or for a non-bool."""

from __future__ import annotations

import inspect

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


def test_bar_has_a_total_grows_past_it_and_closes_at_the_count(monkeypatch):
    monkeypatch.delenv("CI", raising=False)
    bar = pg.progress_bar(True, total=3, desc="x", unit="step")
    pg.tick(bar, text="a")
    pg.tick(bar, 3)  # more than announced: the total follows
    assert bar.n == 4 and bar.total == 4
    bar2 = pg.progress_bar(True, total=10, desc="x", unit="step")
    pg.tick(bar2, 2)
    pg.finish(bar2)  # an upper bound is lowered to the count reached
    assert bar2.total == 2 and bar2.n == 2


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
