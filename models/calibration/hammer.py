"""A whole hammer test predicted from one mode: calibrate on mode 1, predict the others.

:func:`predict_hammer_test` takes a specimen and the hammer ring-down records of several
accelerometers along the beam's axis and runs the route of ``docs/multi_mode.md``
section 4:

1. **Bands.** Each mode's band around the specimen's stuck frequency (``band_width``
   either side), cut at the geometric mean with the neighbouring modes' frequencies
   (:func:`mode_bands`), unless given.
1a. **Linear update** (``update``, on by default): every mode's natural frequency in its
   latest linear (low-amplitude) window of all the records (:func:`iwan_element.
   free_decay_modes`), and :func:`~iwan_element.models.updating.linear_update` of the named
   parameters on them before any joint calibration (docs/linear_update.md): the linear
   structure from the low-level data, then the joint from the amplitude dependence.
2. **Measured curves.** f(X), zeta(X) of every mode at every sensor
   (:func:`iwan_element.amplitude_curve`, from the impact on: the largest sample of the
   calibration record). The calibration mode is read in fixed windows of
   ``calibration_periods`` periods, the other modes in windows that follow the decay.
3. **Calibration.** :func:`~iwan_element.models.calibration.calibrate` on the calibration
   mode at the calibration sensor (the record at ``specimen.sensor_position``): the joint
   comes from that mode alone; each other mode gives only its linear floor, from its
   lowest-amplitude points at that sensor (``floors=``).
4. **Release.** ``release_time`` after the impact, each mode's displacement amplitude at the
   calibration sensor from a straight-line fit of its log envelope over the next
   ``fit_span`` seconds (:func:`release_amplitudes`; zero-phase Butterworth band-pass and
   Hilbert magnitude, :mod:`scipy.signal`). Right after an impact the envelopes hold the
   band-pass filters' response to it; ``release_time`` should exceed about two time
   constants of the narrowest band's filter.
5. **Prediction.** The multi-mode ring-down (:func:`~iwan_element.models.ringdown`,
   ``amplitude={mode: X}``, ``sensors=`` every record's position), each predicted record
   read like the measured one (:meth:`RingdownResult.sensor_curve`), every predicted curve
   against the measured one at the same amplitudes
   (:func:`~iwan_element.models.simulation.compare_curves`), and per mode the ratio of its
   amplitude at each other sensor to the calibration sensor's, measured and predicted (a
   mode-shape check, median envelope ratio over the ring-down).
"""

from __future__ import annotations

import math

import numpy as np

from iwan_element import amplitude_curve, free_decay_modes
from iwan_element.base.stages import require_usable
from iwan_element.base.validation import check_scalar, check_uniform_time, finite_array
from iwan_element.identify.decays.envelope import mode_envelope

from ..modal.qsma import linear_modes
from ..reduced.dispatch import linear_system
from ..simulation.coupling import compare_curves
from ..simulation.ringdown_records import check_run_length, min_record
from ..simulation.solver import MAX_STEPS
from ..simulation.transient import ringdown
from ..updating.result import LinearUpdateResult
from ..updating.update import linear_update
from .hammer_result import HammerPrediction
from .vibration import calibrate

__all__ = ["mode_bands", "release_amplitudes", "predict_hammer_test"]

#: The keyword that lets :func:`predict_hammer_test` go on past an unusable stage.
_GO_ON = "allow_unusable=True"


def mode_bands(specimen, modes, *, band_width: float = 0.12) -> dict:
    """``{mode: (low, high)}`` [Hz]: each mode's stuck frequency times ``1 -+ band_width``,
    cut at the geometric mean with its neighbours' frequencies.
    """
    modes = _modes(modes)
    w = check_scalar("band_width", band_width, low=0.01, high=0.5)
    f = _elastic_frequencies(specimen, max(modes) + 1)
    out = {}
    for r in modes:
        lo, hi = f[r - 1] * (1 - w), f[r - 1] * (1 + w)
        if r >= 2:
            lo = max(lo, math.sqrt(f[r - 2] * f[r - 1]))
        hi = min(hi, math.sqrt(f[r - 1] * f[r]))
        out[r] = (float(lo), float(hi))
    return out


def _elastic_frequencies(specimen, n: int) -> np.ndarray:
    """The ``n`` lowest elastic stuck frequencies [Hz] (rigid-body modes left out)."""
    return np.array([linear_modes(specimen, mode=k)[0] for k in range(1, n + 1)]) / (2 * math.pi)


def release_amplitudes(
    t, a, bands: dict, *, release_time: float = 0.05, fit_span: float = 0.3
) -> dict:
    """``{mode: X}``: each mode's displacement amplitude [m] ``release_time`` [s] after the
    impact (the largest sample of ``a``), from a straight-line fit of its log envelope over
    ``[release_time, release_time + fit_span]`` (module docstring, step 4).

    Parameters
    ----------
    t : array_like, shape (n,)
        Times [s], uniformly sampled.
    a : array_like, shape (n,)
        Acceleration [m/s^2].
    bands : dict
        ``{mode: (low, high)}`` [Hz].
    release_time, fit_span : float, keyword-only
        [s], ``release_time >= 0``, ``fit_span > 0``.
    """
    t, a = _series("t", "a", t, a)
    t_r = check_scalar("release_time", release_time, low=0.0)
    span = check_scalar("fit_span", fit_span, low=0.0, low_open=True)
    t = t - t[np.argmax(np.abs(a))]
    fit = (t >= t_r) & (t <= t_r + span)
    if t[-1] < t_r + span or fit.sum() < 16:
        raise ValueError(
            f"release_time + fit_span = {t_r + span:g} s reaches beyond the "
            f"record's {t[-1]:.4g} s after the impact (or holds fewer than 16 "
            "samples): shorten them or give a longer record"
        )
    out = {}
    for r, band in bands.items():
        env = mode_envelope(t, a, band, integrate=2, span=fit)
        slope, icpt = np.polyfit(t[fit], np.log(env[fit]), 1)
        out[int(r)] = float(math.exp(icpt + slope * t_r))
    return out


def predict_hammer_test(
    specimen,
    records: dict,
    *,
    modes=(1, 2),
    calibration_mode: int = 1,
    fit=("stiffness_per_area", "friction", "chi", "damping_floor"),
    bands: dict | None = None,
    band_width: float = 0.12,
    release_time: float = 0.05,
    fit_span: float = 0.3,
    duration: float = 1.0,
    calibration_periods: float = 20.0,
    update=("youngs_modulus", "stiffness_per_area"),
    progress: bool = False,
    allow_unusable: bool = False,
    max_steps: int = MAX_STEPS,
) -> HammerPrediction:
    """Calibrate the interface on one mode of a hammer test and predict every other mode at
    every sensor by the multi-mode ring-down (module docstring; ``docs/multi_mode.md``).

    Parameters
    ----------
    specimen : Specimen
        The specimen to calibrate (its interface, friction and floors are fitted).
    records : dict
        ``{sensor name: (position [m], t [s], a [m/s^2])}``: each accelerometer's position
        along the beam's axis (the axis of ``specimen.sensor_position``) and its record,
        all on the same clock from before the impact on. One record must sit at
        ``specimen.sensor_position`` (within 1 mm): the calibration sensor.
    modes : sequence of int, keyword-only
        The modes to predict (1: lowest elastic), the calibration mode among them.
    calibration_mode : int, keyword-only
        The mode the joint is calibrated on (default 1).
    fit : sequence of str, keyword-only
        The interface parameters the calibration fits (``calibrate``'s ``fit``).
    bands : dict, optional, keyword-only
        ``{mode: (low, high)}`` [Hz]; default :func:`mode_bands` of the specimen.
    band_width : float, keyword-only
        Relative half-width of the default bands, [0.01, 0.5].
    release_time, fit_span : float, keyword-only
        When the prediction starts after the impact and the span of the envelope fit that
        reads its amplitudes [s] (:func:`release_amplitudes`).
    duration : float, keyword-only
        Length of the predicted ring-down [s]: at least 6 periods of the lowest mode
        (:func:`~iwan_element.models.ringdown`'s minimum at its windows of 3 periods),
        checked with its cost (``max_steps``) on the given specimen before any stage runs.
    calibration_periods : float, keyword-only
        Window of the calibration mode's curves in its periods (>= 3).
    update : sequence of str or None, keyword-only
        Parameters (or groups) of :func:`~iwan_element.models.updating.updatable` updated on
        the modes' low-amplitude natural frequencies before the calibration (module
        docstring, step 1a); ``None``: the specimen's linear structure as given.
    progress : bool, keyword-only
        Progress bars of the calibration and the ring-down.
    allow_unusable : bool, keyword-only
        Go on to the ring-down after a linear update or a calibration that is not usable
        (default False: the route stops there, below). For an expert who wants to see what
        such parameters predict; the result then says so in its warnings and is no success.
    max_steps : int, keyword-only
        Most time steps of the predicted ring-down (``ringdown``'s ``max_steps``).

    Returns
    -------
    HammerPrediction

    Raises
    ------
    ValueError
        An argument out of its range (named), a ``duration`` too short for the curves or
        longer than ``max_steps`` allows (before any stage runs).
    iwan_element.base.stages.StageFailed
        (a ValueError) The linear update or the calibration is not usable (a parameter on
        its bound, not identified, no convergence): the route stops there with that stage's
        reasons, before the ring-down, unless ``allow_unusable=True``.
    """
    run = {"duration": duration, "max_steps": max_steps, "allow_unusable": allow_unusable}
    modes, recs, cal_name, bands, n_cal = _inputs(
        specimen, records, modes, calibration_mode, bands, band_width, calibration_periods, run
    )
    f_cal = float(_elastic_frequencies(specimen, calibration_mode)[-1])
    windows = {r: ({"window": n_cal / f_cal} if r == calibration_mode else {}) for r in modes}
    measured, skipped = _measured_curves(recs, cal_name, bands, windows)
    _, t_c, a_c = recs[cal_name]
    release = release_amplitudes(t_c, a_c, bands, release_time=release_time, fit_span=fit_span)
    upd = None
    if update is not None:
        upd = _linear_update(specimen, recs, cal_name, bands, update)
        require_usable("linear update", upd, allow=allow_unusable, override=_GO_ON)
        specimen = upd.specimen
    floors = {r: measured[(r, cal_name)] for r in modes if r != calibration_mode}
    cal = calibrate(
        specimen,
        measured[(calibration_mode, cal_name)],
        fit=fit,
        mode=calibration_mode,
        floors=floors or None,
        progress=progress,
    )
    require_usable("calibration", cal, allow=allow_unusable, override=_GO_ON)
    names = tuple(recs)
    rd = ringdown(
        cal.specimen,
        amplitude=release,
        duration=duration,
        progress=progress,
        sensors=tuple(recs[n][0] for n in names),
        max_steps=max_steps,
    )
    predicted = {
        (r, n): rd.sensor_curve(i, bands[r], n_periods=n_cal if r == calibration_mode else None)
        for i, n in enumerate(names)
        for r in modes
        if (r, n) in measured
    }
    errors = {k: compare_curves(predicted[k], measured[k]) for k in predicted}
    ratios = _ratios(recs, cal_name, rd, bands, modes, release_time)
    warns, thin = _warnings(upd, cal, rd, skipped, errors)
    return HammerPrediction(
        calibration=cal,
        calibration_mode=calibration_mode,
        calibration_sensor=cal_name,
        bands=bands,
        release=release,
        ringdown=rd,
        measured=measured,
        predicted=predicted,
        errors=errors,
        ratios=ratios,
        update=upd,
        sensors=tuple((n, float(recs[n][0])) for n in names),
        calibration_periods=float(n_cal),
        success=bool(cal.success and not thin and (upd is None or upd.success)),
        warnings=tuple(warns),
    )


def _inputs(
    specimen, records, modes, calibration_mode, bands, band_width, calibration_periods, run
):
    """:func:`predict_hammer_test`'s checked inputs: ``(modes, records, calibration sensor,
    bands, calibration periods)``; ``run``: the ring-down's ``duration`` and ``max_steps``,
    checked on the given specimen's stuck frequencies before any stage runs (the
    ring-down checks them again on the calibrated one), and ``allow_unusable``.
    """
    if not isinstance(run["allow_unusable"], (bool, np.bool_)):
        raise ValueError(f"allow_unusable must be True or False, got {run['allow_unusable']!r}")
    modes = _modes(modes)
    if calibration_mode not in modes:
        raise ValueError(f"calibration_mode must be one of modes {modes}, got {calibration_mode!r}")
    recs = _records(specimen, records)
    cal_name = _calibration_sensor(specimen, recs)
    bands = (
        mode_bands(specimen, modes, band_width=band_width)
        if bands is None
        else _bands(bands, modes)
    )
    duration = check_scalar("duration", run["duration"], low=0.0, low_open=True)
    check_run_length(
        2 * math.pi * _elastic_frequencies(specimen, max(modes))[[r - 1 for r in modes]],
        64,  # ringdown's default, which the prediction runs
        n_periods=3.0,
        duration=duration,
        cycles=None,
        impact=None,
        n_coordinates=linear_system(specimen).M.shape[0],
        max_steps=run["max_steps"],
    )
    n_cal = check_scalar("calibration_periods", calibration_periods, low=3.0)
    _check_read_length(specimen, modes, calibration_mode, bands, n_cal, duration)
    return modes, recs, cal_name, bands, n_cal


def _check_read_length(specimen, modes, calibration_mode, bands, n_cal, duration) -> None:
    """Refuse a ``duration`` [s] too short for the predicted records to be read in their
    bands (:func:`~iwan_element.models.simulation.ringdown_records.min_record`: the
    calibration mode in windows of ``n_cal`` periods, the others in windows of at least 3
    periods), before any stage runs.
    """
    f = _elastic_frequencies(specimen, max(modes))
    for r in modes:
        periods = n_cal if r == calibration_mode else 3.0
        need = min_record(bands[r], periods / f[r - 1])
        if duration < need:
            lo, hi = bands[r]
            raise ValueError(
                f"duration must be >= {need:.4g} s to read the predicted mode {r} in its "
                f"band ({lo:.4g}, {hi:.4g}) Hz: the reader needs 6 / B (B = {hi - lo:.4g} Hz, "
                f"the band's width) to find the mode, and 1.5 / B of filter end effects at "
                f"each end around one window of {periods:g} periods; got {duration!r} "
                "(or widen the band: band_width, bands)"
            )


def _warnings(upd, cal, rd, skipped, errors):
    """``(warnings, thin)``: the update's, calibration's and ring-down's warnings, the
    records left out, and the (mode, sensor) pairs with fewer than 3 common amplitudes.
    """
    warns = [f"linear update: {w}" for w in (upd.warnings if upd is not None else ())]
    warns += [f"calibration: {w}" for w in cal.warnings] + [f"ring-down: {w}" for w in rd.warnings]
    warns += skipped
    warns += [
        f"the {what} is not usable and the prediction was run anyway ({_GO_ON})"
        for what, res in (("linear update", upd), ("calibration", cal))
        if res is not None and not res.success
    ]
    thin = [f"mode {r} at {n}" for (r, n), e in errors.items() if len(e["amplitude"]) < 3]
    if thin:
        warns.append(
            f"fewer than 3 common amplitudes of prediction and measurement: "
            f"{', '.join(thin)} (a sensor near a node of the mode, or a band that "
            "misses it)"
        )
    return warns, thin


def _linear_update(specimen, recs, cal_name, bands, parameters) -> LinearUpdateResult:
    """Step 1a: the modes' natural frequencies in their latest linear windows of all the
    records (from the impact on) and the linear update of ``parameters`` on them.
    """
    _, t_c, a_c = recs[cal_name]
    t_imp = t_c[np.argmax(np.abs(a_c))]
    keep = t_c >= t_imp
    targets = free_decay_modes(
        t_c[keep],
        {n: (x, a[t >= t_imp]) for n, (x, t, a) in recs.items()},
        bands={str(r): b for r, b in bands.items()},
    )
    found = {int(m.label): m.index for m in targets.modes}
    missing = sorted(set(bands) - set(found))
    if missing:
        raise ValueError(
            f"the linear update needs every mode's low-amplitude frequency; modes "
            f"{missing} gave none in their bands (pass update=None, or other "
            "bands)"
        )
    freqs = {r: (targets.frequencies[k], targets.frequency_stderr[k]) for r, k in found.items()}
    return linear_update(specimen, frequencies=freqs, parameters=parameters)


def _measured_curves(recs, cal_name, bands, windows):
    """``({(mode, sensor): AmplitudeCurve}, warnings)``: every mode at every sensor from the
    impact on (the calibration record's largest sample: one clock). A mode the calibration
    sensor does not give is an error; one another sensor does not (a node, noise) is left out
    with a warning.
    """
    _, t_c, a_c = recs[cal_name]
    t_imp = t_c[np.argmax(np.abs(a_c))]
    out, skipped = {}, []
    for name, (_, t, a) in recs.items():
        keep = t >= t_imp
        for r, band in bands.items():
            try:
                out[(r, name)] = amplitude_curve(
                    t[keep], a[keep], quantity="acceleration", band=band, **windows[r]
                )
            except ValueError as exc:
                if name == cal_name:
                    raise ValueError(
                        f"records[{name!r}] (the calibration sensor), mode {r}: {exc}"
                    ) from exc
                skipped.append(
                    f"mode {r} at {name} not read from the record ({exc}); left "
                    "out of the comparison"
                )
    return out, skipped


def _ratios(recs, cal_name, rd, bands, modes, release_time) -> dict:
    """``{(mode, sensor): (measured, predicted)}`` median envelope ratios to the calibration
    sensor over the ring-down (its first and last 50 ms left out: filter end effects).
    """
    out = {}
    edge = 0.05
    span = (edge, rd.t[-1] - edge)
    _, t_c, a_c = recs[cal_name]
    t0 = t_c[np.argmax(np.abs(a_c))] + release_time
    i_c = tuple(recs).index(cal_name)
    mp = (rd.t >= span[0]) & (rd.t <= span[1])
    # the calibration sensor's envelopes, measured and predicted, once per mode
    ref = {
        r: (
            mode_envelope(t_c, a_c, bands[r], integrate=2),
            mode_envelope(rd.t, rd.sensor_acceleration[i_c], bands[r], integrate=2)[mp],
        )
        for r in modes
    }
    for i, (name, (_, t, a)) in enumerate(recs.items()):
        if name == cal_name:
            continue
        m = (t - t0 >= span[0]) & (t - t0 <= span[1])
        for r in modes:
            meas = np.median(mode_envelope(t, a, bands[r], integrate=2)[m] / ref[r][0][m])
            pred = np.median(
                mode_envelope(rd.t, rd.sensor_acceleration[i], bands[r], integrate=2)[mp]
                / ref[r][1]
            )
            out[(r, name)] = (float(meas), float(pred))
    return out


def _modes(modes) -> tuple:
    try:
        out = tuple(modes)
    except TypeError:
        out = ()
    if (
        not out
        or any(isinstance(r, bool) or not isinstance(r, (int, np.integer)) or r < 1 for r in out)
        or len(set(out)) != len(out)
    ):
        raise ValueError(f"modes must be distinct mode numbers >= 1, got {modes!r}")
    return tuple(sorted(int(r) for r in out))


def _bands(bands, modes) -> dict:
    if not isinstance(bands, dict) or set(bands) != set(modes):
        raise ValueError(
            f"bands must be a dict {{mode: (low, high)}} [Hz] for modes {modes}, got {bands!r}"
        )
    out = {}
    for r in modes:
        lo, hi = (float(b) for b in bands[r])
        if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
            raise ValueError(
                f"bands[{r}] must be (low, high) with 0 < low < high [Hz], got {bands[r]!r}"
            )
        out[r] = (lo, hi)
    return out


def _series(tn, an, t, a):
    """``(t, a)`` as new arrays: ``a`` finite with at least 64 samples, ``t`` its uniform
    time grid (:func:`~iwan_element.base.validation.check_uniform_time`).
    """
    a = finite_array(an, a, min_size=64)
    t, _ = check_uniform_time(t, a.size, name=tn, data=an)
    return t, a


def _records(specimen, records) -> dict:
    if not isinstance(records, dict) or not records:
        raise ValueError(
            "records must be a non-empty dict {name: (position [m], t [s], a [m/s^2])}"
        )
    length = 2 * specimen.beam_length - specimen.overlap
    out = {}
    for name, rec in records.items():
        if not isinstance(rec, (tuple, list)) or len(rec) != 3:
            raise ValueError(f"records[{name!r}] must be (position [m], t [s], a [m/s^2])")
        x = check_scalar(f"records[{name!r}] position", rec[0], low=0.0, high=length)
        t, a = _series(f"records[{name!r}] t", f"records[{name!r}] a", rec[1], rec[2])
        out[str(name)] = (x, t, a)
    return out


def _calibration_sensor(specimen, recs) -> str:
    near = [n for n, (x, _, _) in recs.items() if abs(x - specimen.sensor_position) <= 1e-3]
    if not near:
        raise ValueError(
            f"records must hold one record at the specimen's sensor position "
            f"{specimen.sensor_position:g} m (within 1 mm): the calibration "
            f"sensor; positions given: "
            f"{', '.join(f'{n} {x:g}' for n, (x, _, _) in recs.items())}"
        )
    return near[0]
