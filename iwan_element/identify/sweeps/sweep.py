"""Frequency and damping against amplitude from raw stepped-sine sweeps (single nonlinear mode).

Every point of a sweep (drive frequency ``W``, fundamental force amplitude ``F``, response
amplitude and phase relative to the force) is read as the mode at its own amplitude
(the single-nonlinear-mode idea of Szemplinska-Stupnicka, exact reference not checked here;
amplitude-dependent modal properties of friction-damped structures from steady forced
response: Scheel, Peter, Leine, Krack, J. Sound Vib. 435:56-73, 2018). With drive and
response at the same point, one dominant mode and a real modal constant ``c`` shared by all
points (``docs/equations.md`` §8.2; the algorithm in ``docs/sweeps.md``)::

    H = X exp(i phi) / F = c / (w_r(X)**2 - W**2 + 2 i zeta_r(X) w_r(X) W) + B

with ``X`` the displacement amplitude (``A / W**2`` for an acceleration ``A``) and ``B`` a
real residual of the other modes (constant over the narrow band of a sweep). Each point
then gives, for its own amplitude,
``w_r**2 = W**2 + Re G`` and ``zeta_r = Im G / (2 w_r W)`` with ``G = c / (H - B)``.
Neither the force nor the response need be constant along a sweep.

``c`` and ``B`` are fitted to all points at once, together with smooth curves
``w_r(X)**2`` and ``ln zeta_r(X)`` (polynomials in ``ln X``): weighted least squares on the
complex receptance with a relative error per point. That is the requirement that points of
different sweeps at the same amplitude agree. Each point kept (``|H| >= peak_fraction``
times its sweep's peak, where the inversion is well conditioned) is then inverted with the
fitted ``c`` and ``B``, and the points are averaged in bins of ``ln X`` (inverse-variance
weights from the propagated receptance error); the bin's standard error combines the larger
of the propagated and the observed scatter with the uncertainty of ``c`` and ``B``.
"""

from __future__ import annotations

import math

import numpy as np

from ...base.plausibility import QUANTITY_POWER, V_MAX, level_failure
from ...base.validation import check_magnitude, check_scalar, finite_array, same_length
from ..modal.curves import AmplitudeCurve
from ._sweep_fit import _identify

__all__ = ["sweep_curve"]

#: phase of each response quantity at a resonance, for a positive modal constant
_CLASS = {
    -0.5: "receptance-like (displacement)",
    0.0: "velocity-like (mobility)",
    0.5: "accelerance-like",
    1.0: "inverted velocity-like",
}
_EXPECTED = {"displacement": -0.5, "velocity": 0.0, "acceleration": 0.5}
_PHASE_TOL = math.pi / 6  # largest distance of the resonance phase from its class


def _inputs(f, F, response, phase, level):
    arrs = {}
    for name, v in (("f", f), ("F", F), ("response", response), ("phase", phase)):
        arrs[name] = check_magnitude(name, finite_array(name, v, min_size=8))
    same_length(**arrs)
    for name, unit in (("f", "Hz"), ("F", "N"), ("response", "SI units of quantity")):
        if np.any(arrs[name] <= 0):
            raise ValueError(f"{name} must be > 0 [{unit}] (amplitudes, not signed values)")
    if np.max(np.abs(arrs["phase"])) > 2 * math.pi + 1e-9:
        raise ValueError(
            f"phase must be in radians (|phase| <= 2 pi), got values up to "
            f"{np.max(np.abs(arrs['phase'])):.4g}: it looks like degrees"
        )
    lab = _split(arrs["f"]) if level is None else np.asarray(level)
    if lab.shape != arrs["f"].shape:
        raise ValueError(
            f"level must hold one label per point ({arrs['f'].size}), got shape {lab.shape}"
        )
    sweeps = []
    for v in dict.fromkeys(lab.tolist()):
        idx = np.flatnonzero(lab == v)
        idx = idx[np.argsort(arrs["f"][idx], kind="stable")]
        fv = arrs["f"][idx]
        n_distinct = np.unique(fv).size
        if idx.size < 5 or n_distinct != idx.size:
            rep = np.unique(fv[1:][np.diff(fv) == 0])
            again = (
                f"; f repeats {rep.size} frequenc{'y' if rep.size == 1 else 'ies'} "
                f"({', '.join(f'{x:g}' for x in rep[:4])} Hz): give level= to tell "
                "sweeps apart, or average the repeats"
                if rep.size
                else ""
            )
            raise ValueError(
                f"level {v!r}: a sweep must have >= 5 points at distinct "
                f"frequencies, got {idx.size} points at {n_distinct} distinct "
                f"frequencies{again}"
            )
        sweeps.append(idx)
    return arrs, sweeps


def _split(f):
    """Sweep labels when none are given: a new sweep starts where ``f`` turns round or
    repeats a frequency.
    """
    lab = np.zeros(f.size, int)
    direction = 0.0
    for i in range(1, f.size):
        step = np.sign(f[i] - f[i - 1])
        if step == 0 or (direction != 0 and step != direction):
            lab[i:] += 1
            direction = 0.0
        else:
            direction = step
    return lab


def _sweep_phase(W, H, ph):
    """Resonance phase / pi, direction and span of one sweep (phase unwrapped along W)."""
    u = np.unwrap(ph)
    mag = np.abs(H)
    k = int(np.argmax(mag))
    if k == 0 or k == mag.size - 1:
        return None
    near = mag >= 0.5 * mag[k]
    slope = np.polyfit(W[near], u[near], 1)[0] if near.sum() >= 2 else u[k + 1] - u[k - 1]
    res = (u[k] + math.pi) % (2 * math.pi) - math.pi
    return res / math.pi, float(np.sign(slope)), float(np.ptp(u))


def _convention(W, X, F, ph, sweeps, quantity):
    """Rotate the phases to a displacement receptance with a positive modal constant.

    The resonance phase of the sweeps (at the peak of ``|X / F|``) must lie within pi/6 of
    -pi/2, 0, pi/2 or pi and the phase must fall with frequency (``exp(i W t)``); a phase
    that rises is conjugated (``exp(-i W t)``). Returns the rotated phase, a note and the
    phase class (:func:`_quantity_failure` judges it).
    """
    stats = [s for s in (_sweep_phase(W[i], X[i] / F[i], ph[i]) for i in sweeps) if s]
    if not stats:
        raise ValueError(
            "no sweep has its response peak inside its frequencies: the phase "
            "convention cannot be told (sweep through the resonance)"
        )
    span = max(s[2] for s in stats)
    if span < math.pi / 4:
        raise ValueError(
            f"phase varies by only {span:.3g} rad along the sweeps: it does not "
            "pass through a resonance, so its convention cannot be told"
        )
    signs = {s[1] for s in stats}
    if len(signs) != 1 or 0.0 in signs:
        raise ValueError(
            "phase falls with frequency in some sweeps and rises in others: "
            "the phase convention cannot be told"
        )
    sign = signs.pop()
    res = np.array([s[0] for s in stats]) * (-sign)
    mean = math.atan2(np.mean(np.sin(math.pi * res)), np.mean(np.cos(math.pi * res))) / math.pi
    cls = 0.5 * round(2 * mean)
    cls = 1.0 if cls == -1.0 else cls
    dist = abs((mean - cls + 1) % 2 - 1) * math.pi
    if dist > _PHASE_TOL:
        raise ValueError(
            f"phase at the response peak is {mean * math.pi:.3g} rad, "
            f"{dist:.2g} rad from the nearest of -pi/2, 0, pi/2, pi: the phase "
            "convention cannot be told (is it the phase of the response relative "
            "to the force, in rad?)"
        )
    phd = -sign * ph - (cls + 0.5) * math.pi
    note = f"phase {_CLASS[cls]}" + (", rising with frequency (conjugated)" if sign > 0 else "")
    if cls != _EXPECTED[quantity]:
        note += (
            f" although the response is {quantity}: the sign of the response or of the "
            "force is inverted, or the phase is not that of the given quantity; read as "
            f"the displacement phase after adding {-(cls + 0.5) % 2:g} pi"
        )
    return phd, note, cls


def _quantity_failure(cls, quantity, W, X):
    """Why the response cannot be the declared ``quantity`` ("" when it can be): its phase
    class ``cls`` at resonance is a quarter period off (no sign convention does that), or
    half a period off (a sign convention, as in many real records, or displacement and
    acceleration swapped) with displacement amplitudes ``X`` [m] whose velocity ``W X``
    exceeds :data:`~iwan_element.base.plausibility.V_MAX` (issue 34 case 7: acceleration
    declared displacement moved at thousands of m/s).
    """
    shift = (cls - _EXPECTED[quantity]) % 2
    if shift == 0:
        return ""
    fits = [q for q, c in _EXPECTED.items() if c == cls]
    v = float(np.max(W * X))
    if shift == 1 and v <= V_MAX:
        return ""
    why = (
        f"read as {quantity} it moves at up to {v:.3g} m/s, beyond any vibration test "
        f"({V_MAX:g} m/s)"
        if shift == 1
        else "a quarter period off, which no sign convention gives"
    )
    return (
        f"the phase at resonance is {_CLASS[cls]} although quantity={quantity!r} ({why}): "
        + (f"the response is likely {fits[0]} (give quantity={fits[0]!r}); " if fits else "")
        + "the curve is not usable until the quantity is checked"
    )


def sweep_curve(
    f,
    F,
    response,
    phase,
    *,
    level=None,
    quantity: str = "acceleration",
    peak_fraction: float = 0.2,
    degree: int = 3,
    residual: bool = True,
    bins: int | None = None,
) -> AmplitudeCurve:
    """Frequency and damping ratio against amplitude from every point of stepped-sine sweeps.

    Single-nonlinear-mode reading of force- or response-controlled sweeps measured at the
    drive point (see the module docstring and ``docs/sweeps.md``).

    Parameters
    ----------
    f : array_like, shape (n,)
        Drive frequency of each point [Hz] (not rad/s: the method cannot tell them apart).
    F : array_like, shape (n,)
        Fundamental force amplitude [N], > 0; it may change from point to point.
    response : array_like, shape (n,)
        Fundamental response amplitude at the drive point, in SI units of ``quantity``
        ([m], [m/s] or [m/s^2]), > 0.
    phase : array_like, shape (n,)
        Phase of the response fundamental relative to the force [rad]. Its convention is
        read from the data: the phase at the response peak must lie within pi/6 of -pi/2
        (receptance-like), 0 (velocity-like), pi/2 (accelerance-like) or pi, and fall with
        frequency (a phase that rises is conjugated); otherwise ``ValueError``.
    level : array_like, optional, keyword-only
        Sweep label of each point; by default a new sweep starts where ``f`` turns round.
    quantity : {"acceleration", "velocity", "displacement"}, keyword-only
        What ``response`` is; ``X = response / W**k`` with ``k`` = 2, 1, 0.
    peak_fraction : float, keyword-only
        Points whose ``|X / F|`` is below this fraction of their sweep's peak are not
        inverted (they still inform the fit of ``c`` and ``B``); range [0.05, 0.9],
        default 0.2. Below the fraction ``p`` a point lies about ``1/p`` half-power
        bandwidths from its resonance and the relative errors of ``c`` and ``B`` reach its
        damping ratio magnified up to ``1/p`` times (its frequency ``2 zeta / p`` times).
    degree : int, keyword-only
        Polynomial degree in ``ln X`` of the smooth curves fitted with ``c`` and ``B``
        (1 to 5, default 3; reduced to the number of sweeps minus one when every sweep
        holds its response within 10 %, as response control does).
    residual : bool, keyword-only
        Fit the real residual ``B`` of the other modes (default True).
    bins : int, optional, keyword-only
        Number of equal bins in ``ln X``, 1 to 50 (default: kept points / 8, between 3 and
        12); clusters of amplitude separated by more than 0.1 in ``ln X`` are never merged.

    Returns
    -------
    AmplitudeCurve
        Bin means: ``amplitude`` the geometric mean displacement amplitude of the mode in
        the bin, ``|H - B| F`` [m],
        ``frequency`` ``w_r / 2 pi`` [Hz], ``damping_ratio`` (viscous, ``2 zeta w_r W``) with
        standard errors; ``method="stepped-sine-sweep"``; ``notes`` hold ``c``, ``B`` and the
        phase convention.

    Raises
    ------
    ValueError
        Malformed input, phase in degrees, a phase convention that cannot be told, or a
        single-mode inversion that gives damping ratios above 0.1 (not a lightly damped
        mode).
    """
    if quantity not in QUANTITY_POWER:
        raise ValueError(f"quantity must be one of {sorted(QUANTITY_POWER)}, got {quantity!r}")
    frac = check_scalar("peak_fraction", peak_fraction, low=0.05, high=0.9)
    deg = int(check_scalar("degree", degree, low=1, high=5))
    if deg != degree:
        raise ValueError(f"degree must be an integer in [1, 5], got {degree!r}")
    if bins is not None and (
        isinstance(bins, bool) or not isinstance(bins, (int, np.integer)) or not 1 <= bins <= 50
    ):
        raise ValueError(f"bins must be an integer in [1, 50] or None, got {bins!r}")
    arrs, sweeps = _inputs(f, F, response, phase, level)
    W = 2.0 * math.pi * arrs["f"]
    X = arrs["response"] / W ** QUANTITY_POWER[quantity]
    phd, conv_note, cls = _convention(W, X, arrs["F"], arrs["phase"], sweeps, quantity)
    failure = _quantity_failure(cls, quantity, W, X) or level_failure(
        X, arrs["f"], quantity=quantity, name="response"
    )
    H = X * np.exp(1j * phd) / arrs["F"]
    if max(float(np.ptp(np.log(X[i]))) for i in sweeps) < 0.1:
        deg = min(deg, len(sweeps) - 1)  # response held within 10 %: one amplitude a sweep
    r = _identify(W, H, arrs["F"], sweeps, deg, residual, frac, bins)
    amp, wr, z, sw, sz = r["curve"]
    c, B, keep, n_bins, rms = r["c"], r["B"], r["keep"], r["n_bins"], r["rms"]
    if np.any(z >= 0.1):
        raise ValueError(
            f"the single-mode inversion gives damping ratios up to {z.max():.3g}: "
            "not a lightly damped single mode (check the phase and that the "
            "response is co-located with the force)"
        )
    deg = r["deg"]
    notes = (
        f"{len(sweeps)} sweeps, {W.size} points ({keep.sum()} inverted, |X/F| >= {frac:g} "
        f"x sweep peak, X {r['span'][0]:.3g}-{r['span'][1]:.3g} m); {conv_note}; "
        f"modal constant c = {c:.5g} 1/kg, residual B = "
        f"{B:.4g} m/N; smooth curves of degree {deg} in ln X; fit rms relative error "
        f"{rms:.2g}; bins: {len(amp)} of {n_bins} in ln X"
    )
    return AmplitudeCurve(
        amp,
        wr / (2 * math.pi),
        z,
        frequency_std=sw / (2 * math.pi),
        damping_ratio_std=sz,
        method="stepped-sine-sweep",
        notes=notes,
        warnings=r["warnings"],
        failures=(failure,) if failure else (),
    )
