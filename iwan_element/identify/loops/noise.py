"""Noise level of one measured channel, from a single record, without repeated cycles.

Method (``method="savgol"``, what ``"auto"`` uses)
    A quasi-static joint test is a slowly varying signal plus sensor noise. The signal is
    removed by a local cubic least-squares fit (a Savitzky-Golay filter, ``scipy.signal``)
    whose window is short compared with the fastest loading time scale: ``1/16`` of the
    period at the frequency below which 95 % of the (linearly detrended) signal power lies,
    at least 9 samples. A window that short follows every loading protocol (constant, ramped,
    swept or random amplitudes alike: only the time scale matters, no cycle is compared with
    another), while noise faster than the window stays in the residual ``r = y - S y``.

    * Scale: ``sigma = 1.4826 MAD(r) / sqrt(1 - h0)``, where ``h0`` is the filter's central
      weight. For white noise ``var(r) = (1 - h0) sigma^2`` exactly (the filter is a
      projection), so the factor makes the estimate unbiased; the median absolute deviation
      ignores the few samples where the signal has a kink (a reversal of the force, a
      break-away peak) or a short burst of load-frame chatter.
    * Coloured noise: the filter also removes the slow part of correlated noise, and its
      residual of white noise is itself anti-correlated, so neither the residual's variance nor
      its autocorrelation is the noise's. The noise is modelled as AR(1) (lag-one correlation
      ``rho``): the residual's robust lag-one correlation (from the MAD scales of sums and
      differences of neighbouring samples within the clean blocks) is matched to the one the
      same filter ``r = (I - H) e`` produces from AR(1) noise, which gives ``rho``; the scale
      is then divided by the filter's exact variance factor for that ``rho`` (``1 - h0`` for
      white noise). The integrated correlation time is ``tau = (1 + rho)/(1 - rho)``
      [samples] and ``n_eff = n / tau`` the effective number of independent samples (white
      noise: ``tau = 1``). Noise correlated over much longer than the window cannot be told
      from the signal (a warning says so when ``rho`` reaches 0.98). The estimate is repeated
      with half the window: AR(1) noise reads the same through both, so when the two differ
      by more than 25 % and the halved window reads less, signal (or a model's misfit) leaks
      into the longer window's residual and the halved window's estimate is used (a warning
      says so; when the halved window reads more, the noise is not AR(1)-like there).
    * A fit residual (the diagnoses pass the residual of the plain fit) is estimated the same
      way with the window of the measured channel (``window=``): the residual holds the noise
      and whatever the model misses; the smooth part of the misfit is removed by the filter,
      its corners by the robust scale.

``method="difference"``: ``1.4826 MAD`` of the second differences divided by ``sqrt(6)``
(white noise only; kept for comparison). The result is in the units of ``y``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.signal import savgol_coeffs, savgol_filter

from ...base.result_shape import ResultShape, panels
from ...base.validation import check_magnitude, check_scalar, check_time, finite_array, same_length

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["NoiseEstimate", "estimate_noise", "integrated_time", "difference_sigma"]

_MAD = 1.482602218505602  # 1 / Phi^-1(3/4): MAD -> standard deviation of a Gaussian
_POLY = 5
MIN_WINDOW = 9


_RHO_MAX = 0.98
#: Fewest effective samples for a noise level to count as estimated (``NoiseEstimate.success``).
MIN_EFFECTIVE = 10


@dataclass(frozen=True)
class NoiseEstimate(ResultShape):
    """Noise level of one channel (see :func:`estimate_noise`).

    Attributes
    ----------
    sigma : float
        Noise standard deviation, in the units of ``y``.
    method : str
        ``"savgol+ar1"`` or ``"difference"``.
    correlation_time : float
        Integrated autocorrelation time of the noise residual [s] (``tau * dt``).
    n : int
        Samples used.
    n_eff : float
        Effective number of independent noise samples, ``n * dt / correlation_time``.
    window : float
        Smoothing window [s] (``savgol``; one sample step for ``difference``).
    warnings : tuple of str
        What limits the estimate.
    lag_one : float
        Lag-one correlation ``rho`` of the AR(1) noise model (0: white).
    """

    COLUMNS = {
        "sigma": ("noise sigma", "unit of the signal"),
        "correlation_time": ("correlation time", "s"),
        "window": ("window", "s"),
        "n_eff": ("effective samples", "-"),
    }

    sigma: float
    method: str
    correlation_time: float
    n: int
    n_eff: float
    window: float
    lag_one: float = 0.0

    @property
    def tau(self) -> float:
        """Integrated correlation time in samples (``n / n_eff``, at least 1)."""
        return max(float(self.n) / float(self.n_eff), 1.0) if self.n_eff > 0 else 1.0

    @property
    def success(self) -> bool:
        """True for a finite, positive level from at least :data:`MIN_EFFECTIVE` independent
        samples (then its relative standard error, about ``1 / sqrt(2 n_eff)``, is below
        about 22 %).
        """
        return bool(math.isfinite(self.sigma) and self.sigma > 0 and self.n_eff >= MIN_EFFECTIVE)

    def plot(self, ax=None, *, lags: int | None = None) -> list[Artist]:
        """The noise model's autocorrelation ``rho**|k|`` (AR(1)) against the lag [s], with the
        integrated correlation time marked. Returns the artists (one Axes,
        :mod:`iwan_element.base.result_shape`).
        """
        (ax,) = panels(ax, 1, figsize=(5, 3.5))
        dt = self.correlation_time / self.tau if self.tau > 0 else 1.0
        k = np.arange(lags if lags is not None else max(10, int(6 * self.tau)) + 1)
        rho = self.lag_one**k if self.lag_one > 0 else (k == 0).astype(float)
        arts = ax.plot(k * dt, rho, "o-", ms=3, label=f"AR(1), rho = {self.lag_one:.2f}")
        arts.append(
            ax.axvline(
                self.correlation_time,
                color="k",
                ls=":",
                label=f"correlation time {self.correlation_time:.3g} s",
            )
        )
        ax.set_xlabel("lag [s]")
        ax.set_ylabel("noise autocorrelation [-]")
        ax.set_title(f"sigma = {self.sigma:.4g} ({self.method})", fontsize=9)
        ax.legend(fontsize=8)
        return arts

    def to_dict(self) -> dict:
        """JSON-safe dict."""
        return {
            "sigma": float(self.sigma),
            "method": self.method,
            "success": self.success,
            "correlation_time": float(self.correlation_time),
            "n": int(self.n),
            "n_eff": float(self.n_eff),
            "window": float(self.window),
            "lag_one": float(self.lag_one),
            "warnings": list(self.warnings),
        }

    def report(self) -> str:
        """One-paragraph summary."""
        lines = [
            self.verdict(),
            f"noise sigma = {self.sigma:.4g} (method {self.method}, window "
            f"{self.window:.4g} s), correlation time {self.correlation_time:.3g} s "
            f"(lag-one correlation {self.lag_one:.2f}), "
            f"{self.n_eff:.4g} effective of {self.n} samples",
        ]
        lines += [f"  - {w}" for w in self.warnings]
        return "\n".join(lines)


def signal_window(y: np.ndarray) -> int:
    """Odd window [samples]: 1/16 of the period at the 95 % power frequency of ``y``."""
    n = y.size
    x = np.arange(n, dtype=float)
    yd = y - np.polyval(np.polyfit(x, y, 1), x)
    p = np.abs(np.fft.rfft(yd)) ** 2
    p[0] = 0.0
    tot = p.sum()
    if tot <= 0.0:
        return MIN_WINDOW
    k95 = int(np.searchsorted(np.cumsum(p), 0.95 * tot)) + 1  # cycles per record
    w = int(n / (8.0 * k95))
    w = max(MIN_WINDOW, min(w, n // 4))
    return w if w % 2 else w - 1 if w > MIN_WINDOW else MIN_WINDOW


def _clean_blocks(r: np.ndarray, L: int) -> np.ndarray:
    """Residual in blocks of ``L`` samples, shape (m, L), keeping only the blocks whose robust
    scale is at most 1.5 times the median block scale: blocks around force kinks (reversals,
    break-away peaks), signal leaks and bursts of load-frame chatter are left out.
    """
    m = r.size // L
    B = r[: m * L].reshape(m, L)
    B = B - np.median(B, axis=1, keepdims=True)
    sc = np.median(np.abs(B), axis=1)
    med = np.median(sc)
    return B[sc <= 1.5 * med] if med > 0 else B


def _filtered_ar1_acf(w: int, rho: float, lags: int) -> np.ndarray:
    """Autocovariance at lags ``0..lags`` of ``(I - H) e`` (interior of the record) for
    unit-variance AR(1) noise ``e`` of lag-one correlation ``rho``; ``H``: the quintic
    Savitzky-Golay smoother over ``w`` samples.
    """
    c = -savgol_coeffs(w, _POLY)
    c[w // 2] += 1.0
    a = np.correlate(c, c, mode="full")  # filter autocorrelation, lags -(w-1)..w-1
    lag = np.arange(-(w - 1), w)
    return np.array([float(a @ rho ** np.abs(lag + k)) for k in range(lags + 1)])


def _block_acf(B: np.ndarray, lags: int) -> np.ndarray:
    """Robust autocorrelation at lags ``0..lags`` of the residual blocks ``B`` (shape (m, L)):
    ``(S - D)/(S + D)`` with ``S``, ``D`` the squared MAD scales of the sums and differences of
    samples ``k`` apart within a block (a kink, a spike or a chatter burst moves neither
    median; for Gaussian noise it is the ordinary correlation).
    """
    out = np.ones(lags + 1)
    for k in range(1, lags + 1):
        a, b = B[:, k:].ravel(), B[:, : B.shape[1] - k].ravel()
        S = float(np.median(np.abs(a + b - np.median(a + b)))) ** 2
        D = float(np.median(np.abs(a - b - np.median(a - b)))) ** 2
        out[k] = (S - D) / (S + D) if S + D > 0 else 0.0
    return out


def _ar1_match(w: int, rho_hat: np.ndarray) -> tuple[float, float, bool]:
    """``(rho, variance factor, capped)``: the AR(1) noise whose filtered residual has the
    autocorrelation ``rho_hat`` (lags ``0..K``, least squares over lags ``1..K``).
    """
    K = rho_hat.size - 1

    def cost(rho):
        m = _filtered_ar1_acf(w, rho, K)
        return float(np.sum((m[1:] / m[0] - rho_hat[1:]) ** 2))

    grid = np.linspace(-0.9, _RHO_MAX, 38)
    j = int(np.argmin([cost(r) for r in grid]))
    lo, hi = grid[max(j - 1, 0)], grid[min(j + 1, grid.size - 1)]
    rho = (
        float(minimize_scalar(cost, bounds=(lo, hi), method="bounded", options={"xatol": 1e-5}).x)
        if hi > lo
        else float(grid[j])
    )
    capped = rho > _RHO_MAX - 1e-3
    return rho, _filtered_ar1_acf(w, rho, 0)[0], capped


def _savgol_sigma(y: np.ndarray, w: int) -> tuple[float, float, bool]:
    """``(sigma, rho, capped)`` of AR(1) noise from the Savitzky-Golay residual."""
    r = y - savgol_filter(y, w, _POLY, mode="interp")
    L = max(w, 64)
    B = _clean_blocks(r, L if r.size >= 4 * L else max(r.size // 4, 8))
    s_r = _MAD * float(np.median(np.abs(B)))
    if s_r == 0.0:
        return 0.0, 0.0, False
    K = int(min(max(w // 2, 2), 6, B.shape[1] // 2))
    rho, var, capped = _ar1_match(w, _block_acf(B, K))
    return s_r / math.sqrt(var), rho, capped


def _correlation_time(B: np.ndarray, sigma: float) -> float:
    """Integrated autocorrelation time [samples] of the residual blocks ``B`` (shape (m, L)),
    averaged over the blocks, summed over Geyer's initial positive sequence (winsorised at
    4 sigma so that isolated spikes do not dominate).
    """
    if sigma <= 0.0 or B.size == 0:
        return 1.0
    x = np.clip(B, -4.0 * sigma, 4.0 * sigma)
    x = x - x.mean(axis=1, keepdims=True)
    L = x.shape[1]
    f = np.fft.rfft(x, 2 * L, axis=1)
    acf = np.fft.irfft(f * np.conj(f), axis=1)[:, :L].sum(axis=0)
    acf /= L - np.arange(L)  # unbiased lag estimates
    if acf[0] <= 0.0:
        return 1.0
    rho = acf / acf[0]
    tau = -1.0  # 1 + 2 sum_k>=1 rho_k = -1 + 2 sum_m (rho_2m + rho_2m+1)
    for m in range(L // 4):
        pair = rho[2 * m] + rho[2 * m + 1]
        if pair <= 0.0:
            break
        tau += 2.0 * pair
    return max(tau, 1.0)


def integrated_time(r: np.ndarray) -> float:
    """Integrated autocorrelation time of the residual sequence ``r`` [samples], ``>= 1``: the
    package's one estimate (Geyer's initial positive sequence on a robustly scaled residual),
    used by every fit and diagnosis to widen its stated uncertainty for correlated misfit.
    """
    r = np.asarray(r, float)
    if r.size < 8:
        return 1.0
    sc = 1.4826 * float(np.median(np.abs(r - np.median(r))))
    sc = sc if sc > 0 else float(np.std(r))
    return _correlation_time(r[None, :] - np.median(r), sc)


def difference_sigma(y) -> float:
    """Noise standard deviation of a sequence from its second differences: ``1.4826 MAD``
    of ``y[i-1] - 2 y[i] + y[i+1]`` divided by ``sqrt(6)`` (white noise of variance
    ``s**2`` gives second differences of variance ``6 s**2``; the MAD ignores a smooth signal's
    slowly varying curvature and isolated outliers). The package's one copy of this rule.
    """
    d2 = np.diff(np.asarray(y, float), 2)
    return _MAD * float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(6.0)


def estimate_noise(t, y, *, method: str = "auto", window: float | None = None) -> NoiseEstimate:
    """Estimate the noise standard deviation of one measured channel (see the module docstring).

    Parameters
    ----------
    t : array_like, shape (n,)
        Time [s], strictly increasing, (nearly) uniformly sampled. Not modified.
    y : array_like, shape (n,)
        The channel (displacement [m], force [N], ...), ``n >= 32``. Not modified.
    method : {"auto", "savgol", "difference"}, keyword-only
        ``"auto"`` (default) is ``"savgol"`` (reported as ``"savgol+ar1"``).
    window : float, optional, keyword-only
        Smoothing window [s], 9 samples to a quarter of the record. Default: ``1/8`` of the
        fastest loading period of ``y``. Give the measured channel's window when ``y`` is a
        fit residual (whose own spectrum says nothing about the loading).

    Returns
    -------
    NoiseEstimate
        ``sigma`` in the units of ``y``.

    Raises
    ------
    ValueError
        NaN/inf, unequal lengths, fewer than 32 samples, non-increasing ``t`` or an unknown
        ``method``.
    """
    if method not in ("auto", "savgol", "difference"):
        raise ValueError(f"method must be 'auto', 'savgol' or 'difference', got {method!r}")
    yy = check_magnitude("y", finite_array("y", y, ndim=1, min_size=32))
    tt = finite_array("t", t, ndim=1, min_size=32)
    n = same_length(t=tt, y=yy)
    tt = check_time(tt, n)
    dt_all = np.diff(tt)
    dt = float(np.median(dt_all))
    warns = []
    if np.max(np.abs(dt_all - dt)) > 0.05 * dt:
        warns.append(
            "the sampling is not uniform (time steps vary by more than 5 %); the "
            "estimate treats the samples as equally spaced"
        )
    if np.ptp(yy) == 0.0:
        return NoiseEstimate(
            0.0,
            "savgol+ar1" if method != "difference" else "difference",
            dt,
            n,
            float(n),
            dt,
            warnings=tuple(
                warns
                + ["y is constant: no noise is visible (a quantised or switched-off channel?)"]
            ),
        )
    if method == "difference":
        d2 = np.diff(yy, 2)
        s = difference_sigma(yy)
        tau = _correlation_time(_clean_blocks(d2, min(64, d2.size // 4)), s * math.sqrt(6.0))
        return NoiseEstimate(s, "difference", tau * dt, n, n / tau, dt, warnings=tuple(warns))
    if window is None:
        w = signal_window(yy)
    else:
        win = check_scalar("window", window, low=0.0, low_open=True)
        w = int(round(win / dt)) | 1
        if not MIN_WINDOW <= w <= n // 4:
            raise ValueError(
                f"window = {win:g} s is {w} samples; it must span "
                f"{MIN_WINDOW} to {n // 4} samples (a quarter of the record)"
            )
    s, rho, capped = _savgol_sigma(yy, w)
    w2 = max(MIN_WINDOW, (w // 2) | 1)
    if w2 < w and s > 0:
        s2, rho2, capped2 = _savgol_sigma(yy, w2)
        if abs(s2 - s) > 0.25 * s:
            # AR(1) noise reads the same through both windows (the model accounts for the
            # filter); what the longer window adds is signal (or misfit) leaking in
            use = s2 < s
            warns.append(
                f"the estimate changes from {s:.3g} to {s2:.3g} when the window is "
                f"halved ({w} -> {w2} samples): "
                + (
                    "the signal leaks into the longer window's residual; the halved window is used"
                    if use
                    else "the noise is not AR(1)-like on the window's time scale"
                )
            )
            if use:
                s, rho, capped, w = s2, rho2, capped2, w2
    if s == 0.0:
        warns.append(
            "more than half of the residual is exactly zero: the channel is "
            "quantised more coarsely than its noise, or noise-free"
        )
    if capped:
        warns.append(
            f"the noise is strongly correlated (lag-one correlation >= {_RHO_MAX}): "
            f"noise slower than the {w}-sample window is not counted and the level "
            "is uncertain"
        )
    tau = (1.0 + rho) / (1.0 - rho) if rho > 0.0 else 1.0
    return NoiseEstimate(
        s, "savgol+ar1", tau * dt, n, n / tau, w * dt, warnings=tuple(warns), lag_one=float(rho)
    )
