"""One stage's failure stops the next, and a run's length is checked before it starts.

Issue 45, cases 9-13: a release whose static solve did not converge, a calibration that is
not usable, a run too short for its decay curves or longer than anyone would wait: each is
refused before the first time step with the failing stage's or argument's own reason. The
refusals are sub-second; the minimum run length is checked against the decay reader itself
on numpy decays (an independent route: no simulation), and one simulation of the minimum
length shows that it gives a curve.
"""

import math
import time

import numpy as np
import pytest

from iwan_element import amplitude_curve
from iwan_element.base.stages import StageFailed, require_usable, stop_at

models = pytest.importorskip("iwan_element.models", reason="iwan_element.models needs exudyn")
from iwan_element.models.calibration import mode_bands  # noqa: E402
from iwan_element.models.simulation.ringdown_records import min_cycles  # noqa: E402
from iwan_element.models.simulation.solver import MAX_STEPS  # noqa: E402

EXAMPLE = models.preset("example")
TWO_BOLT = models.preset("two-bolt-aluminium")


def _f(specimen, mode=1) -> float:
    """Stuck frequency [Hz] of an elastic mode, from the linear modes."""
    return models.modal.linear_modes(specimen, mode=mode)[0] / (2 * math.pi)


@pytest.fixture(scope="module", autouse=True)
def _modes_cached():
    """The specimens' stuck modes and static condensations computed once, outside the timed
    refusals (they are cached; the first computation takes seconds on a loaded machine)."""
    from iwan_element.models.modal.qsma import static_modal_load

    for spec in (EXAMPLE, TWO_BOLT):
        for mode in (1, 2):
            static_modal_load(spec, [1e-6], mode=mode)


def _fast(fn, *args, **kw):
    """Call ``fn`` expecting a refusal; returns the error and asserts it took < 5 s: no
    simulation ran (the refusals take 0.02-0.6 s once the specimen's modes are cached; the
    failing runs they replace took 12-67 s)."""
    t0 = time.perf_counter()
    with pytest.raises(ValueError) as err:
        fn(*args, **kw)
    assert time.perf_counter() - t0 < 5.0
    return err.value


# ------------------------------------------------------------------ the shared stage rule
class _Result:
    def __init__(self, success, reasons=(), warnings=()):
        self.success, self._r, self.warnings = success, reasons, warnings

    def failure_reasons(self):
        return () if self.success else self._r


def test_a_stage_that_is_not_usable_stops_the_route_with_its_own_reasons():
    ok = _Result(True)
    assert require_usable("fit", ok) is ok
    bad = _Result(False, ("chi ended on its bound",))
    with pytest.raises(StageFailed) as err:
        require_usable("calibration", bad, override="allow_unusable=True")
    e = err.value
    assert isinstance(e, ValueError) and e.stage == "calibration"
    assert e.reasons == ("chi ended on its bound",)
    assert "calibration is not usable" in str(e) and "allow_unusable=True" in str(e)
    assert require_usable("calibration", bad, allow=True) is bad  # the expert's override
    # a result without failure_reasons gives its warnings
    with pytest.raises(StageFailed, match="noisy"):
        require_usable("fit", type("R", (), {"success": False, "warnings": ("noisy",)})())
    assert stop_at("release", []) is None
    with pytest.raises(StageFailed, match="did not converge"):
        stop_at("release", ["did not converge"])


# ------------------------------------------------------------------ case 9: the release
def test_a_release_that_does_not_converge_stops_before_any_step():
    """Case 9: the two-bolt beam released from 0.5 m (1000 x its amplitude range) ended in an
    Exudyn SolverError after 12-22 s, the static solve's own warning dropped."""
    e = _fast(models.ringdown, TWO_BOLT, amplitude=0.5)
    assert isinstance(e, StageFailed) and e.stage == "release"
    assert "amplitude of mode 1 = 0.5 m" in str(e) and "did not converge" in str(e)
    assert "amplitude_range is 5e-06-0.0005 m" in str(e)
    # mode_coupling checks every run's release before the first run
    e = _fast(models.mode_coupling, TWO_BOLT, amplitude={1: 0.5, 2: 1e-6}, duration=1.0)
    assert isinstance(e, StageFailed) and "amplitude of mode 1 = 0.5 m" in str(e)


# ------------------------------------------------------------------ cases 10, 11: too short
def test_a_run_too_short_for_its_curves_is_refused_naming_the_argument_and_the_minimum():
    """Cases 10 and 11: duration=1e-4 ended in "numberOfSteps must be positive" (ringdown)
    and "y must have at least 64 samples, got 1" (mode_coupling); cycles=2.5, which the
    docstring allowed, simulated first and then failed on 41 samples; cycles=4 on "no clear
    mode ... widen the band"."""
    f1 = _f(EXAMPLE)
    need = 6.0 / f1  # 6 periods of mode 1 at the default n_periods = 3
    for fn, kw in (
        (models.ringdown, {"amplitude": 1e-4}),
        (models.mode_coupling, {"amplitude": {1: 1e-4, 2: 1e-5}}),
    ):
        e = _fast(fn, EXAMPLE, duration=1e-4, **kw)
        assert f"duration must be >= {need:.4g} s" in str(e), str(e)
    for c in (2.5, 4.0, 5.9):
        e = _fast(models.ringdown, EXAMPLE, amplitude=1e-4, cycles=c, steps_per_period=16)
        assert "cycles must be >= 6 " in str(e) and f"got {c}" in str(e)
    e = _fast(models.ringdown, EXAMPLE, amplitude=1e-4, cycles=12, n_periods=10)
    assert "cycles must be >= 13 " in str(e) and "n_periods = 10" in str(e)
    # an impact's run is read the same way
    imp = models.Impact(position=0.3, peak_force=50.0, contact_time=2e-4)
    e = _fast(models.ringdown, EXAMPLE, impact=imp, duration=0.05)
    assert f"duration must be >= {need:.4g} s" in str(e)


@pytest.mark.parametrize("n_periods", [3.0, 10.0])
def test_the_minimum_length_is_what_the_decay_reader_needs(n_periods):
    """The reader on numpy decays of the example beam's first mode (band (0.5, 1.5) f0, as the
    ring-down reads it): one period below the minimum it is refused, at the minimum it gives a
    point (measured: the reader's own limit lies 0.5-0.7 periods below)."""
    f0, z = 66.49, 1e-3
    w = 2 * math.pi * f0

    def read(c, spp):
        t = np.arange(int(round(c * spp)) + 1) / (spp * f0)
        y = 1e-4 * np.exp(-z * w * t) * np.cos(w * math.sqrt(1 - z * z) * t)
        band = (0.5 * f0, 1.5 * f0)
        return amplitude_curve(t, y, band=band, n_periods=n_periods, compare=False)

    c = min_cycles(n_periods)
    for spp in (16, 64) if n_periods == 3.0 else (16,):  # (64 at n_periods = 10: 10 s)
        assert len(read(c, spp)) >= 1
        with pytest.raises(ValueError, match="record too short|no clear mode"):
            read(c - 1.0, spp)


def test_a_ring_down_of_the_minimum_length_gives_its_curve():
    r = models.ringdown(EXAMPLE, amplitude=1e-4, cycles=6, steps_per_period=16)
    assert len(r.curve) >= 1
    assert r.curve.frequency[0] == pytest.approx(_f(EXAMPLE), rel=2e-3)


# ------------------------------------------------------------------ case 12: the step budget
def test_a_run_beyond_the_step_budget_is_refused_with_its_estimate():
    """Case 12: the two-bolt beam for 1e6 s at 16 steps a period started 3.5e8 steps (hours)
    without a word."""
    e = _fast(models.ringdown, TWO_BOLT, amplitude=1e-4, duration=1e6, steps_per_period=16)
    n = round(1e6 * _f(TWO_BOLT) * 16)  # steps per period of the (only) released mode
    assert f"would take {n:.3g} time steps" in str(e), str(e)
    assert f"max_steps = {MAX_STEPS}" in str(e) and "GB of records" in str(e)
    # the budget counts every run of mode_coupling (together + each mode alone)
    f2 = _f(TWO_BOLT, 2)
    dur = 110_000 / (64 * f2)  # 110,000 steps together and as many for mode 2 alone
    assert 110_000 < MAX_STEPS < 220_000
    e = _fast(models.mode_coupling, TWO_BOLT, amplitude={1: 1e-4, 2: 1e-5}, duration=dur)
    assert "mode_coupling's 3 ring-downs" in str(e)
    # overridable, and checked as an argument
    e = _fast(models.ringdown, EXAMPLE, amplitude=1e-4, cycles=6, steps_per_period=16, max_steps=95)
    assert "would take 96 time steps" in str(e)
    with pytest.raises(ValueError, match="max_steps must be"):
        models.ringdown(EXAMPLE, amplitude=1e-4, max_steps=0)
    r = models.ringdown(EXAMPLE, amplitude=1e-4, cycles=6, steps_per_period=16, max_steps=96)
    assert r.metadata["steps"] == 96


# ------------------------------------------------------------------ case 13: the calibration
def _linear_records(specimen, *, t_end=4.0, fs=4096.0):
    """A hammer record of a linear structure: two modes at the specimen's stuck frequencies
    with constant damping ratios."""
    t = np.arange(-0.01, t_end, 1.0 / fs)
    tt = np.clip(t, 0.0, None)
    a = np.zeros_like(t)
    for x, r, z in ((3e-4, 1, 2e-3), (2e-5, 2, 1e-3)):
        w = 2 * math.pi * _f(specimen, r)
        a -= w * w * x * np.exp(-z * w * tt) * np.cos(w * math.sqrt(1 - z * z) * tt)
    return {"tip": (specimen.sensor_position, t, a * (t >= 0))}


def test_the_hammer_route_stops_after_a_calibration_that_is_not_usable():
    """Case 13: records of a linear structure; the calibration is not usable (its
    amplitude-dependent parameters end on their bounds), yet the ring-down ran and ended in
    a SolverError after 67-106 s. Now the route stops after the calibration with its
    reasons, and names the override."""
    spec = TWO_BOLT.replace(n_points=12)
    recs = _linear_records(spec)
    with pytest.raises(StageFailed) as err:
        models.predict_hammer_test(spec, recs, update=None, duration=1.5, calibration_periods=10)
    e = err.value
    assert e.stage == "calibration" and e.override == "allow_unusable=True"
    assert any("on its bound" in r for r in e.reasons), e.reasons
    assert "allow_unusable=True" in str(e)
    # the run's length and the override are checked before any stage: the ring-down's
    # minimum, then the reading of each predicted record in its band (the route ran its
    # calibration and ring-down before "band (18.1176, 23.0588) Hz is too narrow for the
    # record length (0.6 s)" at duration=0.6, 29 s)
    e = _fast(models.predict_hammer_test, spec, recs, update=None, duration=0.1)
    assert f"duration must be >= {6.0 / _f(spec):.4g} s" in str(e)
    lo, hi = mode_bands(spec, (1, 2))[1]
    e = _fast(
        models.predict_hammer_test, spec, recs, update=None, duration=0.6, calibration_periods=10
    )
    assert f"duration must be >= {6.0 / (hi - lo):.4g} s to read the predicted mode 1" in str(e)
    _fast(models.predict_hammer_test, spec, recs, update=None, allow_unusable="yes")


def test_a_forced_sweep_beyond_the_step_budget_is_refused_before_it_starts():
    n = 2 * 15 * (10_000 + 10) * 60  # levels x frequencies x cycles x steps a period
    e = _fast(models.forced_response, EXAMPLE, settle_cycles=10_000)
    assert f"forced_response would take {n:.3g} time steps" in str(e), str(e)
    assert "settle_cycles" in str(e) and "GB" not in str(e)
