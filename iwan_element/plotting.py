"""Plots of the joint's closed forms and of simulated or measured loops.

matplotlib is imported only when a function here is called. Every function takes
``ax=None`` (a new figure is made), returns the artists it drew and never calls
``plt.show()``.
"""
from __future__ import annotations

import numpy as np

from .closed_form import (masing_ascending, masing_descending, masing_loop,
                          normalized_backbone)
from .parameters import IwanParameters

__all__ = ["plot_normalized_loops", "plot_loop"]


def _pyplot():
    try:
        import matplotlib.pyplot as plt
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("plotting needs matplotlib: pip install matplotlib") from exc
    return plt


def _axes(ax):
    if ax is None:
        plt = _pyplot()
        _, ax = plt.subplots()
    return ax


def plot_normalized_loops(cases, *, s0: float = 1.0, step: float = 0.002, ax=None):
    """Draw normalised hysteresis loops ``f(s), f_u(s), f_d(s)`` (paper eqs. 12, 13, 15; Fig. 3).

    Parameters
    ----------
    cases : sequence of (beta, chi)
        Parameter pairs, one loop each (any chi > -1; beta < 0 warns as non-physical).
    s0 : float, keyword-only
        Normalised amplitude of the loop.
    step : float, keyword-only
        Grid step of ``s`` in ``[-s0, s0]`` (the paper uses 0.002).
    ax : matplotlib Axes, optional

    Returns
    -------
    list of matplotlib.lines.Line2D
        Three lines per case: virgin curve, descending and ascending branch.
    """
    ax = _axes(ax)
    s = np.arange(-s0, s0 + 0.5 * step, step)
    lines = []
    for beta, chi in cases:
        label = f"beta={beta:g}, chi={chi:g}"
        f = normalized_backbone(s[s >= 0], chi, beta)
        (l1,) = ax.plot(s[s >= 0], f, "-", lw=1.0, label=f"{label}: f(s)")
        c = l1.get_color()
        (l2,) = ax.plot(s, masing_descending(s, s0, chi, beta), "--", color=c, lw=1.2,
                        label=f"{label}: f_u(s)")
        (l3,) = ax.plot(s, masing_ascending(s, s0, chi, beta), ":", color=c, lw=1.5,
                        label=f"{label}: f_d(s)")
        lines += [l1, l2, l3]
    ax.set_xlabel("s = u / phi_max")
    ax.set_ylabel("f = F / Fs")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return lines


def plot_loop(u0: float, params: IwanParameters, *, n: int = 401, ax=None,
              label: str | None = None):
    """Draw the steady Masing loop of amplitude ``u0`` [m] in mm and kN.

    Returns
    -------
    list of matplotlib.lines.Line2D
    """
    ax = _axes(ax)
    u, F = masing_loop(u0, params, n=n)
    lines = ax.plot(u * 1e3, F * 1e-3, label=label)
    ax.set_xlabel("displacement [mm]")
    ax.set_ylabel("force [kN]")
    ax.grid(True, alpha=0.3)
    return lines
