"""Find what the four-parameter Iwan model is missing: diagnose, name, augment, refit.

:func:`diagnose` works on a displacement-driven test record (time, displacement, force):

1. it fits the plain Iwan model (:func:`~iwan_element.fit_loops`);
2. it estimates the force noise *from the data*: the base-fit residuals of two consecutive
   closed cycles at the same amplitude share the model error but not the noise, so their
   difference (over non-overlapping pairs, divided by sqrt 2) is noise only; a slow drift of
   the force from one cycle to the next (slip degradation) is projected out of each
   difference along the model force. The same differences give the noise's correlation time
   ``tau`` (integrated autocorrelation), so coloured noise counts ``n / tau`` independent
   samples;
3. it tests whether the base misfit exceeds that noise (F-test of ``SSR / (n sigma^2)`` with
   ``n/tau`` and ``m/tau`` degrees of freedom, level ``alpha``); if not, it names nothing;
4. otherwise it locates the misfit (which part of the cycle, which amplitudes, which cycles,
   which direction) and refits the Iwan parameters *together with* each candidate effect of
   :data:`~iwan_element.EFFECTS` (bounded Levenberg-Marquardt on transformed parameters,
   ``Fs`` eliminated in closed form: every model is homogeneous in the force scale);
5. an effect is named when its improvement is significant against the noise (F-test,
   Bonferroni over the candidates) and it removes a material part of the excess misfit; the
   best by an information criterion (``SSR/(tau sigma^2) + 2 q``) wins, and every other
   candidate within ``ambiguity`` of it is reported in ``ambiguous_with``;
6. if the misfit left is still more than noise it continues with a second effect wrapping the
   first (``max_effects``).

:func:`diagnose_vibration` does the same for amplitude-dependent frequency and damping curves
(measured against a model's prediction): a damping floor at low amplitude (viscous damping
missing) and a frequency floor / stiffening at high amplitude (pinning stiffness missing).
"""
from __future__ import annotations

import logging
import math
import inspect
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.special import fdtrc

from .._effect_eval import Evaluator, build_element, scale_effect, unit_params
from ..core._validation import (_check_int, _check_time, check_magnitude, check_scalar, finite_array,
                                same_length)
from ..effects import EFFECTS
from ..identify.fit import (_BETA_MAX, _CHI_BOUNDS, _PHI_RANGE, PARAM_NAMES, FitResult, _json, _lsq_box,
                  _quiet, fit_loops)
from ..core.joint import IwanJoint
from ..core.parameters import IwanParameters
from ..core.protocol import check_element
from ..identify.testdata import TestData, find_reversals, split_cycles

__all__ = ["CANDIDATES", "Diagnosis", "VibrationDiagnosis", "diagnose", "diagnose_vibration",
           "simulate_element_test"]

log = logging.getLogger(__name__)

#: Candidate effects tried by :func:`diagnose`, in the order they are reported.
CANDIDATES = ("viscous_damping", "pinning_stiffness", "backlash", "slip_degradation",
              "asymmetric_slip")
_UNITS = {"c": "N s/m", "k_p": "N/m", "delta": "m", "gap": "m", "rate": "1/J", "asymmetry": "1"}
_EXPLAIN_FRACTION = 0.25   # a named effect removes at least this share of the excess misfit


# =============================================================================== data generator
def simulate_element_test(element, amplitudes, *, cycles: int = 3, frequency: float = 1.0,
                          samples_per_cycle: int = 96, waveform: str = "sine",
                          force_noise: float = 0.0, noise_correlation: float = 0.0,
                          seed=0) -> TestData:
    """Displacement-driven test of any joint element (an effect stack included), with noise.

    Each amplitude is applied for ``cycles`` periods from ``u = 0`` (as
    :func:`~iwan_element.simulate_test`), then ``u`` returns to 0.

    Parameters
    ----------
    element : joint element
        Anything with ``force_history(u, v)`` or ``force_history(u)`` (``IwanJoint``).
    amplitudes : array_like, shape (m,)
        Displacement amplitudes [m], ``> 0``.
    cycles : int, keyword-only
        Periods per amplitude, ``>= 1``.
    frequency : float, keyword-only
        Loading frequency [Hz], ``> 0``.
    samples_per_cycle : int, keyword-only
        Samples per period, ``>= 16``.
    waveform : {"sine", "triangle"}, keyword-only
        ``"triangle"`` loads at one constant rate ``4 max(amplitudes) frequency`` (``|v|``
    constant; the periods at smaller amplitudes are shorter).
    The element gets the velocity ``np.gradient(u, t)``, as :func:`diagnose` computes it.
    force_noise : float, keyword-only
        Standard deviation of the force noise [N], ``>= 0``.
    noise_correlation : float, keyword-only
        Lag-one correlation of the noise, ``[0, 1)``: 0 is white noise, otherwise AR(1)
        (coloured) noise with the same standard deviation.
    seed : int or numpy.random.Generator, keyword-only

    Returns
    -------
    TestData
    """
    check_element(element, name="element")
    if not callable(getattr(element, "force_history", None)):
        raise ValueError(f"element must have a force_history(u[, v]) method; "
                         f"{type(element).__name__} has none")
    amps = check_magnitude("amplitudes", finite_array("amplitudes", amplitudes, ndim=1), unit="m")
    if np.any(amps <= 0.0):
        raise ValueError("amplitudes must all be > 0 [m]")
    cycles = _check_int("cycles", cycles, 1)
    f = check_scalar("frequency", frequency, low=0.0, low_open=True)
    n_per = _check_int("samples_per_cycle", samples_per_cycle, 16)
    if waveform not in ("sine", "triangle"):
        raise ValueError(f"waveform must be 'sine' or 'triangle', got {waveform!r}")
    sf = check_scalar("force_noise", force_noise, low=0.0, high=1e100)
    phi = check_scalar("noise_correlation", noise_correlation, low=0.0, high=1.0, high_open=True)
    rng = np.random.default_rng(seed)
    if waveform == "sine":
        ph = np.arange(n_per * cycles) / n_per
        blocks = [a * np.sin(2 * np.pi * ph) for a in amps]
    else:                        # constant rate 4 max(a) f: shorter periods at small amplitudes
        blocks = []
        for a in amps:
            n_a = max(8, int(round(n_per * a / amps.max())))
            frac = (np.arange(n_a * cycles) / n_a + 0.25) % 1.0
            blocks.append(a * np.where(frac < 0.5, 4 * frac - 1, 3 - 4 * frac))
    u = np.concatenate(blocks + [np.zeros(1)])
    t = np.arange(u.size) / (n_per * f)
    v = np.gradient(u, t)
    if "v" in inspect.signature(element.force_history).parameters:
        F = element.force_history(u, v)
    else:                        # IwanJoint/DiscreteIwan: rate independent, no velocity
        F = element.force_history(u)
    if sf > 0.0:
        e = rng.normal(0.0, 1.0, u.size)
        if phi > 0.0:
            from scipy.signal import lfilter
            e = lfilter([math.sqrt(1 - phi * phi)], [1.0, -phi], e)
        F = F + sf * e
    return TestData.from_arrays(t, u, F, source=f"simulate_element_test({element!r})")


# =============================================================================== noise
def _aligned_lag(u, a, b, n, max_lag=2):
    """Lag in ``[-max_lag, max_lag]`` that best aligns ``u[b:b+n]`` with ``u[a:a+n]``
    (displacement only, so it does not bias the force-noise estimate)."""
    best, best_lag = math.inf, 0
    for lag in range(-max_lag, max_lag + 1):
        lo = b + lag
        if lo < 0 or lo + n > u.size:
            continue
        s = float(np.sum((u[a:a + n] - u[lo:lo + n]) ** 2))
        if s < best:
            best, best_lag = s, lag
    return best_lag


def _repeat_noise(u, r, Fm, cycles):
    """Noise from repeated cycles: ``(sigma [N], samples, tau, pairs)`` or ``None`` when no
    amplitude is repeated in two consecutive closed cycles.

    The base-fit residuals of two consecutive closed cycles at the same amplitude share the
    model error; their difference is noise (times sqrt 2). A slow drift of the force amplitude
    between the two (slip degradation) is projected out of each difference along the model
    force (one degree of freedom per pair).
    """
    pairs, prev = [], None
    for c in cycles:
        if prev is not None and prev.closed and c.closed and (
                abs(c.u0 - prev.u0) <= 0.02 * max(c.u0, prev.u0)
                and abs((c.stop - c.start) - (prev.stop - prev.start))
                <= max(2, 0.02 * (prev.stop - prev.start))):
            pairs.append((prev, c))
            prev = None                  # non-overlapping pairs: independent differences
        else:
            prev = c
    segs, dof = [], 0
    for a_c, b_c in pairs:
        n = min(a_c.stop - a_c.start, b_c.stop - b_c.start) - 4
        if n < 8:
            continue
        a = a_c.start + 2
        b = b_c.start + 2 + _aligned_lag(u, a, b_c.start + 2, n)
        d = (r[a:a + n] - r[b:b + n]) / math.sqrt(2.0)
        g = Fm[a:a + n]
        gg = float(g @ g)
        if gg > 0:
            d = d - g * (float(g @ d) / gg)
        segs.append(d)
        dof += n - 1
    if not segs:
        return None
    alld = np.concatenate(segs)
    s2 = float(alld @ alld) / dof
    # integrated autocorrelation time (initial positive sequence, within segments)
    tau = 1.0
    for k in range(1, 60):
        num = sum(float(np.dot(d[:-k], d[k:])) for d in segs if d.size > k)
        cnt = sum(d.size - k for d in segs if d.size > k)
        if cnt < 10:
            break
        rho = num / cnt / s2
        if rho <= 0.02:
            break
        tau += 2.0 * rho
    return math.sqrt(s2), int(dof), tau, len(segs)


# =============================================================================== effect fits
def _effect_spec(name, scales):
    """Bounds, starts and decoder of one effect's transformed parameters."""
    um, vs, Dref = scales["u_max"], scales["v_rms"], scales["D_ref"]
    if name == "viscous_damping":
        return ([0.0], [2.0], [[0.0], [0.03]], lambda z: {"c": z[0] / vs}, lambda d: [d["c"] * vs])
    if name == "pinning_stiffness":
        return ([0.0, 0.0], [20.0, 0.95], [[0.0, 0.0], [0.2, 0.0], [0.3, 0.5]],
                lambda z: {"k_p": z[0] / um, "delta": z[1] * um},
                lambda d: [d["k_p"] * um, d["delta"] / um])
    if name == "backlash":
        return ([0.0], [0.5], [[0.0], [0.01]], lambda z: {"gap": z[0] * um},
                lambda d: [d["gap"] / um])
    if name == "slip_degradation":
        return ([0.0], [5.0], [[0.0], [0.2]], lambda z: {"rate": z[0] / Dref},
                lambda d: [d["rate"] * Dref])
    if name == "asymmetric_slip":
        return ([-0.9], [0.9], [[0.0], [0.1], [-0.1]], lambda z: {"asymmetry": z[0]},
                lambda d: [d["asymmetry"]])
    raise ValueError(f"unknown effect {name!r}")


class _Model:
    """Transformed parameter vector ``z = (ln(phi_max/x_max), chi, ln(1+beta), effects...)``."""

    def __init__(self, ev: Evaluator, y, names, scales):
        self.ev, self.y, self.names = ev, y, tuple(names)
        self.specs = [_effect_spec(nm, scales) for nm in self.names]
        lo = [math.log(_PHI_RANGE[0]), _CHI_BOUNDS[0], 0.0]
        hi = [math.log(_PHI_RANGE[1]), _CHI_BOUNDS[1], math.log1p(_BETA_MAX)]
        for s in self.specs:
            lo += s[0]
            hi += s[1]
        self.lower, self.upper = np.array(lo), np.array(hi)
        self.yy = float(y @ y)

    def decode(self, z):
        xm = self.ev.x_max
        shape = (xm * math.exp(z[0]), float(z[1]), math.expm1(z[2]))
        vals, k = [], 3
        for s in self.specs:
            q = len(s[0])
            vals.append(s[3](z[k:k + q]))
            k += q
        return shape, vals

    def unit(self, z):
        shape, vals = self.decode(z)
        return self.ev.unit_force(shape, self.names, vals)

    def residual(self, z):
        try:
            g = self.unit(z)
        except (ValueError, ZeroDivisionError, OverflowError, FloatingPointError):
            return np.full(self.y.size, 1e6 * math.sqrt(self.yy / self.y.size + 1.0))
        den = float(g @ g)
        Fs = float(g @ self.y) / den if den > 0 else 1.0
        Fs = max(Fs, 1e-300)
        return self.y - Fs * g

    def Fs(self, z):
        g = self.unit(z)
        return max(float(g @ self.y) / float(g @ g), 1e-300)


def _fit(model: _Model, starts, *, max_nfev):
    best = None
    nfev = 0
    for z0 in starts:
        z0 = np.clip(np.asarray(z0, float), model.lower, model.upper)
        res = _lsq_box(model.residual, z0, model.lower, model.upper, max_nfev=max_nfev)
        nfev += res.nfev
        if best is None or res.cost < best.cost:
            best = res
    return best, nfev


def _physical(model: _Model, z):
    """(IwanParameters, [effect parameter dicts in SI]) for a transformed vector."""
    shape, vals = model.decode(z)
    Fs = model.Fs(z)
    p1 = unit_params(*shape)
    p = IwanParameters(Fs, Fs * p1.KT, p1.chi, p1.beta)
    return p, [scale_effect(nm, v, Fs, to_unit=False) for nm, v in zip(model.names, vals)]


def _flat(p: IwanParameters, effs, names):
    out = [p.Fs, p.KT, p.chi, p.beta]
    labels = list(PARAM_NAMES)
    for nm, d in zip(names, effs):
        for k in EFFECTS[nm].parameter_names:
            out.append(d[k])
            labels.append(f"{nm}.{k}")
    return np.array(out), labels


def _uncertainty(model: _Model, z, r):
    """Standard errors and correlation of (Fs, KT, chi, beta, effect params) by the delta
    method from the Jacobian in ``theta = (ln Fs, z)``."""
    Fs = model.Fs(z)
    theta = np.concatenate([[math.log(Fs)], z])
    h = 1e-5
    lo = np.concatenate([[-np.inf], model.lower])
    hi = np.concatenate([[np.inf], model.upper])

    def resid(th):
        return model.y - math.exp(th[0]) * model.unit(th[1:])

    def phys(th):
        p, effs = _physical(model, th[1:])
        scale = math.exp(th[0]) / p.Fs
        p = IwanParameters(p.Fs * scale, p.KT * scale, p.chi, p.beta)
        effs = [scale_effect(nm, d, scale, to_unit=False) for nm, d in zip(model.names, effs)]
        return _flat(p, effs, model.names)[0]

    cols, pcols = [], []
    for j in range(theta.size):
        tp, tm = theta.copy(), theta.copy()
        tp[j] = min(theta[j] + h, hi[j])
        tm[j] = max(theta[j] - h, lo[j])
        dh = tp[j] - tm[j]
        cols.append((resid(tp) - resid(tm)) / dh)
        pcols.append((phys(tp) - phys(tm)) / dh)
    J = np.column_stack(cols)
    Jp = np.column_stack(pcols)
    s2 = float(r @ r) / max(r.size - theta.size, 1)
    cov_t = s2 * np.linalg.pinv(J.T @ J, rcond=1e-12, hermitian=True)
    cov = Jp @ cov_t @ Jp.T
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se, se)
    return se, corr, 2 * theta.size


# =============================================================================== result
@dataclass(frozen=True, eq=False)
class Diagnosis:
    """What the four-parameter Iwan fit misses in a test record, and the augmented model.

    Attributes
    ----------
    effect : str
        The first effect named (a name of :data:`~iwan_element.EFFECTS`) or ``"none"``.
    effects : tuple of str
        All effects named, in the order they were added (innermost first).
    ambiguous_with : tuple of str
        Effects that explain the first step's misfit nearly as well as ``effect``.
    where : str
        Where the base misfit lies (part of the cycle, amplitudes, cycles, direction).
    error_before, error_after : float
        NRMSE of the force [-] (RMS residual over ``max F - min F``) of the base and the
        augmented model on the whole record.
    noise_level : float
        Estimated noise standard deviation on the same scale [-].
    noise_sigma : float
        Estimated noise standard deviation [N].
    misfit : bool
        True if the base misfit is significantly more than noise.
    base_fit, fit : FitResult
        The plain Iwan fit and the augmented fit (``fit.details["effects"]`` holds the effect
        parameters with standard errors; ``fit is base_fit`` when nothing is named).
    model : joint element
        The augmented element (an ``IwanJoint`` when nothing is named), ready for
        :func:`iwan_element.exudyn.add_iwan_connector`.
    steps : tuple of dict
        Per step: every candidate's NRMSE, information-criterion difference, p-value and why
        it was or was not named.
    untestable : dict
        Effects this record cannot reveal, with the reason.
    warnings : tuple of str
    force_before, force_after : ndarray, shape (n,)
        Forces [N] of the base and the augmented model on the measured displacement.
    t, u, F : ndarray, shape (n,)
        The data (read-only copies; ``t`` is the sample index if no time was given).
    details : dict
        Test statistics (JSON-safe).
    """

    effect: str
    effects: tuple
    ambiguous_with: tuple
    where: str
    error_before: float
    error_after: float
    noise_level: float
    noise_sigma: float
    misfit: bool
    base_fit: FitResult
    fit: FitResult
    model: object
    steps: tuple
    untestable: dict
    warnings: tuple
    force_before: np.ndarray
    force_after: np.ndarray
    t: np.ndarray
    u: np.ndarray
    F: np.ndarray
    details: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """JSON-safe dict (NaN/inf become None); the fits as :meth:`FitResult.to_dict`."""
        return _json({
            "effect": self.effect, "effects": list(self.effects),
            "ambiguous_with": list(self.ambiguous_with), "where": self.where,
            "error_before": self.error_before, "error_after": self.error_after,
            "noise_level": self.noise_level, "noise_sigma": self.noise_sigma,
            "misfit": self.misfit, "steps": list(self.steps), "untestable": dict(self.untestable),
            "warnings": list(self.warnings), "base_fit": self.base_fit.to_dict(),
            "fit": self.fit.to_dict(), "model": _describe(self.model), "details": self.details,
        })

    def report(self) -> str:
        """Human-readable account: noise, misfit, where, candidates, verdict, before/after."""
        d = self.details
        p = self.base_fit.params
        lines = ["Iwan model diagnosis",
                 f"  {d['samples']} samples, {d['cycles']} cycles; noise estimated "
                 + (f"from {d['noise_groups']} pairs of repeated cycles ({d['noise_samples']} "
                    f"degrees of freedom), correlation time {d['tau']:.2g} samples"
                    if d["noise_from"] == "repeats" else "as given"),
                 f"  noise: sigma = {self.noise_sigma:.4g} N (NRMSE {100 * self.noise_level:.3g} %)",
                 f"  base Iwan fit: Fs={p.Fs:.5g} N, KT={p.KT:.5g} N/m, chi={p.chi:.4f}, "
                 f"beta={p.beta:.4f}; NRMSE {100 * self.error_before:.3g} % "
                 f"= {self.error_before / self.noise_level:.3g} x noise "
                 f"(misfit p-value {d['misfit_p']:.2g}, level {d['alpha']:g})",
                 f"  where: {self.where}"]
        for k, st in enumerate(self.steps):
            lines.append(f"  step {k + 1}: candidates on {' + '.join(st['on']) or 'Iwan'}")
            lines.append("    effect               NRMSE[%]  x noise     dAIC    p-value  verdict")
            for c in st["candidates"]:
                lines.append(f"    {c['name']:<20} {100 * c['nrmse']:8.3g} {c['ratio']:8.3g} "
                             f"{c['dAIC']:8.1f} {c['p']:10.2g}  {c['verdict']}")
        for name, why in self.untestable.items():
            lines.append(f"  cannot test {name}: {why}")
        if self.effects:
            lines.append(f"  named: {', '.join(self.effects)}"
                         + (f" (nearly as good: {', '.join(self.ambiguous_with)})"
                            if self.ambiguous_with else ""))
            for e in self.fit.details.get("effects", []):
                ps = ", ".join(f"{k} = {v:.4g} {_UNITS[k]} (+- {e['stderr'][k]:.2g})"
                               for k, v in e["parameters"].items())
                lines.append(f"    {e['name']}: {ps}")
            q = self.fit.params
            lines.append(f"    Iwan part: Fs={q.Fs:.5g} N, KT={q.KT:.5g} N/m, chi={q.chi:.4f}, "
                         f"beta={q.beta:.4f}")
        else:
            lines.append("  named: none")
        lines.append(f"  error before {100 * self.error_before:.3g} % -> after "
                     f"{100 * self.error_after:.3g} % (noise {100 * self.noise_level:.3g} %)")
        if self.warnings:
            lines += ["  warnings:"] + [f"  - {w}" for w in self.warnings]
        return "\n".join(lines)

    def plot(self, ax=None):
        """Data, base fit and augmented fit (force-displacement, mm and kN) and the residual
        before and after against time.

        Parameters
        ----------
        ax : None, a pair of Axes, or one Axes
            ``None``: a new figure with two panels; one Axes: the loops there and the
            residuals in an inset.

        Returns
        -------
        list of matplotlib artists
        """
        if ax is None:
            import matplotlib.pyplot as plt
            _, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.5))
        elif isinstance(ax, (list, tuple, np.ndarray)):
            if len(ax) != 2:
                raise ValueError(f"ax must be None, one Axes or two Axes, got {len(ax)}")
            a1, a2 = ax
        else:
            a1 = ax
            a2 = ax.inset_axes([0.6, 0.07, 0.38, 0.3])
        step = max(1, self.u.size // 20000)
        u, F = self.u[::step] * 1e3, self.F[::step] * 1e-3
        arts = a1.plot(u, F, ".", ms=1.5, color="0.6", label="measured")
        arts += a1.plot(u, self.force_before[::step] * 1e-3, "-", lw=0.9, color="C0",
                        label=f"Iwan fit ({100 * self.error_before:.2g} %)")
        lab = " + ".join(self.effects) if self.effects else "no effect named"
        arts += a1.plot(u, self.force_after[::step] * 1e-3, "--", lw=0.9, color="C3",
                        label=f"augmented: {lab} ({100 * self.error_after:.2g} %)")
        a1.set_xlabel("displacement [mm]")
        a1.set_ylabel("force [kN]")
        a1.grid(True, alpha=0.3)
        a1.legend(fontsize=7, loc="upper left")
        tt = self.t[::step]
        arts += a2.plot(tt, (self.F - self.force_before)[::step], "-", lw=0.6, color="C0",
                        label="residual before")
        arts += a2.plot(tt, (self.F - self.force_after)[::step], "-", lw=0.6, color="C3",
                        label="residual after")
        arts.append(a2.axhspan(-2 * self.noise_sigma, 2 * self.noise_sigma, color="0.85",
                               zorder=0, label="+-2 noise"))
        a2.set_xlabel("time [s]", fontsize=7)
        a2.set_ylabel("residual [N]", fontsize=7)
        a2.tick_params(labelsize=6)
        a2.legend(fontsize=6, loc="upper right")
        return arts


def _describe(model) -> str:
    return model.describe() if hasattr(model, "describe") else repr(model.params)


# =============================================================================== location
def _locate(t, u, F, Fm, r, cycles, sigma, tau) -> tuple[str, dict]:
    """A sentence saying where the residual exceeds the noise, and the numbers behind it."""
    s2 = sigma * sigma
    ratio = float(np.mean(r ** 2) / s2)
    region = np.full(u.size, -1)
    cyc_ratio, amps = [], []
    for c in cycles:
        sl = slice(c.start, c.stop)
        uu = u[sl]
        imin = int(np.argmin(uu))
        # displacement travelled since the last turning point, relative to the stroke
        d = np.where(np.arange(uu.size) <= imin, uu[0] - uu, uu - uu[imin]) / max(2 * c.u0, 1e-300)
        region[sl] = np.where(d < 0.15, 0, np.where(d > 0.85, 2, 1))
        rr = r[sl]
        cyc_ratio.append(float(np.mean(rr ** 2) / s2))
        amps.append(c.u0)
    names = ("just after the reversals", "mid-stroke", "at the ends of the stroke")
    reg = {}
    for k, nm in enumerate(names):
        m = region == k
        if m.sum() >= 5:
            reg[nm] = float(np.mean(r[m] ** 2) / s2)
    parts = [f"the residual is {math.sqrt(ratio):.2g} x the noise (RMS {math.sqrt(ratio) * sigma:.3g} N "
             f"vs {sigma:.3g} N)"]
    if reg:
        worst = max(reg, key=reg.get)
        parts.append(f"largest {worst} ({math.sqrt(reg[worst]):.2g} x noise there"
                     + ", ".join([""] + [f"{math.sqrt(v):.2g} x {k}" for k, v in reg.items()
                                         if k != worst]) + ")")
    amps = np.array(amps)
    cr = np.array(cyc_ratio)
    if amps.size:
        levels = np.unique(np.round(amps / amps.max(), 2))
        grp = {lv: cr[np.round(amps / amps.max(), 2) == lv].mean() for lv in levels}
        thresh = 1.0 + 3.0 * math.sqrt(2.0 * tau / max(np.mean([c.stop - c.start for c in cycles]), 1))
        bad = [lv for lv, v in grp.items() if v > thresh]
        if bad and len(bad) == len(grp):
            top = max(grp, key=grp.get)
            parts.append(f"at every amplitude, most at u0 = {top * amps.max() * 1e3:.3g} mm")
        elif bad:
            parts.append("at amplitudes u0 = " + ", ".join(f"{b * amps.max() * 1e3:.3g}" for b in bad)
                         + " mm" + (" (the largest)" if min(bad) > np.median(levels) else
                                    " (the smallest)" if max(bad) < np.median(levels) else ""))
        else:
            parts.append("spread over all amplitudes")
    # patterns: the share of the excess residual power each one carries
    excess = max(float(r @ r) - u.size * s2, 1e-300)
    pats = {}
    af = np.abs(Fm)
    pats["the measured force is {} than the model in one direction and {} in the other "
         "(a forward/back asymmetry)"] = af
    if t is not None:
        pats["the loops are {} than the model (a force in phase with the velocity)"] = np.gradient(u)
    tc = np.arange(u.size) - 0.5 * u.size
    pats["the force changes from cycle to cycle ({} cycles carry more force than the model)"] = Fm * tc
    shares = {}
    for text, g in pats.items():
        gg = float(g @ g)
        if gg <= 0:
            continue
        coef = float(g @ r) / gg
        share = coef * coef * gg / excess
        shares[text] = (share, coef)
        if share >= 0.25:
            if "asymmetry" in text:
                hi = "higher" if coef > 0 else "lower"
                parts.append(text.format(hi + " (F > 0)", "higher" if coef < 0 else "lower"))
            elif "loops" in text:
                parts.append(text.format("wider" if coef > 0 else "narrower"))
            else:
                parts.append(text.format("late" if coef > 0 else "early"))
    sentence = "; ".join(parts) + "."
    sentence = sentence[0].upper() + sentence[1:]
    return sentence, {"ratio": ratio, "regions": reg,
                      "pattern_shares": {k.split(" (")[0].replace("{}", "..."): v[0]
                                         for k, v in shares.items()}}


# =============================================================================== diagnose
def _check_candidates(candidates):
    if candidates is None:
        return CANDIDATES
    if isinstance(candidates, str):
        raise ValueError("candidates must be a sequence of effect names, not a string")
    cand = tuple(candidates)
    bad = [c for c in cand if c not in EFFECTS]
    if bad or not cand or len(set(cand)) != len(cand):
        raise ValueError(f"candidates must be distinct names of {sorted(EFFECTS)}, got {cand!r}")
    return cand


def _untestable(t, v, cycles) -> dict:
    out = {}
    if t is None:
        out["viscous_damping"] = ("no time vector was given, so the velocity is unknown; "
                                  "a rate effect cannot be tested")
    else:
        s = np.abs(v)
        moving = s > 0.05 * s.max()
        med = float(np.median(s[moving])) if moving.any() else 0.0
        if moving.sum() > 10 and np.mean(np.abs(s[moving] - med) <= 0.05 * med) >= 0.9:
            out["viscous_damping"] = ("the record is loaded at a single constant rate (|v| "
                                      "within 5 % of one value on 90 % of the samples), so a dashpot force c v cannot be told from a "
                                      "rate-independent friction offset; test at several rates "
                                      "or with sinusoidal loading")
    return out


def diagnose(t, u, F, *, candidates=None, max_effects: int = 2, noise: float | None = None,
             alpha: float = 1e-3, ambiguity: float = 10.0, max_samples: int = 1500,
             seed=0) -> Diagnosis:
    """Find what the four-parameter Iwan model misses in a displacement-driven test.

    See the module docstring for the procedure.

    Parameters
    ----------
    t : array_like, shape (n,), or None
        Time [s], strictly increasing. Needed for velocity-dependent effects (``v = du/dt``);
        with ``None`` viscous damping is reported as untestable. Not modified.
    u, F : array_like, shape (n,)
        Measured displacement [m] and force [N], starting at rest. Not modified.
    candidates : sequence of str, optional, keyword-only
        Effects to try (default :data:`CANDIDATES`, all of the library).
    max_effects : int, keyword-only
        Most effects named one after the other, ``>= 1`` (default 2).
    noise : float, optional, keyword-only
        Force noise standard deviation [N], ``> 0``, taken as white. Default: estimated from
        repeated cycles (the record must repeat some amplitude in consecutive cycles).
    alpha : float, keyword-only
        Significance level of the misfit test and (Bonferroni-divided over the candidates)
        of each effect's improvement, in ``(0, 0.5)``. Default 1e-3.
    ambiguity : float, keyword-only
        Information-criterion difference below which another effect counts as explaining the
        misfit nearly equally, ``>= 0`` (default 10).
    max_samples : int, keyword-only
        Samples fitted per effect (evenly spaced, turning points kept), ``>= 100``.
    seed : int or numpy.random.Generator, keyword-only
        Seed of the base fit's random starts.

    Returns
    -------
    Diagnosis

    Raises
    ------
    ValueError
        Bad arrays, fewer than two complete cycles, no repeated cycles to estimate the noise
        (and no ``noise`` given), or an option out of range.
    """
    t_start = time.perf_counter()
    uu = check_magnitude("u", finite_array("u", u, ndim=1, min_size=10), unit="m")
    FF = check_magnitude("F", finite_array("F", F, ndim=1, min_size=10), unit="N")
    n = same_length(u=uu, F=FF)
    tt = None if t is None else _check_time(t, n)
    cand = _check_candidates(candidates)
    max_effects = _check_int("max_effects", max_effects, 1)
    alpha = check_scalar("alpha", alpha, low=0.0, high=0.5, low_open=True, high_open=True)
    ambiguity = check_scalar("ambiguity", ambiguity, low=0.0)
    max_samples = _check_int("max_samples", max_samples, 100)
    if noise is not None:
        noise = check_scalar("noise", noise, low=0.0, low_open=True)
    cycles = split_cycles(tt, uu, FF)
    if len(cycles) < 2:
        raise ValueError(f"u contains {len(cycles)} complete cycle(s): a single cycle cannot "
                         "separate model error from noise; at least 2 (better 3 per amplitude) "
                         "are needed")
    with _quiet():                       # its warnings are reported with the diagnosis
        base = fit_loops(np.arange(n, dtype=float) if tt is None else tt, uu, FF, seed=seed)
    warns = [f"base fit: {w}" for w in base.warnings]
    F_base = IwanJoint(base.params).force_history(uu)
    r0 = FF - F_base
    span = float(np.ptp(FF))
    if noise is None:
        est = _repeat_noise(uu, r0, F_base, cycles)
        if est is None:
            raise ValueError("too little data to estimate the noise: no amplitude is repeated "
                             "in consecutive cycles (the noise is estimated from the difference "
                             "of repeated cycles); repeat each amplitude 2-3 times or pass noise=")
        sigma, m_noise, tau, groups = est
        if m_noise < 50:
            raise ValueError(f"too little data to estimate the noise: only {m_noise} samples of "
                             "repeated cycles; record more (or longer) repeated cycles or pass noise=")
        noise_from = "repeats"
    else:
        sigma, m_noise, tau, groups = noise, 10 ** 7, 1.0, 0
        noise_from = "given"
    v = np.zeros(n) if tt is None else np.gradient(uu, tt)
    untestable = {k: why for k, why in _untestable(tt, v, cycles).items() if k in cand}
    testable = tuple(c for c in cand if c not in untestable)
    if not base.identified.get("Fs", True):
        warns.append("the record does not reach macroslip: a pinning stiffness without "
                     "clearance would be indistinguishable from a stiffer Iwan joint here")
    # ---- fit set
    keep = np.unique(np.round(np.linspace(0, n - 1, min(n, max_samples))).astype(np.intp))
    rev = find_reversals(uu)
    ev = Evaluator(uu, v, keep, rev)
    y = FF[keep]
    nf = keep.size
    s2 = sigma * sigma
    n_eff = nf / tau
    m_eff = m_noise / tau
    bshape = (base.params.phi_max, base.params.chi, base.params.beta)
    g_base = ev.unit_force(bshape, (), ())
    r_b = y - base.params.Fs * g_base
    ssr_b = float(r_b @ r_b)

    def misfit_p(ssr, p):
        ratio = ssr / ((nf - p) * s2)
        return ratio, float(fdtrc(max(n_eff - p, 1.0), m_eff, ratio))

    ratio0, p0 = misfit_p(ssr_b, 4)
    misfit = p0 < alpha
    where, loc = _locate(tt, uu, FF, F_base, r0, cycles, sigma, tau)
    if not misfit:
        where = (f"The residual is consistent with the noise (RMS {math.sqrt(ratio0) * sigma:.3g} N "
                 f"vs {sigma:.3g} N, p = {p0:.2g}); there is no misfit to explain.")
    scales = {"u_max": float(np.abs(uu).max()), "v_rms": float(np.sqrt(np.mean(v ** 2))) or 1.0,
              "D_ref": float(ev._unit_dissipation(unit_params(*bshape))[-1]) or 1.0}
    z_base = np.array([math.log(bshape[0] / ev.x_max), bshape[1], math.log1p(bshape[2])])
    named: list[str] = []
    ambiguous: tuple = ()
    steps = []
    current = {"names": (), "z": z_base, "ssr": ssr_b, "q": 4, "model": None}
    nfev_total = 0
    fitted_models = {}
    while misfit and len(named) < max_effects:
        rest = [c for c in testable if c not in named]
        if not rest:
            break
        ratio_c, p_c = misfit_p(current["ssr"], current["q"])
        if current["names"] and p_c >= alpha:
            break
        excess = current["ssr"] - (nf - current["q"]) * s2
        rows = []
        for name in rest:
            names = current["names"] + (name,)
            mdl = _Model(ev, y, names, scales)
            spec = mdl.specs[-1]
            starts = [np.concatenate([current["z"], s]) for s in spec[2]]
            res, nfev = _fit(mdl, starts, max_nfev=200 if ev.fast(names) else 60)
            nfev_total += nfev
            ssr = 2.0 * res.cost
            q = len(spec[0])
            gain = max(current["ssr"] - ssr, 0.0)
            F_stat = gain / (q * tau * s2)
            p = float(fdtrc(q, m_eff, F_stat))
            aic = ssr / (tau * s2) + 2 * q
            rows.append({"name": name, "ssr": ssr, "q": q, "p": p, "aic": aic, "gain": gain,
                         "nrmse": math.sqrt(ssr / nf) / span, "ratio": math.sqrt(ssr / ((nf - current["q"] - q) * s2)),
                         "model": mdl, "z": res.x, "message": res.message, "status": res.status})
        a_lim = alpha / len(rows)
        ok = [rw for rw in rows if rw["p"] < a_lim and rw["gain"] >= _EXPLAIN_FRACTION * max(excess, 0.0)]
        best = min(ok, key=lambda rw: rw["aic"]) if ok else None
        if best is not None and untestable:
            # a guess is not a diagnosis: with effects that cannot be tested, name one only if
            # it brings the misfit down to the noise
            if misfit_p(best["ssr"], current["q"] + best["q"])[1] < alpha:
                best = None
                warns.append("the misfit is real but no testable effect explains it; the effects "
                             f"this record cannot reveal ({', '.join(untestable)}) may be the cause")
        best_aic = min(rw["aic"] for rw in rows)
        for rw in rows:
            if rw is best:
                rw["verdict"] = "NAMED"
            elif rw["p"] >= a_lim:
                rw["verdict"] = "not significant"
            elif rw["gain"] < _EXPLAIN_FRACTION * max(excess, 0.0):
                rw["verdict"] = "significant, explains little"
            elif best is not None and rw["aic"] - best["aic"] < ambiguity:
                rw["verdict"] = "nearly as good"
            else:
                rw["verdict"] = "worse"
            rw["dAIC"] = rw["aic"] - best_aic
        step = {"on": list(current["names"]),
                "candidates": [{k: rw[k] for k in ("name", "nrmse", "ratio", "p", "dAIC", "verdict",
                                                   "message")} for rw in rows]}
        steps.append(step)
        if best is None:
            break
        if not named:
            ambiguous = tuple(rw["name"] for rw in rows if rw["verdict"] == "nearly as good")
        named.append(best["name"])
        current = {"names": best["model"].names, "z": best["z"], "ssr": best["ssr"],
                   "q": current["q"] + best["q"], "model": best["model"]}
        fitted_models[best["name"]] = best
    # ---- results
    if current["model"] is None:
        fit = base
        model = IwanJoint(base.params)
        F_after = F_base
    else:
        mdl = current["model"]
        z = current["z"]
        p_aug, effs = _physical(mdl, z)
        model = build_element(p_aug, mdl.names, effs)
        F_after = model.force_history(uu, v)
        r_fit = y - p_aug.Fs * mdl.unit(z)
        se, corr, nfe = _uncertainty(mdl, z, r_fit)
        nfev_total += nfe
        flat, labels = _flat(p_aug, effs, mdl.names)
        stderr = dict(zip(PARAM_NAMES, se[:4].tolist()))
        for k in PARAM_NAMES:
            if not base.identified.get(k, True):
                stderr[k] = math.nan
        eff_out, k0 = [], 4
        for nm, d in zip(mdl.names, effs):
            q = len(EFFECTS[nm].parameter_names)
            eff_out.append({"name": nm, "parameters": dict(d),
                            "stderr": dict(zip(EFFECTS[nm].parameter_names, se[k0:k0 + q].tolist())),
                            "units": {k: _UNITS[k] for k in d}})
            k0 += q
        fit_warns = list(base.warnings)
        last = fitted_models[named[-1]]
        converged = last["status"] > 0
        if not converged:
            fit_warns.append(f"the augmented fit did not converge: {last['message']}")
        fit = FitResult(
            params=p_aug, stderr=stderr, correlation=corr[:4, :4], identified=dict(base.identified),
            fixed=(), ranges=dict(base.ranges), residual_norm=math.sqrt(float(r_fit @ r_fit)),
            nrmse=float(np.sqrt(np.mean((FF - F_after) ** 2)) / span), success=bool(converged),
            message=str(last["message"]), nfev=int(nfev_total), method="loops+" + "+".join(mdl.names),
            n_data=int(nf), warnings=tuple(fit_warns), wall_time=time.perf_counter() - t_start,
            details=_json({"effects": eff_out, "labels": labels, "correlation_all": corr,
                           "fitted_samples": nf}))
    error_before = float(np.sqrt(np.mean(r0 ** 2)) / span)
    error_after = float(np.sqrt(np.mean((FF - F_after) ** 2)) / span)
    if misfit and named and misfit_p(current["ssr"], current["q"])[1] < alpha:
        warns.append(f"misfit beyond the noise remains after {' + '.join(named)} "
                     f"({error_after / (sigma / span):.3g} x noise)")
    if misfit and not named and not any("no testable effect" in w for w in warns):
        warns.append("the misfit is more than noise but no tested effect explains it"
                     + (f"; this record cannot reveal {', '.join(untestable)} (see above)"
                        if untestable else ""))
    ro = lambda a: (a.setflags(write=False), a)[1]  # noqa: E731
    details = {"samples": n, "cycles": len(cycles), "fitted_samples": nf, "tau": tau,
               "noise_samples": m_noise if noise is None else None, "noise_groups": groups,
"noise_from": noise_from, "misfit_ratio": ratio0,
               "misfit_p": p0, "alpha": alpha, "ambiguity": ambiguity, "location": loc,
               "wall_time": time.perf_counter() - t_start}
    return Diagnosis(
        effect=named[0] if named else "none", effects=tuple(named), ambiguous_with=ambiguous,
        where=where, error_before=error_before, error_after=error_after,
        noise_level=sigma / span, noise_sigma=float(sigma), misfit=bool(misfit), base_fit=base,
        fit=fit, model=model, steps=tuple(_json(s) for s in steps), untestable=untestable,
        warnings=tuple(warns), force_before=ro(F_base), force_after=ro(np.array(F_after)),
        t=ro(np.arange(n, dtype=float) if tt is None else tt), u=ro(uu), F=ro(FF),
        details=_json(details))


# =============================================================================== vibration
_VIB_EFFECTS = ("viscous_damping", "pinning_stiffness")
_VIB_UNITS = {"zeta_v": "1", "k_p_per_mass": "1/s^2", "delta": "m"}


def _dead_zone_gain(X, delta):
    """Describing function of ``sign(u) max(|u| - delta, 0)`` at amplitude ``X``: the
    equivalent linear stiffness per unit ``k_p`` [-] (1 for ``delta = 0``)."""
    r = np.clip(delta / X, 0.0, 1.0)
    return 1.0 - (2.0 / np.pi) * (np.arcsin(r) + r * np.sqrt(1.0 - r * r))


def _vib_model(names, vals, fp, zp, X, zeta0):
    """Frequency [Hz] and damping ratio with the named effects added to a prediction."""
    f, z = fp, zp
    if "pinning_stiffness" in names:
        d = vals["pinning_stiffness"]
        f = np.sqrt(fp * fp + d["k_p_per_mass"] * _dead_zone_gain(X, d["delta"]) / (4 * np.pi ** 2))
        z = zeta0 + (zp - zeta0) * (fp / f) ** 2     # same dissipation, stiffer mode
    if "viscous_damping" in names:
        z = z + vals["viscous_damping"]["zeta_v"]
    return f, z


@dataclass(frozen=True, eq=False)
class VibrationDiagnosis:
    """Measured against predicted amplitude-dependent frequency and damping: what is missing.

    Attributes
    ----------
    effect : str
        ``"viscous_damping"``, ``"pinning_stiffness"`` or ``"none"`` (the first one named).
    effects : tuple of str
        All effects named, in order.
    ambiguous_with : tuple of str
        Effects explaining the first step nearly as well.
    where : str
        Where measured and predicted curves disagree beyond the noise.
    parameters : dict
        Fitted magnitudes: ``viscous_damping: {"zeta_v"}`` (added modal viscous damping
        ratio [-]); ``pinning_stiffness: {"k_p_per_mass" [1/s^2], "delta" [m]}`` (added modal
        stiffness over modal mass, and the clearance in amplitude units).
    error_before, error_after : float
        RMS relative mismatch of frequency and damping together [-] (log residuals).
    noise_level : float
        RMS relative noise of the two curves [-].
    frequency_noise, damping_noise : float
        Relative noise of each curve [-] (estimated or given).
    amplitude, frequency, damping, predicted_frequency, predicted_damping : ndarray, shape (n,)
        The inputs (read-only copies).
    model_frequency, model_damping : ndarray, shape (n,)
        The prediction with the named effects added.
    steps : tuple of dict
    details : dict
    """

    effect: str
    effects: tuple
    ambiguous_with: tuple
    where: str
    parameters: dict
    error_before: float
    error_after: float
    noise_level: float
    frequency_noise: float
    damping_noise: float
    amplitude: np.ndarray
    frequency: np.ndarray
    damping: np.ndarray
    predicted_frequency: np.ndarray
    predicted_damping: np.ndarray
    model_frequency: np.ndarray
    model_damping: np.ndarray
    steps: tuple
    details: dict = field(default_factory=dict)

    def augment(self, joint, *, modal_mass: float, slip_per_amplitude: float = 1.0):
        """Wrap a joint element with the named effects, converted from modal to joint terms.

        Parameters
        ----------
        joint : joint element
        modal_mass : float, keyword-only
            Modal mass [kg] of the mode the curves describe, ``> 0``.
        slip_per_amplitude : float, keyword-only
            Joint slip per unit modal amplitude ``r`` [-], ``> 0``: a joint spring ``k`` adds
            ``k r^2`` to the modal stiffness, a dashpot ``c`` adds ``c r^2``.

        Returns
        -------
        joint element
            ``PinningStiffness(k_p = kappa m / r^2, delta = delta r)`` and/or
            ``ViscousDamping(c = 2 zeta_v omega_0 m / r^2)`` around ``joint``, with
            ``omega_0`` the measured angular frequency at the smallest amplitude.
        """
        m = check_scalar("modal_mass", modal_mass, low=0.0, low_open=True)
        r = check_scalar("slip_per_amplitude", slip_per_amplitude, low=0.0, low_open=True)
        el = joint
        for name in self.effects:
            d = self.parameters[name]
            if name == "pinning_stiffness":
                el = EFFECTS[name](el, k_p=d["k_p_per_mass"] * m / r ** 2, delta=d["delta"] * r)
            else:
                w0 = 2 * np.pi * float(self.frequency[np.argmin(self.amplitude)])
                el = EFFECTS[name](el, c=2.0 * d["zeta_v"] * w0 * m / r ** 2)
        return el

    def to_dict(self) -> dict:
        """JSON-safe dict."""
        return _json({k: getattr(self, k) for k in (
            "effect", "effects", "ambiguous_with", "where", "parameters", "error_before",
            "error_after", "noise_level", "frequency_noise", "damping_noise", "amplitude",
            "frequency", "damping", "predicted_frequency", "predicted_damping",
            "model_frequency", "model_damping", "steps", "details")})

    def report(self) -> str:
        """Human-readable account."""
        lines = ["Vibration diagnosis (amplitude-dependent frequency and damping)",
                 f"  {self.amplitude.size} amplitudes, {self.amplitude.min():.3g} .. "
                 f"{self.amplitude.max():.3g} m; noise: frequency {100 * self.frequency_noise:.2g} %, "
                 f"damping {100 * self.damping_noise:.2g} % ({self.details['noise_from']})",
                 f"  where: {self.where}"]
        for k, st in enumerate(self.steps):
            lines.append(f"  step {k + 1}: candidates on {' + '.join(st['on']) or 'prediction'}")
            for c in st["candidates"]:
                lines.append(f"    {c['name']:<18} mismatch {100 * c['error']:7.3g} %  dAIC "
                             f"{c['dAIC']:8.1f}  p {c['p']:9.2g}  {c['verdict']}")
        if self.effects:
            lines.append(f"  named: {', '.join(self.effects)}" + (
                f" (nearly as good: {', '.join(self.ambiguous_with)})" if self.ambiguous_with else ""))
            for name, d in self.parameters.items():
                lines.append("    " + name + ": " + ", ".join(
                    f"{k} = {v:.4g} {_VIB_UNITS[k]}" for k, v in d.items()))
        else:
            lines.append("  named: none")
        lines.append(f"  mismatch before {100 * self.error_before:.3g} % -> after "
                     f"{100 * self.error_after:.3g} % (noise {100 * self.noise_level:.3g} %)")
        return "\n".join(lines)

    def plot(self, ax=None):
        """Frequency and damping against amplitude: measured, predicted, augmented.

        ``ax``: ``None`` (new figure, two panels) or a pair of Axes. Returns the artists."""
        if ax is None:
            import matplotlib.pyplot as plt
            _, ax = plt.subplots(1, 2, figsize=(11, 4.2))
        if not isinstance(ax, (list, tuple, np.ndarray)) or len(ax) != 2:
            raise ValueError("ax must be None or a pair of Axes (frequency, damping)")
        a1, a2 = ax
        X = self.amplitude
        o = np.argsort(X)
        arts = a1.semilogx(X[o], self.frequency[o], "o", ms=3, mfc="none", color="k", label="measured")
        arts += a1.semilogx(X[o], self.predicted_frequency[o], "-", color="C0", label="predicted")
        arts += a1.semilogx(X[o], self.model_frequency[o], "--", color="C3",
                            label="+ " + (" + ".join(self.effects) or "nothing"))
        a1.set_xlabel("amplitude [m]")
        a1.set_ylabel("frequency [Hz]")
        arts += a2.loglog(X[o], self.damping[o], "o", ms=3, mfc="none", color="k", label="measured")
        arts += a2.loglog(X[o], self.predicted_damping[o], "-", color="C0", label="predicted")
        arts += a2.loglog(X[o], self.model_damping[o], "--", color="C3",
                          label="+ " + (" + ".join(self.effects) or "nothing"))
        a2.set_xlabel("amplitude [m]")
        a2.set_ylabel("damping ratio [-]")
        for a in (a1, a2):
            a.grid(True, which="both", alpha=0.3)
            a.legend(fontsize=7)
        return arts


def _curve_noise(r):
    """Relative noise of a curve from its second differences along amplitude (MAD, robust
    to a smooth systematic mismatch)."""
    d2 = r[:-2] - 2 * r[1:-1] + r[2:]
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / math.sqrt(6.0))


def diagnose_vibration(amplitude, frequency, damping, *, predicted_frequency, predicted_damping,
                       frequency_noise: float | None = None, damping_noise: float | None = None,
                       predicted_zeta0: float = 0.0, alpha: float = 1e-3,
                       ambiguity: float = 10.0, max_effects: int = 2) -> VibrationDiagnosis:
    """Compare measured and predicted amplitude-dependent frequency and damping; name what the
    jointed model misses.

    Two effects are tried, alone and one after the other:

    * ``viscous_damping``: a constant added modal damping ratio ``zeta_v`` (a damping floor:
      measured damping levels off at low amplitude where the joint's hysteresis fades);
    * ``pinning_stiffness``: an added modal stiffness ``k_p`` per modal mass engaging beyond a
      clearance ``delta`` (harmonic-balance gain of the dead-zone spring), which raises the
      frequency (a frequency floor / stiffening at high amplitude, where the joint slips) and
      lowers the hysteretic damping ratio by ``(f_pred / f)^2`` (same dissipation, stiffer mode).

    Residuals are the log ratios of measured to modelled frequency and damping, weighted by
    their relative noise; the tests are as in :func:`diagnose` (F-tests against the noise, an
    information criterion, ``ambiguity``).

    Parameters
    ----------
    amplitude : array_like, shape (n,)
        Response amplitude [m] (joint slip or modal amplitude), ``> 0``; ``n >= 8``.
    frequency, damping : array_like, shape (n,)
        Measured (or reference) frequency [Hz] and damping ratio [-], ``> 0``.
    predicted_frequency, predicted_damping : array_like, shape (n,), keyword-only
        The model's prediction at the same amplitudes (e.g. the jointed-beam simulation or the
        single-mode closed form), ``> 0``.
    frequency_noise, damping_noise : float, optional, keyword-only
        Relative noise standard deviations [-], ``> 0``; default: estimated from the scatter of
        the curves (second differences along amplitude, robust).
    predicted_zeta0 : float, keyword-only
        Viscous damping ratio already in the prediction [-], ``>= 0`` (not rescaled by a
        pinning stiffness).
    alpha, ambiguity, max_effects : keyword-only
        As in :func:`diagnose` (``max_effects`` at most 2).

    Returns
    -------
    VibrationDiagnosis

    Raises
    ------
    ValueError
        Non-positive or non-finite values, unequal lengths, fewer than 8 amplitudes without
        given noise levels, or an option out of range.
    """
    from scipy.optimize import least_squares

    X = finite_array("amplitude", amplitude, ndim=1, min_size=3)
    fm = finite_array("frequency", frequency, ndim=1, min_size=3)
    zm = finite_array("damping", damping, ndim=1, min_size=3)
    fp = finite_array("predicted_frequency", predicted_frequency, ndim=1, min_size=3)
    zp = finite_array("predicted_damping", predicted_damping, ndim=1, min_size=3)
    n = same_length(amplitude=X, frequency=fm, damping=zm, predicted_frequency=fp,
                    predicted_damping=zp)
    for nm, a in (("amplitude", X), ("frequency", fm), ("damping", zm),
                  ("predicted_frequency", fp), ("predicted_damping", zp)):
        if np.any(a <= 0):
            raise ValueError(f"{nm} must be > 0 everywhere")
    zeta0 = check_scalar("predicted_zeta0", predicted_zeta0, low=0.0)
    alpha = check_scalar("alpha", alpha, low=0.0, high=0.5, low_open=True, high_open=True)
    ambiguity = check_scalar("ambiguity", ambiguity, low=0.0)
    max_effects = _check_int("max_effects", max_effects, 1)
    if max_effects > 2:
        raise ValueError(f"max_effects must be 1 or 2 for vibration curves (two candidate "
                         f"effects), got {max_effects}")
    o = np.argsort(X)
    rf0 = np.log(fm / fp)
    rz0 = np.log(zm / zp)
    if frequency_noise is None or damping_noise is None:
        if n < 8:
            raise ValueError(f"too little data to estimate the noise from {n} amplitudes (at least "
                             "8 are needed); pass frequency_noise= and damping_noise=")
        noise_from = "estimated from the scatter of the curves"
        dof = 0.37 * (n - 2)                     # efficiency of the MAD for Gaussian data
    else:
        noise_from = "given"
        dof = 1e7
    sf = (check_scalar("frequency_noise", frequency_noise, low=0.0, low_open=True)
          if frequency_noise is not None else max(_curve_noise(rf0[o]), 1e-12))
    sz = (check_scalar("damping_noise", damping_noise, low=0.0, low_open=True)
          if damping_noise is not None else max(_curve_noise(rz0[o]), 1e-12))
    noise_level = math.sqrt(0.5 * (sf * sf + sz * sz))
    dof_all = 2 * dof
    Xmax = float(X.max())
    f2min = float(np.min(fp)) ** 2

    def decode(names, z):
        vals, k = {}, 0
        for nm in names:
            if nm == "viscous_damping":
                vals[nm] = {"zeta_v": float(z[k]) * float(np.median(zp))}
                k += 1
            else:
                vals[nm] = {"k_p_per_mass": float(z[k]) * 4 * np.pi ** 2 * f2min,
                            "delta": float(z[k + 1]) * Xmax}
                k += 2
        return vals

    def resid(names, z):
        f, zz = _vib_model(names, decode(names, z), fp, zp, X, zeta0)
        return np.concatenate([np.log(fm / f) / sf, np.log(zm / zz) / sz])

    def err(names, z):
        f, zz = _vib_model(names, decode(names, z), fp, zp, X, zeta0)
        return math.sqrt(np.mean(np.concatenate([np.log(fm / f), np.log(zm / zz)]) ** 2))

    specs = {"viscous_damping": ([0.0], [100.0], [[0.0], [0.5], [5.0]]),
             "pinning_stiffness": ([0.0, 0.0], [10.0, 0.99], [[0.0, 0.0], [0.05, 0.0], [0.05, 0.3]])}
    chi_b = float(np.sum(resid((), np.zeros(0)) ** 2))
    N = 2 * n
    misfit_ratio = chi_b / N
    p0 = float(fdtrc(N, dof_all, misfit_ratio))
    misfit = p0 < alpha
    # where
    parts = []
    for label, r, s in (("frequency", rf0, sf), ("damping", rz0, sz)):
        big = np.abs(r) > 3 * s
        if big.sum() >= 2:
            xs = X[big]
            sign = "above" if np.median(r[big]) > 0 else "below"
            top = float(X[np.argmax(np.abs(r))])
            lo_hi = "low" if top <= np.median(X) else "high"
            parts.append(f"measured {label} is {sign} the prediction, most at {lo_hi} amplitudes "
                         f"(beyond 3 x noise from {xs.min():.3g} to {xs.max():.3g} m, up to "
                         f"{100 * np.max(np.abs(r[big])):.3g} % at {top:.3g} m)")
    where = ("; ".join(parts) if (misfit and parts) else
             "measured and predicted curves agree within the noise") + "."
    where = where[0].upper() + where[1:]
    named, ambiguous, steps = [], (), []
    cur_names, cur_z, cur_chi, cur_q = (), np.zeros(0), chi_b, 0
    while misfit and len(named) < max_effects:
        if cur_names and float(fdtrc(N - cur_q, dof_all, cur_chi / (N - cur_q))) >= alpha:
            break
        rows = []
        for nm in _VIB_EFFECTS:
            if nm in named:
                continue
            names = cur_names + (nm,)
            lo, hi, starts = specs[nm]
            lower = np.concatenate([np.zeros(cur_z.size), lo])
            upper = np.concatenate([np.full(cur_z.size, np.inf), hi])
            if cur_names:
                lower[:cur_z.size] = np.concatenate([specs[c][0] for c in cur_names])
                upper[:cur_z.size] = np.concatenate([specs[c][1] for c in cur_names])
            best = None
            for s0 in starts:
                z0 = np.clip(np.concatenate([cur_z, s0]), lower, upper - 1e-12)
                res = least_squares(lambda z: resid(names, z), z0, bounds=(lower, upper),
                                    method="trf", x_scale="jac")
                if best is None or res.cost < best.cost:
                    best = res
            chi2 = 2 * best.cost
            q = len(lo)
            gain = max(cur_chi - chi2, 0.0)
            p = float(fdtrc(q, dof_all, gain / q))
            rows.append({"name": nm, "names": names, "z": best.x, "chi2": chi2, "q": q, "p": p,
                         "aic": chi2 + 2 * q, "error": err(names, best.x)})
        if not rows:
            break
        a_lim = alpha / len(rows)
        ok = [r for r in rows if r["p"] < a_lim]
        best = min(ok, key=lambda r: r["aic"]) if ok else None
        best_aic = min(r["aic"] for r in rows)
        for r in rows:
            r["dAIC"] = r["aic"] - best_aic
            r["verdict"] = ("NAMED" if r is best else "not significant" if r["p"] >= a_lim else
                            "nearly as good" if r["aic"] - best["aic"] < ambiguity else "worse")
        steps.append({"on": list(cur_names), "candidates": [
            {k: r[k] for k in ("name", "error", "p", "dAIC", "verdict")} for r in rows]})
        if best is None:
            break
        if not named:
            ambiguous = tuple(r["name"] for r in rows if r["verdict"] == "nearly as good")
        named.append(best["name"])
        cur_names, cur_z, cur_chi, cur_q = best["names"], best["z"], best["chi2"], cur_q + best["q"]
    params = decode(cur_names, cur_z)
    f_new, z_new = _vib_model(cur_names, params, fp, zp, X, zeta0)
    ro = lambda a: (a.setflags(write=False), a)[1]  # noqa: E731
    details = {"noise_from": noise_from, "misfit_ratio": misfit_ratio, "misfit_p": p0,
               "alpha": alpha, "chi2_before": chi_b, "chi2_after": cur_chi,
               "frequency_error_before": float(np.sqrt(np.mean(rf0 ** 2))),
               "damping_error_before": float(np.sqrt(np.mean(rz0 ** 2))),
               "frequency_error_after": float(np.sqrt(np.mean(np.log(fm / f_new) ** 2))),
               "damping_error_after": float(np.sqrt(np.mean(np.log(zm / z_new) ** 2)))}
    return VibrationDiagnosis(
        effect=named[0] if named else "none", effects=tuple(named), ambiguous_with=ambiguous,
        where=where, parameters=params,
        error_before=float(math.sqrt(np.mean(np.concatenate([rf0, rz0]) ** 2))),
        error_after=err(cur_names, cur_z), noise_level=noise_level, frequency_noise=sf,
        damping_noise=sz, amplitude=ro(X), frequency=ro(fm), damping=ro(zm),
        predicted_frequency=ro(fp), predicted_damping=ro(zp), model_frequency=ro(f_new),
        model_damping=ro(z_new), steps=tuple(_json(s) for s in steps), details=_json(details))
