"""Diagnose many records at once: a test campaign on local processes or a Dask cluster.

:func:`diagnose_many` runs :func:`~iwan_element.diagnose` on every record through
:func:`~iwan_element.ensemble.run_ensemble` (one task per record: local processes by default,
``"serial"``, any ``concurrent.futures`` executor or a ``dask.distributed.Client``), with a
tqdm progress bar when asked, and returns one :class:`BatchDiagnosis`: a table (one row per
record) and the full JSON of every diagnosis. A record that cannot be diagnosed (refused as
bad input, or failing) keeps its row with the reason and does not stop the others.

The table's band misfit is the RMS force residual where ``|F| < band * max|F|`` (default
0.25): the part of the cycle where a gap or a break-away acts, which the whole-record NRMSE
dilutes (the damper benchmark's measure).
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ...base.result_shape import ResultShape, panels
from ...base.validation import check_scalar, finite_array
from ...ensemble import run_ensemble
from .diagnosis import diagnose

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = [
    "diagnose_many",
    "BatchDiagnosis",
    "band_misfit",
    "check_records",
    "check_options",
    "executor_for",
    "diagnosed",
]

#: Table columns of :class:`BatchDiagnosis` (besides the record's name).
COLUMNS = (
    "samples",
    "named",
    "error_before",
    "error_after",
    "band_before",
    "band_after",
    "band_ratio",
    "noise_sigma",
    "success",
    "seconds",
    "status",
)


def diagnosed(row: dict) -> bool:
    """The record's diagnosis ran (its status is its verdict, not a refusal or a failure)."""
    return not str(row["status"]).startswith(("refused", "failed"))


def band_misfit(F, F_model, band: float) -> float:
    """RMS of ``F - F_model`` [N] where ``|F| < band * max|F|``."""
    F = np.asarray(F, dtype=float)
    mask = np.abs(F) < band * np.abs(F).max()
    if not mask.any():
        return math.nan
    return float(np.sqrt(np.mean((F - np.asarray(F_model, dtype=float))[mask] ** 2)))


def _diagnose_task(params, rng):
    """One record (module level, so that worker processes can import it)."""
    del rng  # the diagnosis is seeded by its own ``seed``
    t0 = time.perf_counter()
    try:
        d = diagnose(params["t"], params["u"], params["F"], **params["options"])
    except ValueError as exc:  # a refusal is a result, reported as such
        return {
            "status": f"refused: {' '.join(str(exc).split())}",
            "json": "null",
            "seconds": time.perf_counter() - t0,
        }
    bb = band_misfit(d.F, d.force_before, params["band"])
    ba = band_misfit(d.F, d.force_after, params["band"])
    return {
        "status": "usable" if d.success else "NOT usable",
        "samples": int(d.F.size),
        "named": " + ".join(d.effects) or "none",
        "error_before": d.error_before,
        "error_after": d.error_after,
        "band_before": bb,
        "band_after": ba,
        "band_ratio": ba / bb if bb > 0 else math.nan,
        "noise_sigma": d.noise_sigma,
        "success": bool(d.success),
        "seconds": time.perf_counter() - t0,
        "json": json.dumps(d.to_dict()),
    }


def check_records(records, names) -> tuple[list[tuple[NDArray[np.float64], ...]], list[str]]:
    """The records as triples of finite arrays and their labels (``names`` or ``record i``)."""
    try:
        recs = list(records)
    except TypeError:
        raise ValueError("records must be a sequence of (t, u, F) triples") from None
    if not recs:
        raise ValueError("records must hold at least one (t, u, F) triple")
    out = []
    for i, r in enumerate(recs):
        try:
            t, u, F = r
        except (TypeError, ValueError):
            raise ValueError(f"records[{i}] must be a triple (t [s], u [m], F [N])") from None
        out.append(tuple(finite_array(f"records[{i}].{k}", a) for k, a in zip("tuF", (t, u, F))))
    if names is None:
        names = [f"record {i}" for i in range(len(out))]
    names = [str(s) for s in names]
    if len(names) != len(out):
        raise ValueError(f"names must have one entry per record ({len(out)}), got {len(names)}")
    return out, names


def check_options(options) -> dict[str, Any]:
    """``options`` as a dict, every key an option of :func:`~iwan_element.diagnose`."""
    unknown = sorted(set(options) - set(diagnose.__kwdefaults__ or ()))
    if unknown:
        raise ValueError(
            f"options {unknown} are not options of diagnose(); it takes "
            f"{sorted(diagnose.__kwdefaults__ or ())}"
        )
    return dict(options)


def executor_for(jobs: int, client) -> Any:
    """The executor of ``run_ensemble`` for ``jobs`` local processes or a Dask ``client``
    (``"serial"`` for one job); the caller shuts down a process pool it gets.
    """
    if client is not None:
        return client
    if jobs == 1:
        return "serial"
    from concurrent.futures import ProcessPoolExecutor

    return ProcessPoolExecutor(jobs)


def diagnose_many(
    records,
    *,
    names=None,
    executor=None,
    progress: bool = False,
    band: float = 0.25,
    seed=None,
    **options,
) -> BatchDiagnosis:
    """Diagnose every record of a campaign, on local processes, serially or on Dask.

    Parameters
    ----------
    records : sequence of (t, u, F)
        Each a triple of arrays as :func:`~iwan_element.diagnose` takes them: time [s],
        displacement [m], force [N]. Not modified.
    names : sequence of str, optional, keyword-only
        A label per record (file names, test conditions); default ``"record i"``.
    executor : None, "serial", concurrent.futures.Executor or dask.distributed.Client, keyword-only
        Where the records run (see :func:`~iwan_element.ensemble.run_ensemble`); default local
        processes, one per core.
    progress : bool, keyword-only
        A tqdm progress bar over the records (needs tqdm).
    band : float, keyword-only
        Fraction of ``max|F|`` below which the table's band misfit is measured, in (0, 1]
        (default 0.25).
    seed : int, optional, keyword-only
        Root seed of the ensemble run (the diagnoses themselves are seeded by ``options``'
        ``seed``, default 0, so a record gives the same result alone and in a batch).
    **options
        Keyword options of :func:`~iwan_element.diagnose`, the same for every record (for
        example ``lowpass=20``, ``max_effects=3``).

    Returns
    -------
    BatchDiagnosis

    Raises
    ------
    ValueError
        Records that are not triples of finite arrays, names of the wrong length, an option
        :func:`~iwan_element.diagnose` does not take, a band outside (0, 1].
    """
    recs, labels = check_records(records, names)
    band = check_scalar("band", band, low=0.0, high=1.0, low_open=True)
    opts = check_options(options)
    sets = [{"t": t, "u": u, "F": F, "options": opts, "band": band} for t, u, F in recs]
    res = run_ensemble(_diagnose_task, sets, executor=executor, seed=seed, progress=progress)
    rows, docs, warns = [], [], list(res.warnings)
    for name, row, err in zip(labels, res.rows, _errors_by_index(res)):
        out = {"record": name}
        out.update({k: row.get(k, math.nan) for k in COLUMNS})
        if err is not None:
            out["status"] = f"failed: {err}"
        docs.append(None if err is not None else json.loads(row.get("json", "null")))
        rows.append(out)
    n_bad = sum(not diagnosed(r) for r in rows)
    if n_bad:
        warns.append(f"{n_bad} of {len(rows)} records were not diagnosed (see the status column)")
    return BatchDiagnosis(
        rows=tuple(rows),
        diagnoses=tuple(docs),
        options=opts,
        executor=res.executor,
        wall_time=res.wall_time,
        warnings=tuple(warns),
    )


def _errors_by_index(res):
    by = {e.index: e.message for e in res.errors}
    return [by.get(i) for i in range(len(res.rows))]


@dataclass(frozen=True, eq=False)
class BatchDiagnosis(ResultShape):
    """What :func:`diagnose_many` returns: one table row and one diagnosis per record.

    Attributes
    ----------
    rows : tuple of dict
        Per record: ``record`` (its name), ``samples``, ``named`` (effects, ``" + "``-joined),
        ``error_before``/``error_after`` (NRMSE [-]), ``band_before``/``band_after`` [N] and
        their ratio, ``noise_sigma`` [N], ``success``, ``seconds`` (wall time of that
        diagnosis) and ``status`` (``"usable"``, ``"NOT usable"`` (the diagnosis ran; its
        verdict, as ``success``), ``"refused: ..."`` or ``"failed: ..."``).
    diagnoses : tuple of dict or None
        :meth:`Diagnosis.to_dict` of each record (None where it was not diagnosed).
    options : dict
        The options every record was diagnosed with.
    executor : str
        Where it ran.
    wall_time : float
        [s], the whole batch.
    warnings : tuple of str
    """

    rows: tuple
    diagnoses: tuple
    options: dict
    executor: str
    wall_time: float

    @property
    def success(self) -> bool:
        """True when every record was diagnosed and every diagnosis succeeded."""
        return all(diagnosed(r) and bool(r["success"]) for r in self.rows)

    def failure_reasons(self) -> tuple:
        """Which records are not usable and why (empty when every one is)."""
        out = []
        for r, d in zip(self.rows, self.diagnoses):
            if not diagnosed(r):
                out.append(f"{r['record']}: {r['status']}")
            elif not r["success"]:
                why = "; ".join((d or {}).get("failure_reasons") or ()) or "not usable"
                out.append(f"{r['record']}: {why}")
        return tuple(out)

    def report(self) -> str:
        """The table: one line per record, then the batch's totals and warnings."""
        head = (
            f"{'record':<28} {'named':<36} {'NRMSE before':>12} {'after':>8} "
            f"{'band before':>11} {'after':>9} {'ratio':>6} {'time [s]':>8}"
        )
        lines = [
            self.verdict(),
            f"Batch diagnosis of {len(self.rows)} records on {self.executor} "
            f"({self.wall_time:.1f} s)",
            head,
        ]
        for r in self.rows:
            if not diagnosed(r):
                lines.append(f"{r['record']:<28} {r['status']}")
                continue
            lines.append(
                f"{r['record']:<28} {r['named']:<36} {100 * r['error_before']:11.3g}% "
                f"{100 * r['error_after']:7.3g}% {r['band_before']:11.4g} "
                f"{r['band_after']:9.4g} {r['band_ratio']:6.2f} {r['seconds']:8.1f}"
            )
        lines += [f"warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-safe dict: the table, the options, every diagnosis."""

        def clean(v):
            if isinstance(v, (float, np.floating)) and not math.isfinite(float(v)):
                return None
            return v.item() if isinstance(v, np.generic) else v

        return {
            "rows": [{k: clean(v) for k, v in r.items()} for r in self.rows],
            "options": {k: clean(v) for k, v in self.options.items()},
            "executor": self.executor,
            "wall_time": self.wall_time,
            "success": self.success,
            "warnings": list(self.warnings),
            "diagnoses": list(self.diagnoses),
        }

    def to_csv(self, path) -> Path:
        """Write the table (one row per record) as CSV: the columns of the "rows" table
        (:meth:`to_dataframe`), titled with their units, the NRMSE in % as its title says.
        """
        _, cols, rows = self._tables()[0]
        lines = [",".join(_csv_cell(c) for c in cols)]
        for r in rows:
            lines.append(",".join(_csv_cell(v) for v in r))
        path = Path(path)
        path.write_text("\n".join(lines) + "\n")
        return path

    def plot(self, ax=None) -> list[Artist]:
        """Band misfit before and after per record (bars, log scale).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            One axes; a new figure if omitted.

        Returns
        -------
        list
            The matplotlib artists drawn.
        """
        (ax,) = panels(ax, 1, figsize=(max(5.0, 0.5 * len(self.rows) + 2), 4))
        ok = [r for r in self.rows if diagnosed(r)]
        x = np.arange(len(ok))
        artists = list(ax.bar(x - 0.2, [r["band_before"] for r in ok], 0.4, label="Iwan"))
        artists += list(
            ax.bar(x + 0.2, [r["band_after"] for r in ok], 0.4, label="with named effects")
        )
        ax.set_xticks(x, [r["record"] for r in ok], rotation=60, ha="right", fontsize=7)
        ax.set_ylabel("band misfit [N]")
        ax.set_yscale("log")
        ax.legend(fontsize=8)
        return artists


def _csv_cell(v) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return ""
    s = str(v)
    return f'"{s}"' if ("," in s or '"' in s) else s
