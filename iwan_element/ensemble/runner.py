"""Run one function over many parameter sets on any executor, reproducibly.

:func:`run_ensemble` is the engine of the uncertainty and parameter studies: it calls
``func(params, rng)`` for each parameter set, on local processes
(:class:`concurrent.futures.ProcessPoolExecutor`, the default), in this process
(``"serial"``), on any :class:`concurrent.futures.Executor`, or on a ``dask.distributed``
``Client`` (through the client's own ``concurrent.futures`` adapter, ``Client.get_executor``).

Reproducibility
    One ``seed`` is split with :meth:`numpy.random.SeedSequence.spawn` into one independent
    child per task, in input order; task ``i`` always gets ``default_rng(children[i])``,
    wherever and in whatever order it runs. Serial, process-pool and Dask runs therefore give
    bit-identical outputs (floats cross process boundaries by pickle, exactly).

Failures
    A task that raises does not stop the ensemble: its index, parameters, error message and
    traceback text go to :attr:`EnsembleResult.errors`, its row keeps the parameters with NaN
    outputs, and the other results are kept. A worker process that dies under a Dask run is
    recovered by the Dask scheduler, which re-runs the lost tasks elsewhere (up to its
    ``distributed.scheduler.allowed-failures`` limit, 3 by default); a dead process of a
    ``ProcessPoolExecutor`` breaks that pool, and its unfinished tasks are reported as errors.
"""

from __future__ import annotations

import concurrent.futures as cf
import csv
import logging
import math
import os
import pickle
import time
import traceback
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from numbers import Number
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Any, SupportsFloat, cast

import numpy as np

from ..base.progress import finish, progress_bar
from ..base.result_shape import ResultShape, panels
from ..base.serialize import json_safe

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["run_ensemble", "EnsembleResult", "TaskError"]

log = logging.getLogger(__name__)


# ================================================================== result types
@dataclass(frozen=True)
class TaskError:
    """One failed task: ``index`` in the input, its ``params``, the error ``message``
    (``"ExceptionType: text"``) and the ``traceback`` text from the worker.
    """

    index: int
    params: dict
    message: str
    traceback: str = ""

    def to_dict(self) -> dict:
        """The failed member as a JSON-safe dict (index, parameters, message, traceback)."""
        return json_safe(
            {
                "index": self.index,
                "params": self.params,
                "message": self.message,
                "traceback": self.traceback,
            }
        )


@dataclass(frozen=True, eq=False)
class EnsembleResult(ResultShape):
    """What :func:`run_ensemble` returns.

    Attributes
    ----------
    rows : tuple of dict
        One dict per parameter set, in input order: the parameters followed by the outputs.
        The row of a failed task holds its parameters and NaN for every output name (a NaN
        array of the common shape for array outputs); see ``errors``.
    errors : tuple of TaskError
        The failed tasks (index, parameters, message, traceback), in input order.
    outputs : tuple of str
        Output names, in the order the first successful task returned them.
    parameters : tuple of str
        Parameter names (union over the sets, in first-seen order).
    seed : int
        The entropy of the root ``SeedSequence`` (give it back as ``seed=`` to repeat the run).
    executor : str
        Where the ensemble ran (``"serial"``, ``"processes (2 workers)"``, ``"dask: ..."``).
    wall_time : float
        [s].
    warnings : tuple of str
    """

    rows: tuple
    errors: tuple
    outputs: tuple
    parameters: tuple
    seed: int
    executor: str
    wall_time: float

    def __len__(self) -> int:
        return len(self.rows)

    @property
    def ok(self) -> np.ndarray:
        """Boolean mask of the successful tasks, in input order."""
        mask = np.ones(len(self.rows), bool)
        mask[[e.index for e in self.errors]] = False
        return mask

    def column(self, name: str) -> np.ndarray:
        """Values of one parameter or output over the rows: shape ``(n,)`` for scalars,
        ``(n, m)`` for array outputs of a common shape ``(m,)``; NaN for failed tasks'
        outputs. Raises ``ValueError`` for an unknown name or arrays of different shapes.
        """
        if name not in self.outputs and name not in self.parameters:
            raise ValueError(
                f"unknown column {name!r}; parameters are {list(self.parameters)}, "
                f"outputs are {list(self.outputs)}"
            )
        values = [row.get(name, math.nan) for row in self.rows]
        shapes = {np.shape(v) for v in values}
        if len(shapes) > 1:
            raise ValueError(f"column {name!r} holds values of different shapes {sorted(shapes)}")
        try:
            return np.array(values, dtype=float)
        except (TypeError, ValueError):
            return np.array(values, dtype=object)

    def to_csv(self, path: str | PathLike) -> Path:
        """Write the tidy table (one row per parameter set, an ``ok`` column, array outputs
        expanded to ``name[0], name[1], ...``) to ``path``; return the path.
        """
        p = Path(path)
        expanded: list[tuple[str, tuple[str, int] | None]] = []
        for name in self.parameters + self.outputs:
            shape = next((np.shape(r[name]) for r in self.rows if name in r), ())
            if len(shape) == 0:
                expanded.append((name, None))
            else:
                expanded += [(f"{name}[{k}]", (name, k)) for k in range(int(np.prod(shape)))]
        ok = self.ok
        with p.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["index", "ok"] + [h for h, _ in expanded])
            for i, row in enumerate(self.rows):
                cells: list[Any] = [i, bool(ok[i])]
                for header, src in expanded:
                    if src is None:
                        cells.append(_cell(row.get(header, "")))
                    else:
                        v = row.get(src[0])
                        cells.append("" if v is None else _cell(np.ravel(v)[src[1]]))
                w.writerow(cells)
        return p

    def to_dict(self) -> dict:
        """JSON-safe dict (NaN becomes ``None``)."""
        return json_safe(
            {
                "rows": list(self.rows),
                "errors": [e.to_dict() for e in self.errors],
                "outputs": list(self.outputs),
                "parameters": list(self.parameters),
                "seed": self.seed,
                "executor": self.executor,
                "wall_time": self.wall_time,
                "warnings": list(self.warnings),
            }
        )

    @property
    def success(self) -> bool:
        """True when every task ran (failed tasks are in ``errors``)."""
        return bool(len(self.rows) > 0 and not self.errors)

    def plot(self, ax=None, *, output: str | None = None, bins: int = 30) -> list[Artist]:
        """Histogram of one scalar output over the successful tasks (default: the first
        scalar output). Returns the artists (one Axes, :mod:`iwan_element.base.result_shape`).
        Raises ``ValueError`` when there is no scalar output to draw.
        """
        names = [output] if output is not None else list(self.outputs)
        for name in names:
            col = self.column(name)
            if col.dtype != object and col.ndim == 1 and np.isfinite(col).any():
                break
        else:
            raise ValueError(f"no scalar output with finite values among {names}")
        (ax,) = panels(ax, 1, figsize=(5, 3.5))
        vals = col[np.isfinite(col)]
        arts = list(ax.hist(vals, bins=max(1, min(bins, vals.size)), color="C0", alpha=0.7)[2])
        ax.set_xlabel(name)
        ax.set_ylabel("tasks")
        ax.set_title(f"{vals.size} of {len(self.rows)} tasks ({self.executor})", fontsize=9)
        return arts

    def report(self) -> str:
        """Summary: tasks, failures (with their messages), outputs and their ranges."""
        n, nf = len(self.rows), len(self.errors)
        lines = [
            self.verdict(),
            f"Ensemble of {n} tasks on {self.executor}: {n - nf} succeeded, {nf} failed, "
            f"{self.wall_time:.2f} s (seed {self.seed})",
            f"  parameters: {', '.join(self.parameters)}",
        ]
        for name in self.outputs:
            try:
                col = self.column(name)
            except ValueError:
                lines.append(f"  output {name}: values of different shapes")
                continue
            if col.dtype == object or col.size == 0 or np.all(np.isnan(col)):
                lines.append(f"  output {name}")
            else:
                lines.append(
                    f"  output {name}: shape {col.shape[1:] or 'scalar'}, range "
                    f"{np.nanmin(col):.6g} .. {np.nanmax(col):.6g}"
                )
        for e in self.errors[:10]:
            lines.append(f"  FAILED task {e.index} {e.params}: {e.message}")
        if nf > 10:
            lines.append(f"  ... and {nf - 10} more failures")
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)


def _cell(v):
    if isinstance(v, (float, np.floating)):
        return repr(float(v)) if math.isfinite(v) else ("nan" if math.isnan(v) else repr(float(v)))
    if isinstance(v, (bool, np.bool_, int, np.integer, str)):
        return v if not isinstance(v, np.generic) else v.item()
    return str(v)


# ================================================================== the task wrapper
def _check_outputs(out, params: dict) -> dict:
    """Validate the dict ``func`` returned; arrays are copied to float ndarrays."""
    if not isinstance(out, Mapping):
        raise TypeError(f"func must return a dict of outputs, got {type(out).__name__}")
    clean: dict[str, Any] = {}
    for key, value in out.items():
        if not isinstance(key, str):
            raise TypeError(f"output names must be str, got {key!r}")
        if key in params:
            raise ValueError(f"output {key!r} has the name of a parameter; rename it")
        if isinstance(value, (str, bool, np.bool_)):
            clean[key] = value if isinstance(value, str) else bool(value)
        elif isinstance(value, (Number, np.number)):
            # numbers.Number declares no __float__ (typeshed); the real numbers all have one
            real = cast(SupportsFloat, value)
            clean[key] = float(real) if not isinstance(value, (int, np.integer)) else int(value)
        else:
            try:
                arr = np.array(value, dtype=float)
            except (TypeError, ValueError):
                raise TypeError(
                    f"output {key!r} must be a number, a str or a numeric array, "
                    f"got {type(value).__name__}"
                ) from None
            clean[key] = arr if arr.ndim else float(arr)
    return clean


def _run_task(func, index: int, params: dict, seed_seq: np.random.SeedSequence):
    """Run one task; never raises (the error travels back as data)."""
    try:
        out = func(params, np.random.default_rng(seed_seq))
        return index, True, _check_outputs(out, params), ""
    except Exception as exc:  # noqa: BLE001 - any task failure is reported, not raised
        return index, False, f"{type(exc).__name__}: {exc}", traceback.format_exc()


# ================================================================== input checks
def _check_sets(parameter_sets) -> list[dict]:
    if isinstance(parameter_sets, (str, bytes, Mapping)) or not isinstance(
        parameter_sets, Sequence
    ):
        raise ValueError(
            "parameter_sets must be a sequence (list or tuple) of dicts, got "
            f"{type(parameter_sets).__name__}"
        )
    sets = []
    for i, s in enumerate(parameter_sets):
        if not isinstance(s, Mapping):
            raise ValueError(f"parameter_sets[{i}] must be a dict, got {type(s).__name__}")
        bad = [k for k in s if not isinstance(k, str)]
        if bad:
            raise ValueError(f"parameter_sets[{i}] has non-str keys {bad!r}")
        sets.append(dict(s))  # a copy: nothing the caller gave is mutated
    if not sets:
        raise ValueError("parameter_sets is empty: give at least one parameter set")
    return sets


def _check_seed(seed):
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be None or an integer >= 0, got {seed!r}")
    return int(seed)


def _is_dask_client(obj) -> bool:
    """True for a ``distributed.Client`` (checked by type name: dask is not imported)."""
    return any(
        c.__name__ == "Client" and c.__module__.split(".")[0] == "distributed"
        for c in type(obj).__mro__
    )


def _check_picklable(func) -> None:
    try:
        pickle.dumps(func)
    except Exception as exc:  # noqa: BLE001 - pickle raises many types
        raise ValueError(
            f"func {func!r} cannot be sent to worker processes ({type(exc).__name__}: {exc}). "
            "With local processes (executor=None or a ProcessPoolExecutor) func must be "
            "importable: a function defined at module level (not a lambda or a nested "
            "function), or functools.partial of one; use executor='serial' or a Dask Client "
            "(cloudpickle) for other callables"
        ) from None


# ================================================================== the runner
def run_ensemble(
    func, parameter_sets, *, executor=None, seed=None, progress: bool = False
) -> EnsembleResult:
    """Run ``func(params, rng)`` for every parameter set, on local processes, serially, on any
    ``concurrent.futures.Executor`` or on a ``dask.distributed.Client``.

    Parameters
    ----------
    func : callable
        ``func(params, rng) -> dict``: ``params`` is one parameter set (a dict, a copy),
        ``rng`` a :class:`numpy.random.Generator` seeded for this task. It returns a dict of
        outputs, each a number, a str or a numeric array; output names must differ from the
        parameter names. For local processes it must be importable (module level).
    parameter_sets : sequence of dict
        One dict per task (str keys; values anything ``func`` accepts). Not modified.
    executor : None, "serial", concurrent.futures.Executor or dask.distributed.Client, keyword-only
        ``None`` (default): a ``ProcessPoolExecutor`` with ``min(os.cpu_count(), n)`` workers,
        shut down at the end. ``"serial"``: in this process, in order (for debugging). An
        executor or a Dask client is used as given and not shut down.
    seed : int or None, keyword-only
        Root seed of the per-task generators (``SeedSequence(seed).spawn(n)``); ``None`` draws
        fresh entropy, recorded in ``result.seed``.
    progress : bool, keyword-only
        Show a tqdm progress bar (needs ``tqdm``: ``pip install iwan-element[progress]``).

    Returns
    -------
    EnsembleResult

    Raises
    ------
    ValueError
        ``func`` not callable or (for processes) not picklable, ``parameter_sets`` not a
        sequence of dicts, a bad ``seed`` or ``executor``.
    ImportError
        ``progress=True`` without tqdm installed.

    Examples
    --------
    >>> def square(params, rng):
    ...     return {"y": params["x"] ** 2}
    >>> res = run_ensemble(square, [{"x": 1.0}, {"x": 2.0}], executor="serial", seed=1)
    >>> res.column("y").tolist()
    [1.0, 4.0]
    """
    t0 = time.perf_counter()
    if not callable(func):
        raise ValueError(f"func must be callable as func(params, rng), got {type(func).__name__}")
    sets = _check_sets(parameter_sets)
    root = np.random.SeedSequence(_check_seed(seed))
    children = root.spawn(len(sets))
    bar = progress_bar(progress, total=len(sets), desc="ensemble", unit="task")
    try:
        raw, where, warns = _dispatch(func, sets, children, executor, bar)
    finally:
        if bar is not None:
            finish(bar)
    return _assemble(sets, raw, root, where, time.perf_counter() - t0, warns)


def _dispatch(func, sets, children, executor, bar) -> tuple[list, str, list[str]]:
    """Run the tasks; return ``(list of raw task results, description, warnings)``."""
    n = len(sets)
    warns: list[str] = []
    if isinstance(executor, str):
        if executor != "serial":
            raise ValueError(
                f"executor must be None, 'serial', a concurrent.futures.Executor or "
                f"a dask.distributed.Client, got {executor!r}"
            )
        raw: list = []
        for i, (s, c) in enumerate(zip(sets, children)):
            raw.append(_run_task(func, i, s, c))
            if bar is not None:
                bar.update(1)
        return raw, "serial", warns
    if executor is None:
        _check_picklable(func)
        workers = max(1, min(os.cpu_count() or 1, n))
        with cf.ProcessPoolExecutor(max_workers=workers) as pool:
            raw = _collect(pool, func, sets, children, bar)
        return raw, f"processes ({workers} workers)", warns
    if _is_dask_client(executor):
        info = executor.scheduler_info() if hasattr(executor, "scheduler_info") else {}
        desc = f"dask ({len(info.get('workers', {}))} workers at {info.get('address', '?')})"
        pool = executor.get_executor(pure=False)
        return _collect(pool, func, sets, children, bar), desc, warns
    if isinstance(executor, cf.Executor):
        if isinstance(executor, cf.ProcessPoolExecutor):
            _check_picklable(func)
        return _collect(executor, func, sets, children, bar), type(executor).__name__, warns
    raise ValueError(
        f"executor must be None, 'serial', a concurrent.futures.Executor or a "
        f"dask.distributed.Client, got {type(executor).__name__}"
    )


def _collect(pool, func, sets, children, bar):
    futures = {
        pool.submit(_run_task, func, i, s, c): i for i, (s, c) in enumerate(zip(sets, children))
    }
    raw = [None] * len(sets)
    for fut in cf.as_completed(futures):
        i = futures[fut]
        try:
            raw[i] = fut.result()
        except Exception as exc:  # noqa: BLE001 - the executor itself failed
            raw[i] = (
                i,
                False,
                f"{type(exc).__name__}: {exc} (the executor lost the task)",
                traceback.format_exc(),
            )
        if bar is not None:
            bar.update(1)
    return raw


def _assemble(sets, raw, root, where, wall, warns) -> EnsembleResult:
    outputs: list[str] = []
    shapes: dict = {}
    for _, ok, out, _ in raw:
        if ok:
            for k, v in out.items():
                if k not in outputs:
                    outputs.append(k)
                    shapes[k] = np.shape(v)
    params = list(dict.fromkeys(k for s in sets for k in s))
    rows, errors = [], []
    for (i, ok, out, tb), s in zip(raw, sets):
        row = dict(s)
        if ok:
            row.update(out)
        else:
            errors.append(TaskError(index=i, params=dict(s), message=out, traceback=tb))
            log.warning("ensemble task %d failed: %s", i, out)
            row.update(
                {
                    k: (math.nan if shapes[k] == () else np.full(shapes[k], math.nan))
                    for k in outputs
                }
            )
        rows.append(row)
    if errors:
        warns.append(
            f"{len(errors)} of {len(sets)} tasks failed (see errors); their rows hold NaN outputs"
        )
    entropy = int(root.entropy)
    return EnsembleResult(
        rows=tuple(rows),
        errors=tuple(errors),
        outputs=tuple(outputs),
        parameters=tuple(params),
        seed=entropy,
        executor=where,
        wall_time=wall,
        warnings=tuple(warns),
    )
