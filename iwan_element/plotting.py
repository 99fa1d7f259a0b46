"""Plots of the joint's closed forms and of simulated or measured loops.

matplotlib is imported only when a function here is called. Every function takes
``ax=None`` (a new figure is made), returns the artists it drew and never calls
``plt.show()``.
"""

from __future__ import annotations

import textwrap
from typing import TYPE_CHECKING

import numpy as np

from .base.result_shape import axes_or_new
from .base.validation import check_int, finite_array, same_length
from .core.closed_form import dissipation as cycle_dissipation
from .core.closed_form import (
    dissipation_slope,
    force_amplitude,
    masing_ascending,
    masing_descending,
    masing_loop,
    normalized_backbone,
)
from .core.parameters import IwanParameters

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

__all__ = [
    "plot_normalized_loops",
    "plot_loop",
    "plot_fitted_loops",
    "plot_dissipation_fit",
    "fit_figure",
]


def plot_normalized_loops(cases, *, s0: float = 1.0, step: float = 0.002, ax=None) -> list[Line2D]:
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
    ax = axes_or_new(ax)
    s = np.arange(-s0, s0 + 0.5 * step, step)
    lines = []
    for beta, chi in cases:
        label = f"beta={beta:g}, chi={chi:g}"
        f = normalized_backbone(s[s >= 0], chi, beta)
        (l1,) = ax.plot(s[s >= 0], f, "-", lw=1.0, label=f"{label}: f(s)")
        c = l1.get_color()
        (l2,) = ax.plot(
            s, masing_descending(s, s0, chi, beta), "--", color=c, lw=1.2, label=f"{label}: f_u(s)"
        )
        (l3,) = ax.plot(
            s, masing_ascending(s, s0, chi, beta), ":", color=c, lw=1.5, label=f"{label}: f_d(s)"
        )
        lines += [l1, l2, l3]
    ax.set_xlabel("s = u / phi_max")
    ax.set_ylabel("f = F / Fs")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return lines


def plot_loop(
    amplitude: float, params: IwanParameters, *, n: int = 401, ax=None, label: str | None = None
) -> list[Line2D]:
    """Draw the steady Masing loop of amplitude ``u0`` [m] in mm and kN.

    Returns
    -------
    list of matplotlib.lines.Line2D
    """
    ax = axes_or_new(ax)
    u, F = masing_loop(amplitude, params, n=n)
    lines = ax.plot(u * 1e3, F * 1e-3, label=label)
    ax.set_xlabel("displacement [mm]")
    ax.set_ylabel("force [kN]")
    ax.grid(True, alpha=0.3)
    return lines


# ------------------------------------------------------------------ identification (fit.py)


def _fit_params(params) -> IwanParameters:
    p = getattr(params, "joint", params)  # a FitResult or IwanParameters
    if not isinstance(p, IwanParameters):
        raise ValueError(
            f"params must be IwanParameters or a FitResult, got {type(params).__name__}"
        )
    return p


def plot_fitted_loops(u, F, params, *, ax=None, max_points: int = 20000) -> list[Line2D]:
    """Measured against fitted force-displacement loops, in mm and kN (paper Fig. 8).

    The fitted force is the exact :class:`~iwan_element.IwanJoint` driven by the measured
    displacement from the virgin state.

    Parameters
    ----------
    u, F : array_like, shape (n,)
        Measured displacement [m] and force [N]. Not modified.
    params : IwanParameters or FitResult
        The fitted joint.
    ax : matplotlib Axes, optional, keyword-only
    max_points : int, keyword-only
        Most points drawn per curve (evenly thinned), ``>= 10``.

    Returns
    -------
    list of matplotlib.lines.Line2D
        ``[measured, fitted]``.
    """
    from .core.joint import IwanJoint

    p = _fit_params(params)
    uu = finite_array("u", u, ndim=1, min_size=2)
    FF = finite_array("F", F, ndim=1, min_size=2)
    same_length(u=uu, F=FF)
    max_points = check_int("max_points", max_points, 10)
    F_fit = IwanJoint(p).force_history(uu)
    step = max(1, -(-uu.size // max_points))
    ax = axes_or_new(ax)
    (meas,) = ax.plot(
        uu[::step] * 1e3, FF[::step] * 1e-3, ".", ms=1.5, color="0.55", label="measured"
    )
    (fit,) = ax.plot(
        uu[::step] * 1e3,
        F_fit[::step] * 1e-3,
        "-",
        lw=1.0,
        color="C3",
        label=(
            f"Iwan fit: Fs={p.Fs * 1e-3:.4g} kN, KT={p.KT * 1e-6:.4g} kN/mm, "
            f"chi={p.chi:.3f}, beta={p.beta:.3f}"
        ),
    )
    ax.set_xlabel("displacement [mm]")
    ax.set_ylabel("force [kN]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    return [meas, fit]


def plot_dissipation_fit(
    force, dissipation, params, *, ax=None, slope: bool = True, n: int = 200
) -> list[Artist]:
    """Log-log dissipation per cycle against force amplitude with the fitted curve (Fig. 7).

    The curve is the exact relation ``(F0(u0), D(u0))`` of the fitted joint (vertical at
    ``F0 = Fs`` in macroslip); with ``slope=True`` its local slope ``d ln D / d ln F0`` (paper eq.
    21, which tends to ``chi + 3`` only as ``F0 -> 0``) is drawn on a second y axis with the
    asymptote.

    Parameters
    ----------
    force, dissipation : array_like, shape (m,)
        Measured force amplitudes ``F0`` [N] and dissipation per cycle ``D`` [J], ``> 0``
        (as :func:`~iwan_element.fit_dissipation` takes them). Not modified.
    params : IwanParameters or FitResult
    ax : matplotlib Axes, optional, keyword-only
    slope : bool, keyword-only
    n : int, keyword-only
        Points on the fitted curve, ``>= 10``.

    Returns
    -------
    list of matplotlib artists
        ``[data, curve]`` plus ``[slope, asymptote]`` with ``slope=True`` (those live on
        ``ax.twinx()``).
    """
    p = _fit_params(params)
    F0a = finite_array("force", force, ndim=1)
    Da = finite_array("dissipation", dissipation, ndim=1)
    same_length(force=F0a, dissipation=Da)
    if np.any(F0a <= 0) or np.any(Da <= 0):
        raise ValueError("force and dissipation must be > 0 for a log-log plot")
    n = check_int("n", n, 10)
    lo = 0.5 * min(F0a.min() / p.KT, p.phi_max)
    u_grid = np.geomspace(lo, p.phi_max * (1 - 1e-9), n)
    ax = axes_or_new(ax)
    (data,) = ax.loglog(
        F0a * 1e-3, Da * 1e3, "o", ms=4, mfc="none", color="k", label="measured cycles"
    )
    F_curve = force_amplitude(u_grid, p)
    D_curve = np.asarray(cycle_dissipation(u_grid, p))
    if Da.max() > D_curve[-1]:  # macroslip: F0 stays at Fs while D keeps growing
        F_curve = np.append(F_curve, p.Fs)
        D_curve = np.append(D_curve, Da.max())
    (curve,) = ax.loglog(F_curve * 1e-3, D_curve * 1e3, "-", color="C3", label="Iwan fit (exact)")
    ax.set_xlabel("force amplitude F0 [kN]")
    ax.set_ylabel("dissipation per cycle D [mJ]")
    ax.grid(True, which="both", alpha=0.3)
    artists = [data, curve]
    if slope:
        ax2 = ax.twinx()
        (sl,) = ax2.semilogx(
            force_amplitude(u_grid, p) * 1e-3,
            dissipation_slope(u_grid, p),
            "--",
            color="C0",
            lw=1.0,
            label="local slope d ln D / d ln F0",
        )
        asym = ax2.axhline(
            p.chi + 3.0, color="C0", lw=0.8, ls=":", label=f"chi + 3 = {p.chi + 3:.3f} (F0 -> 0)"
        )
        ax2.set_ylabel("local slope [-]")
        ax2.set_ylim(max(0.0, p.chi + 2.5), p.chi + 5.0)
        artists += [sl, asym]
        h1, l1 = ax.get_legend_handles_labels()
        h2, l2 = ax2.get_legend_handles_labels()
        ax.legend(h1 + h2, l1 + l2, fontsize=7, loc="upper left")
    else:
        ax.legend(fontsize=7, loc="upper left")
    return artists


def fit_figure(data, result) -> tuple[Figure, list[str]]:
    """The figure ``iwan-element fit --plot`` writes: the fit's own plot
    (:meth:`FitResult.plot`: a loop fit's model and data with the fitted offsets removed, as
    in Python), beside the dissipation per cycle against the force amplitude (measured
    cycles and the fitted joint's closed form; a dissipation fit's own plot, beside its loops).
    When the record has too few usable cycles for the dissipation panel, the panel says
    why instead of vanishing.

    Returns
    -------
    (matplotlib.figure.Figure, list of str)
        The figure and notes for the command's output (a panel left empty and why).
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 4.5), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    notes = []
    if result.method == "loops":
        result.plot(ax=ax1)
        try:
            table = data.amplitude_table(min_cycles=1)  # every closed cycle, one or more
        except ValueError as exc:
            table, why = None, str(exc)
        if table is not None:
            plot_dissipation_fit(table["F0"], table["D"], result, ax=ax2)
        else:
            ax2.text(
                0.5,
                0.5,
                "no dissipation panel:\n" + "\n".join(textwrap.wrap(why, width=50)),
                ha="center",
                va="center",
                fontsize=8,
                transform=ax2.transAxes,
            )
            ax2.set_axis_off()
            notes.append(f"--plot: no dissipation panel ({why})")
    else:
        plot_fitted_loops(data.u, data.F, result, ax=ax1)
        result.plot(ax=ax2)
    ax1.set_title("measured vs fitted loops", fontsize=9)
    ax2.set_title("dissipation per cycle", fontsize=9)
    return fig, notes
