"""Vibration records from CSV, beside :func:`~iwan_element.load_test` (loops): a ring-down
(time and one response column) or stepped-sine sweeps (:func:`read_sweep_csv`), told apart by
the units in the header, read in SI.

A file of the wrong kind is refused naming the reader (and the command) for its kind, so a
ring-down given to the loop fit and a loop record given here both say where to go.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from os import PathLike
from pathlib import Path

import numpy as np

from ...base.validation import finite_array
from .csv_input import FORCE_UNITS, TIME_UNITS, _bare, _column_unit, _data_lines, column_index
from .formats import _FREQUENCY_UNITS, _PHASE_UNITS, RESPONSE_UNITS, read_sweep_csv

__all__ = ["file_kind", "read_vibration_csv", "KIND_READERS"]

#: What reads each kind of record, in Python and on the command line.
KIND_READERS = {
    "loops": ("load_test", "iwan-element fit FILE (or diagnose)"),
    "ringdown": ("read_vibration_csv", "iwan-element curve FILE"),
    "sweep": ("read_sweep_csv (or read_vibration_csv)", "iwan-element curve FILE"),
}


def _split(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:
        return line.split()
    return [f.strip() for f in next(csv.reader(io.StringIO(line), delimiter=delimiter))]


def _guess_delimiter(line: str) -> str | None:
    return next((d for d in (",", ";", "\t") if d in line), None)


def _is_time(name: str) -> bool:
    """A header entry in a unit of time, or named time."""
    return _column_unit(name) in TIME_UNITS or _bare(name) in ("time", "t")


def _header_kind(header: list[str]) -> str | None:
    """The kind of record a header describes from its units and names, or None."""
    units = [_column_unit(h) for h in header]
    bare = [_bare(h) for h in header]
    has_time = any(_is_time(h) for h in header)
    has_force = any(u in FORCE_UNITS for u in units) or any(b in ("force", "load") for b in bare)
    has_response = any(u in RESPONSE_UNITS for u in units)
    if any(u in _FREQUENCY_UNITS for u in units) and any(u in _PHASE_UNITS for u in units):
        return "sweep"
    if has_time and has_force:
        return "loops"
    if has_time and has_response:
        return "ringdown"
    return None


def file_kind(path: str | PathLike) -> str | None:
    """The kind of test record a CSV holds, read from its header: ``"loops"`` (time,
    displacement, force), ``"ringdown"`` (time and a response, no force), ``"sweep"``
    (frequency, force, response, phase), or None (no header, or one that does not tell).
    """
    first = _data_lines(Path(path))[0][1]
    header = _split(first, _guess_delimiter(first))
    try:
        [float(x) for x in header]
        return None  # numbers: no header
    except ValueError:
        return _header_kind(header)


def _ringdown_columns(header, columns) -> tuple[int, int]:
    if columns is not None:
        if isinstance(columns, (str, bytes)) or len(columns) != 2:
            raise ValueError(
                f"columns must be two names or indices (time, response), got {columns!r}"
            )
        return (
            column_index(header, columns[0], "time"),
            column_index(header, columns[1], "response"),
        )
    units = [_column_unit(h) for h in header]
    times = [k for k, h in enumerate(header) if _is_time(h)]
    resp = [k for k, u in enumerate(units) if u in RESPONSE_UNITS and k not in times]
    if len(times) != 1 or len(resp) != 1:
        raise ValueError(
            f"cannot tell the time and the response column from the header {header} (one "
            "time column and one response column with a unit in brackets are read); name "
            "them with columns=(time, response) (on the command line --columns T,Y)"
        )
    return times[0], resp[0]


def _unit(label: str | None, given: str | None, table: dict, what: str) -> str:
    if given is not None and given not in table:
        raise ValueError(f"{what}_unit={given!r} is not a known unit; allowed: {sorted(table)}")
    if given is not None and label is not None and label != given:
        raise ValueError(f"the {what} column is labelled {label!r} but {what}_unit={given!r}")
    unit = given if given is not None else label
    if unit is None or unit not in table:
        raise ValueError(
            f"the unit of the {what} column is not stated or not known ({label!r}); a unit is "
            f"never guessed: label the header ('a [m/s^2]') or pass {what}_unit, one of "
            f"{sorted(table)}"
        )
    return unit


def read_vibration_csv(
    path: str | PathLike,
    *,
    columns: Sequence | None = None,
    time_unit: str | None = None,
    response_unit: str | None = None,
    delimiter: str | None = None,
) -> dict:
    """A ring-down or stepped-sine sweep record from CSV, in SI units.

    Parameters
    ----------
    path : str or path-like
        The CSV file; ``#`` lines are comments. Its header tells the kind: a frequency and a
        phase column make sweeps (read by :func:`read_sweep_csv`), a time column and one
        response column (``m``, ``m/s``, ``m/s^2``, ``g``, ...) a ring-down.
    columns : sequence of 2 str or int, optional, keyword-only
        Ring-down only: the (time, response) columns by name or 0-based index; default the
        header's one time and one response column (a file without a header: 0 and 1).
    time_unit, response_unit : str, optional, keyword-only
        Ring-down only: units of the columns when the header does not label them (one of
        ``s``, ``ms``, ``min``; a response unit decides the quantity); a given unit must
        agree with the header's label.
    delimiter : str, optional, keyword-only
        Ring-down only: field separator (default guessed among ``,``, ``;``, tab, spaces).

    Returns
    -------
    dict
        ``kind`` ("ringdown" or "sweep") and ``source``; a ring-down: ``t`` [s], ``y`` (SI
        unit of ``quantity``), ``quantity``, ``units`` (as read); sweeps: the keyword
        arguments of :func:`~iwan_element.sweep_curve` (``f``, ``F``, ``response``,
        ``phase``, ``level``, ``quantity``).

    Raises
    ------
    ValueError
        A loop record (time, displacement, force: read by :func:`load_test`), columns or
        units not found or contradicting, non-numeric or non-finite data, fewer than 16
        samples.
    """
    p = Path(path)
    lines = _data_lines(p)
    delimiter = _guess_delimiter(lines[0][1]) if delimiter is None else delimiter
    head = _split(lines[0][1], delimiter)
    try:
        [float(x) for x in head]
        header, kind = None, "ringdown"
    except ValueError:
        header, kind = head, _header_kind(head) or "ringdown"
        lines = lines[1:]
    if kind == "loops":
        py, cmd = KIND_READERS["loops"]
        raise ValueError(
            f"{p.name} is a loop record (time, displacement, force columns), not a ring-down "
            f"or a sweep: read it with {py} (on the command line: {cmd})"
        )
    if kind == "sweep":
        if columns is not None or time_unit is not None or response_unit is not None:
            raise ValueError(
                "sweep files are read by the units of their header: no columns or units"
            )
        return {"kind": "sweep", "source": str(p), **read_sweep_csv(p)}
    names = header if header is not None else [str(k) for k in range(len(head))]
    jt, jy = (0, 1) if header is None and columns is None else _ringdown_columns(names, columns)
    tu = _unit(_column_unit(names[jt]), time_unit, TIME_UNITS, "time")
    yu = _unit(_column_unit(names[jy]), response_unit, RESPONSE_UNITS, "response")
    try:
        rows = np.array(
            [[float(r[jt]), float(r[jy])] for r in (_split(s, delimiter) for _, s in lines)]
        )
    except (ValueError, IndexError) as exc:
        raise ValueError(
            f"{p.name}: a row without a number in column {jt} or {jy} ({exc})"
        ) from None
    if rows.shape[0] < 16:
        raise ValueError(f"{p.name}: {rows.shape[0]} samples; a ring-down needs at least 16")
    quantity, k = RESPONSE_UNITS[yu]
    return {
        "kind": "ringdown",
        "source": str(p),
        "t": finite_array("t", rows[:, 0]) * TIME_UNITS[tu],
        "y": finite_array("y", rows[:, 1]) * k,
        "quantity": quantity,
        "units": {"time": tu, "response": yu},
    }
