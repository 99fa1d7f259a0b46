"""The result of a campaign fit, :class:`CampaignFit`: law coefficients with their
uncertainty, the per-record agreement table, and the methods that predict and cross-check
(:mod:`.predict`); :mod:`.assemble` builds it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ...base.result_shape import ResultShape, axes_or_new, table_lines, unit_label
from ...base.serialize import json_safe
from ...fitting import ParameterTable
from ..selection.probable import Probable
from . import model as CM
from .holdout import leave_one_out as campaign_leave_one_out
from .predict import condition_vector
from .predict import predict as campaign_predict
from .probability import campaign_band

if TYPE_CHECKING:
    from matplotlib.artist import Artist

    from ..selection.averaging import AveragedBand
    from .holdout import LeaveOneOut
    from .predict import CampaignPrediction

__all__ = ["CampaignFit", "law_at"]


def law_at(model, theta, cov_int, x) -> tuple[dict[str, float], dict[str, float]]:
    """Law values and their standard errors at conditions ``x``."""
    vals = model.law_values(theta, x)
    se = {}
    for q in model.qnames:
        a = CM.design(np.atleast_2d(x), model.cnames, model.laws[q], model.centre, model.cscale)[0]
        sl = model.slices[q]
        se[q] = math.sqrt(max(float(a @ cov_int[sl, sl] @ a), 0.0)) * model.qscale[q]
    return vals, se


@dataclass(frozen=True, eq=False)
class CampaignFit(Probable, ResultShape):
    """What :func:`~iwan_element.diagnose.campaign.fit_campaign` returns.

    Attributes
    ----------
    records : tuple of str
        The records fitted (those diagnosed), in order.
    condition_names : tuple of str
    effects : tuple of str
        The campaign's effect stack (innermost first); ``effects_from`` says how it was chosen.
    laws : dict
        ``{quantity: conditions}``: each quantity is ``a + sum_c b_c x_c`` over these.
    units : dict
        Unit of each quantity.
    params : ParameterTable
        The law coefficients ``"quantity:term"`` (term ``"1"`` for ``a``, a condition name
        for its ``b_c``) with their standard errors (delta method), units and verdicts
        (:func:`iwan_element.fitting.verdict`; a slope of zero is a valid finding, so only a
        finite standard error, no relative precision, is asked).
    coefficients, stderr : dict
        (properties) ``{quantity: {"1": a, condition: b_c}}`` and their standard errors,
        from ``params``.
    covariance : ndarray
        Of all coefficients, in the order of ``coefficient_labels`` (``"quantity:term"``).
    scatter : dict
        Record-to-record scatter about the laws (standard deviation per quantity, the slip
        force as ``"ln Fs"``: a relative scatter), from each record refitted alone with the
        campaign's stack; empty when ``scatter=False``. It is the part of the device the
        conditions do not predict; :meth:`predict` carries it in its band.
    stderr_scatter : dict
        The coefficients' standard errors with that scatter: the delta method's (``stderr``,
        which sees each record's noise only) plus the generalised least-squares covariance
        of the laws over records that scatter by ``scatter`` (docs/campaign.md section 6);
        empty when ``scatter=False``.
    rows : tuple of dict
        Per record: conditions, effects named on its own, those the stack adds (``missing``)
        or lacks (``extra``), band misfit [N] of its own fit and of the campaign model and
        their ratio, force offset [N], start [m], law values and the z-scores of its own
        estimates against the laws.
    converged, success : bool
        The fit converged; and (the one rule of docs/guards.md) every law coefficient is
        identified (:meth:`failure_reasons` says why not).
    message : str
    nfev : int
    wall_time : float
        [s], with ``details["times"]`` split into diagnoses, joint fit and uncertainty.
    warnings : tuple of str
    details : dict
    explanations : tuple of Explanation
        The explanations over all records together with their probabilities
        (:mod:`.probability`): ``probabilities``, ``effect_probability(name)``.
    alternatives : dict
        ``{explanation: CampaignFit}``: the campaign model of every other probable
        explanation, which :meth:`averaged_band` mixes in.
    """

    records: tuple
    condition_names: tuple
    effects: tuple
    effects_from: str
    laws: dict
    units: dict
    params: ParameterTable
    covariance: np.ndarray
    coefficient_labels: tuple
    rows: tuple
    scatter: dict
    stderr_scatter: dict
    converged: bool
    success: bool
    message: str
    nfev: int
    wall_time: float
    details: dict = field(default_factory=dict)
    _state: dict = field(default_factory=dict, repr=False)
    explanations: tuple = ()
    alternatives: dict = field(default_factory=dict)

    def averaged_band(self, conditions, t, u, *, level: float = 0.95, **options) -> AveragedBand:
        """The force at ``conditions`` (tested or not) under ``(t, u)`` averaged over the
        probable explanations, each campaign model with its own band (:meth:`predict`,
        ``options`` passed on): :class:`~iwan_element.diagnose.averaging.AveragedBand`.
        """
        return campaign_band(self, conditions, t, u, level=level, **options)

    def _tables(self) -> list:
        base = super()._tables()
        return base[:1] + self.probability_tables() + base[1:]

    def _nested(self, what: str) -> dict:
        out: dict[str, dict] = {}
        for p in self.params.parameters:
            q, term = p.name.split(":", 1)
            out.setdefault(q, {})[term] = getattr(p, what)
        return out

    @property
    def coefficients(self) -> dict:
        """``{quantity: {"1": a, condition: b_c}}`` (from ``params``)."""
        return self._nested("value")

    @property
    def stderr(self) -> dict:
        """The coefficients' standard errors, nested as :attr:`coefficients`."""
        return self._nested("stderr")

    def law(self, quantity: str, conditions: dict) -> tuple[float, float]:
        """``(value, stderr)`` of one quantity's law at ``conditions``."""
        st = self._state
        x = condition_vector(self.condition_names, conditions)
        if quantity not in self.laws:
            raise ValueError(f"quantity must be one of {list(self.laws)}, got {quantity!r}")
        vals, se = law_at(st["model"], st["theta"], st["cov_int"], x)
        return vals[quantity], se[quantity]

    def predict(
        self,
        conditions,
        t,
        u,
        *,
        F0: float = 0.0,
        start: float = 0.0,
        level: float = 0.95,
        draws: int = 64,
        rng=None,
        scatter: bool = True,
    ) -> CampaignPrediction:
        """Force history of the device at ``conditions`` (tested or not) under the drive
        ``(t, u)``, with a band from the law coefficients' uncertainty.

        Parameters
        ----------
        conditions : dict
            The campaign's condition names, finite numbers.
        t, u : array_like, shape (n,)
            Time [s] and displacement [m] from the joint's rest position, ``n >= 3``.
        F0 : float, keyword-only
            Force offset [N] added (a sensor zero, not a device property).
        start : float, keyword-only
            Joint's starting state [m] (path ``0 -> start -> u[0]``; 0: virgin rest).
        level : float, keyword-only
            Probability of the band, in (0, 1).
        draws : int, keyword-only
            Coefficient draws from their normal distribution for the band, ``>= 8``.
        rng : numpy.random.Generator or int, optional, keyword-only
            Source of the draws (default seed 0: reproducible).
        scatter : bool, keyword-only
            Add to each draw a record-to-record deviation from the scatter the records show
            about the laws (:attr:`scatter`; default True): the band then says how far a new
            test at these conditions may fall from the law, not only how well the law is
            known.

        Returns
        -------
        CampaignPrediction
            ``.force``, ``.lower``, ``.upper`` [N] and ``warnings`` (e.g. extrapolation).
        """
        return campaign_predict(
            self,
            conditions,
            t,
            u,
            F0=F0,
            start=start,
            level=level,
            draws=draws,
            rng=rng,
            scatter=scatter,
        )

    def leave_one_out(
        self,
        *,
        refit: str = "step",
        jobs: int = 1,
        client=None,
        progress: bool = False,
        max_nfev: int = 20,
        coverage: bool = False,
        draws: int = 32,
        level: float = 0.95,
        seed: int = 0,
    ) -> LeaveOneOut:
        """Predict each record from the campaign fitted without it.

        The device comes from the laws fitted to the other records; the record's nuisances
        (force offset, starting state) are fitted to it with the device held. Per record:
        the band misfit [N] (``|F| < 0.25 max|F|``) of that prediction over the record's own
        fit's (its diagnosis), target at most 1.5 on at least 80 % of the records.

        Parameters
        ----------
        refit : {"step", "full"}, keyword-only
            ``"step"`` (default): one Gauss-Newton step from the full fit on the weighted
            normal equations without the record (no new fit); ``"full"``: a warm-started
            least-squares refit per record.
        jobs : int, keyword-only
            Local processes for ``"full"`` (1: in this process).
        client : dask.distributed.Client, optional, keyword-only
            Run the ``"full"`` refits on this Dask cluster instead.
        progress : bool, keyword-only
            tqdm progress bar over the refits (``"full"``).
        max_nfev : int, keyword-only
            Most objective evaluations per refit (``"full"``), ``>= 1``.
        coverage : bool, keyword-only
            Also state, per record, the share of its band samples (``|F| < 0.25 max|F|``, at
            its fitted samples) inside the ``level`` prediction band, with the scatter read
            from the other records and with the coefficients' uncertainty only.
        draws : int, keyword-only
            Devices drawn per record and per band for ``coverage``, ``>= 8``.
        level : float, keyword-only
            Probability of the band, in (0, 1).
        seed : int, keyword-only
            Seed of the draws (one stream per record), ``>= 0``.

        Returns
        -------
        LeaveOneOut
            ``rows`` (record, own and predicted band misfit [N], ratio), ``share_within``,
            ``success``, ``report()``, ``to_dict()``, ``plot()``, ``warnings``.
        """
        return campaign_leave_one_out(
            self,
            refit=refit,
            jobs=jobs,
            client=client,
            progress=progress,
            max_nfev=max_nfev,
            coverage=coverage,
            draws=draws,
            level=level,
            seed=seed,
        )

    def failure_reasons(self) -> tuple:
        """Why ``success`` is False (empty when it is True), in a tester's words."""
        if self.success:
            return ()
        out = [] if self.converged else [f"the joint fit did not converge ({self.message})"]
        bad = [k for k, p in self.params.items() if not p.identified]
        if bad:
            out.append(
                f"law coefficients {', '.join(bad)} are not identified by the records "
                "(see the warnings: a clipped law, or too few records or conditions)"
            )
        return tuple(out) or super().failure_reasons()

    def report(self) -> str:
        """Laws with their coefficients, the per-record table, warnings and times."""
        tm = self.details["times"]
        lines = [
            self.verdict(),
            f"Campaign fit of {len(self.records)} records: stack "
            f"{' + '.join(self.effects) or 'Iwan'} ({self.effects_from}); "
            f"{'converged' if self.converged else 'NOT converged'}, {self.nfev} "
            f"evaluations; {self.wall_time:.1f} s (diagnoses {tm['diagnoses']:.1f} s, "
            f"joint fit {tm['joint_fit']:.1f} s, uncertainty {tm['uncertainty']:.1f} s)",
            "  laws (coefficient +- standard error (with the record scatter)):",
        ]
        for q, terms in self.coefficients.items():
            parts = [
                f"{c:.5g} +- {self.stderr[q][k]:.2g}"
                + (f" ({self.stderr_scatter[q][k]:.2g})" if self.stderr_scatter else "")
                + ("" if k == "1" else f" x {k}")
                for k, c in terms.items()
            ]
            lines.append(f"    {q} [{unit_label(self.units[q])}] = " + " + ".join(parts))
        if self.scatter:
            lines.append(
                "  record-to-record scatter about the laws (standard deviation): "
                + ", ".join(f"{q} {v:.3g}" for q, v in self.scatter.items())
            )
        lines += table_lines(
            [
                ("record", "<26"),
                ("named", "<40"),
                ("own band", "9.4g"),
                ("campaign", "9.4g"),
                ("ratio", "6.2f"),
            ],
            [
                [r[k] for k in ("record", "named", "band_own", "band_campaign", "band_ratio")]
                for r in self.rows
            ],
        )
        lines += self.probability_lines() + [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-safe dict (NaN becomes None)."""
        return json_safe(
            {"params": self.params.to_dict()}
            | {
                k: getattr(self, k)
                for k in (
                    "records",
                    "condition_names",
                    "effects",
                    "effects_from",
                    "laws",
                    "units",
                    "coefficients",
                    "stderr",
                    "covariance",
                    "coefficient_labels",
                    "rows",
                    "scatter",
                    "stderr_scatter",
                    "converged",
                    "success",
                    "message",
                    "nfev",
                    "wall_time",
                    "warnings",
                    "details",
                )
            }
            | {
                "failure_reasons": list(self.failure_reasons()),
                "probabilities": self.probabilities_dict(),
            }
        )

    def plot(self, ax=None, *, quantity: str = "Fs", condition: str | None = None) -> list[Artist]:
        """One quantity against one condition: the records' own estimates (with their
        standard errors) and the law with its 95 % band, the other conditions held at their
        mean over the records.

        Parameters
        ----------
        ax : matplotlib Axes, optional
        quantity : str, keyword-only
            A key of :attr:`laws` (default ``"Fs"``).
        condition : str, optional, keyword-only
            A condition name (default: the first one).

        Returns
        -------
        list
            The matplotlib artists drawn.
        """
        if quantity not in self.laws:
            raise ValueError(f"quantity must be one of {list(self.laws)}, got {quantity!r}")
        condition = self.condition_names[0] if condition is None else condition
        if condition not in self.condition_names:
            raise ValueError(
                f"condition must be one of {list(self.condition_names)}, got {condition!r}"
            )
        ax = axes_or_new(ax)
        st = self._state
        model, j = st["model"], self.condition_names.index(condition)
        x_rec = model.X[:, j]
        est = np.array([p["estimates"].get(quantity, np.nan) for p in st["preps"]])
        err = np.array([p["stderr"].get(quantity, np.nan) for p in st["preps"]])
        eb = ax.errorbar(
            x_rec,
            est,
            yerr=np.where(np.isfinite(err), err, 0.0),
            fmt="o",
            ms=4,
            label="records (own fit)",
        )
        arts = [eb[0], *eb[2]]
        grid = np.linspace(x_rec.min(), x_rec.max(), 50)
        mid, lo, hi = [], [], []
        for g in grid:
            x = model.centre.copy()
            x[j] = g
            v, s = law_at(model, st["theta"], st["cov_int"], x)
            mid.append(v[quantity])
            lo.append(v[quantity] - 1.96 * s[quantity])
            hi.append(v[quantity] + 1.96 * s[quantity])
        arts += ax.plot(grid, mid, "-", label="campaign law")
        arts.append(ax.fill_between(grid, lo, hi, alpha=0.3, label="95 % band"))
        ax.set_xlabel(condition)
        ax.set_ylabel(f"{quantity} [{self.units[quantity]}]")
        ax.legend(fontsize=7)
        return arts
