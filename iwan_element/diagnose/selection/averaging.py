"""Model-averaged predictions: the doubt about the model as well as about its parameters.

A diagnosis that is not sure which explanation holds predicts with all the probable ones
(Bayesian model averaging: Hoeting, Madigan, Raftery and Volinsky 1999, Statist. Sci.
14:382-417): each explanation ``M`` with posterior probability ``w_M`` predicts a Gaussian
``N(mu_M, s_M^2)`` per sample, ``mu_M`` its fitted model's prediction and ``s_M`` the
linearised spread of its parameters' posterior covariance (the Laplace covariance of
:mod:`.probabilities`); the prediction is their mixture, with mean
``sum w_M mu_M``, variance ``sum w_M (s_M^2 + mu_M^2) - mean^2`` and a central band of
probability ``level`` from the mixture's quantiles. Explanations below
:data:`MIN_WEIGHT` are left out (their weights renormalised), at most :data:`MAX_MEMBERS`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy.special import ndtr

from ...base.result_shape import ResultShape, panels
from ...base.serialize import json_safe
from ...base.validation import check_scalar

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["AveragedBand", "members", "mixture", "linear_spread", "MIN_WEIGHT", "MAX_MEMBERS"]

#: Explanations with a smaller probability do not take part in the average.
MIN_WEIGHT = 1e-3
#: Most explanations averaged.
MAX_MEMBERS = 6


def members(explanations) -> list:
    """``[(explanation, weight)]``: the probable explanations (:data:`MIN_WEIGHT`,
    :data:`MAX_MEMBERS`), weights renormalised to 1.
    """
    top = [e for e in explanations if e.probability >= MIN_WEIGHT][:MAX_MEMBERS]
    if not top:
        top = list(explanations[:1])
    s = sum(e.probability for e in top)
    return [(e, e.probability / s) for e in top]


def linear_spread(predict, theta, cov, lower=None, upper=None) -> tuple:
    """``(prediction, its standard deviation)`` of ``predict(theta)`` (an array) under
    ``theta ~ N(theta, cov)``, linearised by forward differences of a tenth of each
    parameter's standard deviation (stepping back at an upper bound); parameters without
    spread are skipped.
    """
    y0 = np.asarray(predict(theta), float)
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0)) if cov.size else np.zeros(0)
    cols, idx = [], []
    for j, s in enumerate(sd):
        if not s > 0:
            continue
        h = 0.1 * s
        th = np.array(theta, float)
        if upper is not None and th[j] + h > upper[j]:
            h = -h
        th[j] += h
        cols.append((np.asarray(predict(th), float) - y0) / h)
        idx.append(j)
    if not cols:
        return y0, np.zeros_like(y0)
    G = np.column_stack(cols)
    C = cov[np.ix_(idx, idx)]
    var = np.einsum("ij,jk,ik->i", G, C, G)
    return y0, np.sqrt(np.maximum(var, 0.0))


def mixture(
    weights, means, sds, level: float
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Mean, standard deviation and the central ``level`` band of a Gaussian mixture at each
    sample: ``weights`` (m,), ``means`` and ``sds`` (m, n). The band's ends are the
    mixture's quantiles (bisection on its distribution function).
    """
    w = np.asarray(weights, float)[:, None]
    mu, sd = np.asarray(means, float), np.maximum(np.asarray(sds, float), 0.0)
    mean = (w * mu).sum(axis=0)
    var = (w * (sd**2 + mu**2)).sum(axis=0) - mean**2
    std = np.sqrt(np.maximum(var, 0.0))
    tiny = 1e-12 * (np.abs(mu).max() + 1e-300)
    s = np.maximum(sd, tiny)

    def quantile(q):
        lo = (mu - 10 * s).min(axis=0)
        hi = (mu + 10 * s).max(axis=0)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            cdf = (w * ndtr((mid - mu) / s)).sum(axis=0)
            lo, hi = np.where(cdf < q, mid, lo), np.where(cdf < q, hi, mid)
        return 0.5 * (lo + hi)

    return mean, std, quantile(0.5 * (1 - level)), quantile(0.5 * (1 + level))


@dataclass(frozen=True, eq=False)
class AveragedBand(ResultShape):
    """A model-averaged prediction with its band (module docstring).

    Attributes
    ----------
    x : ndarray, shape (n,)
        Where it is predicted (time [s] or amplitude [m], ``x_label``).
    x_label : str
    channels : dict
        ``{name: {"mean", "std", "lower", "upper": ndarray (n,), "unit": str}}``: e.g.
        ``"force"`` [N], or ``"frequency"`` [Hz] and ``"damping_ratio"`` [-].
    members : tuple of (tuple of str, float)
        The explanations averaged (effect names, ``()`` the plain model) and their weights.
    member_means : dict
        ``{name: ndarray (m, n)}``: each explanation's own prediction.
    level : float
        Probability of the band ``lower .. upper``.
    """

    x: np.ndarray
    x_label: str
    channels: dict
    members: tuple
    member_means: dict
    level: float

    @property
    def plot_panels(self) -> int:  # type: ignore[override]  # read-only: one per channel
        """Number of axes :meth:`plot` draws on: one per channel."""
        return len(self.channels)

    @property
    def success(self) -> bool:
        """True when the prediction and its band are finite everywhere."""
        return bool(
            all(
                np.all(np.isfinite(c[k]))
                for c in self.channels.values()
                for k in ("mean", "lower", "upper")
            )
        )

    def to_dict(self) -> dict:
        """The averaged prediction as a JSON-safe dict (channels in their own units)."""
        return json_safe(
            {
                "x": self.x,
                "x_label": self.x_label,
                "level": self.level,
                "members": [{"effects": list(m), "weight": w} for m, w in self.members],
                "channels": self.channels,
                "warnings": list(self.warnings),
                "success": self.success,
            }
        )

    def report(self) -> str:
        """The explanations averaged and each channel's band width."""
        lines = [
            self.verdict(),
            f"Model-averaged prediction over {len(self.members)} "
            f"explanation(s), {self.x.size} points ({self.x_label})",
        ]
        for m, w in self.members:
            lines.append(f"  {' + '.join(m) or 'plain model'}: weight {w:.3g}")
        for name, c in self.channels.items():
            width = c["upper"] - c["lower"]
            lines.append(
                f"  {name} [{c['unit']}]: {100 * self.level:g} % band mean width "
                f"{float(np.mean(width)):.4g}, largest {float(np.max(width)):.4g}"
            )
        return "\n".join(lines + [f"  warning: {w}" for w in self.warnings])

    def _tables(self) -> list:
        cols = [self.x_label]
        data = [self.x]
        for name, c in self.channels.items():
            for k in ("mean", "std", "lower", "upper"):
                cols.append(f"{name} {k} [{c['unit']}]")
                data.append(c[k])
        return [
            ("prediction", tuple(cols), list(zip(*(map(float, a) for a in data)))),
            (
                "members",
                ("explanation", "weight [-]"),
                [(" + ".join(m) or "plain model", w) for m, w in self.members],
            ),
        ]

    def plot(self, ax=None) -> list[Artist]:
        """Each channel against ``x``: the mean, the band, each explanation's own mean."""
        axs = panels(ax, len(self.channels), figsize=(6, 3.2 * len(self.channels)))
        arts = []
        for a, (name, c) in zip(axs, self.channels.items()):
            arts.append(
                a.fill_between(
                    self.x,
                    c["lower"],
                    c["upper"],
                    color="C1",
                    alpha=0.3,
                    label=f"{100 * self.level:g} % band",
                )
            )
            arts += a.plot(self.x, c["mean"], "-", color="C3", lw=0.9, label="averaged")
            for (m, w), y in zip(self.members, self.member_means[name]):
                arts += a.plot(
                    self.x, y, ":", lw=0.6, label=f"{' + '.join(m) or 'plain'} ({w:.2g})"
                )
            a.set_xlabel(self.x_label)
            a.set_ylabel(f"{name} [{c['unit']}]")
            a.legend(fontsize=6)
        return arts


def band(x, x_label, parts, level, warnings=()) -> AveragedBand:
    """An :class:`AveragedBand` from ``parts = [(effects, weight, {channel: (mean, std,
    unit)})]``.
    """
    level = check_scalar("level", level, low=0.0, high=1.0, low_open=True, high_open=True)
    w = np.array([p[1] for p in parts])
    chans, means = {}, {}
    for name in parts[0][2]:
        mu = np.array([p[2][name][0] for p in parts])
        sd = np.array([p[2][name][1] for p in parts])
        m, s, lo, hi = mixture(w, mu, sd, level)
        ro = [a.copy() for a in (m, s, lo, hi)]
        for a in ro:
            a.setflags(write=False)
        chans[name] = dict(zip(("mean", "std", "lower", "upper"), ro), unit=parts[0][2][name][2])
        means[name] = mu
    x = np.array(x, float)
    x.setflags(write=False)
    return AveragedBand(
        x=x,
        x_label=x_label,
        channels=chans,
        members=tuple((tuple(p[0]), float(p[1])) for p in parts),
        member_means=means,
        level=float(level),
        warnings=tuple(warnings),
    )


__all__ += ["band"]
