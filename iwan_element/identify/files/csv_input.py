"""CSV input: a file of time, displacement and force in, a :class:`TestData` in SI out."""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Sequence
from os import PathLike
from pathlib import Path

import numpy as np

from ..loops.testdata import TestData

__all__ = ["DISPLACEMENT_UNITS", "FORCE_UNITS", "TIME_UNITS", "load_test"]

#: Factors to SI of the accepted displacement units (to metres).
DISPLACEMENT_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "in": 0.0254}
#: Factors to SI of the accepted force units (to newtons).
FORCE_UNITS = {"N": 1.0, "kN": 1e3, "MN": 1e6, "lbf": 4.4482216152605, "kip": 4448.2216152605}
#: Factors to SI of the accepted time units (to seconds).
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "min": 60.0}

_QUANTITIES = ("time", "displacement", "force")
_NAME_HINTS = {
    "time": ("time", "t"),
    "displacement": ("displacement", "disp", "u", "x", "extension", "position"),
    "force": ("force", "load", "f"),
}


def _unit_factor(kind: str, unit, table: dict) -> float:
    name = f"{kind}_unit"
    if unit is None or (isinstance(unit, str) and not unit.strip()):
        raise ValueError(f"{name} is missing; allowed units are {sorted(table)}")
    if not isinstance(unit, str) or unit.strip() not in table:
        raise ValueError(f"{name}={unit!r} is not a known unit; allowed units are {sorted(table)}")
    return table[unit.strip()]


_UNIT_IN_NAME = re.compile(r"[\[(]\s*([^\])]+?)\s*[\])]\s*$")


def _column_unit(name: str) -> str | None:
    m = _UNIT_IN_NAME.search(name)
    return m.group(1) if m else None


def _bare(name: str) -> str:
    return _UNIT_IN_NAME.sub("", name).strip().lower()


def column_index(header: list[str], spec, what: str, *, ncol: int | None = None) -> int:
    """The column ``spec`` names: an index below ``ncol`` (default: the header's length), or
    a header entry, whole or without its bracketed unit (case-insensitive), found once.
    ``ValueError`` naming ``what`` otherwise.
    """
    if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool):
        n = len(header) if ncol is None else ncol
        if not 0 <= spec < n:
            raise ValueError(f"{what} column index {spec} is out of range [0, {n - 1}]")
        return int(spec)
    hits = [k for k, h in enumerate(header) if h == spec or _bare(h) == str(spec).strip().lower()]
    if len(hits) != 1:
        raise ValueError(f"{what} column {spec!r} not found in the header {header}")
    return hits[0]


def _resolve_columns(header: list[str] | None, columns, ncol: int) -> list[int]:
    if columns is None:
        if header is None:
            if ncol < 3:
                raise ValueError(
                    f"the file has {ncol} column(s); time, displacement and force are needed"
                )
            return [0, 1, 2]
        idx = []
        for q in _QUANTITIES:
            hits = [k for k, h in enumerate(header) if _bare(h) in _NAME_HINTS[q]]
            if len(hits) != 1:
                raise ValueError(
                    f"cannot tell which column is the {q} from the header {header}; "
                    "pass columns=(time, displacement, force) as names or indices (a "
                    "ring-down or sweep file is read by read_vibration_csv)"
                )
            idx.append(hits[0])
        return idx
    if isinstance(columns, (str, bytes)) or len(columns) != 3:
        raise ValueError(
            "columns must be a sequence of three names or indices "
            f"(time, displacement, force), got {columns!r}"
        )
    idx = []
    for q, c in zip(_QUANTITIES, columns):
        if not isinstance(c, (str, int, np.integer)) or isinstance(c, bool):
            raise ValueError(f"{q} column must be a name or an index, got {c!r}")
        idx.append(column_index(header or [], c, q, ncol=ncol))
    if len(set(idx)) != 3:
        raise ValueError(f"time, displacement and force must be different columns, got {columns!r}")
    return idx


def _header_units(header, idx, given: dict) -> dict:
    """The unit of each of time, displacement, force: the caller's, else the header's label
    (``"force [kN]"``), never a guess. ``ValueError`` when they contradict, or when a unit is
    neither given nor labelled (naming the columns found and how to pass it).
    """
    units, missing = {}, []
    for q, k in zip(_QUANTITIES, idx):
        said = _column_unit(header[k]) if header is not None else None
        unit = given[q]
        if unit is not None and said is not None and said != unit.strip():
            raise ValueError(
                f"column {header[k]!r} is labelled in {said!r} but "
                f"{q}_unit={unit!r}; pass the unit of the file"
            )
        if unit is None and said is None:
            missing.append(q)
        units[q] = unit if unit is not None else said
    if missing:
        found = (
            f"the header names the columns {header} without a unit in brackets"
            if header is not None
            else "the file has no header"
        )
        example = {"time": "s", "displacement": "mm", "force": "kN"}
        raise ValueError(
            f"the unit of the {', '.join(missing)} column(s) is not stated: {found}, and a "
            "unit is never guessed (SI and mm/kN records look alike); pass "
            + ", ".join(f"{q}_unit='{example[q]}'" for q in missing)
            + " (the file's units) or label the header as "
            + ", ".join(f"'{q} [{example[q]}]'" for q in missing)
        )
    return units


def _check_given_units(given):
    """Each unit given by the caller checked against its table."""
    for q, table in (
        ("time", TIME_UNITS),
        ("displacement", DISPLACEMENT_UNITS),
        ("force", FORCE_UNITS),
    ):
        if given[q] is not None:
            _unit_factor(q, given[q], table)


def _data_lines(p):
    """The file's non-blank, non-comment lines with their line numbers."""
    try:
        text = p.read_text(encoding="utf-8-sig")  # tolerate a byte-order mark
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"cannot read {str(p)!r}: {exc}") from None
    lines = [
        (k + 1, ln)
        for k, ln in enumerate(text.splitlines())
        if ln.strip() and not ln.lstrip().startswith("#")
    ]
    if not lines:
        raise ValueError(f"{str(p)!r} contains no data lines")
    return lines


def _numbers(lines, fields, idx, p):
    """The time, displacement and force columns as numbers, each finite."""
    data = np.empty((len(lines), 3))
    for r, (lineno, line) in enumerate(lines):
        row = fields(line)
        for j, k in enumerate(idx):
            try:
                data[r, j] = float(row[k])
            except IndexError:
                raise ValueError(
                    f"line {lineno} of {str(p)!r} has {len(row)} fields; column "
                    f"{k} ({_QUANTITIES[j]}) is missing"
                ) from None
            except ValueError:
                raise ValueError(
                    f"line {lineno} of {str(p)!r}: {_QUANTITIES[j]} value "
                    f"{row[k]!r} is not a number"
                ) from None
    for j, q in enumerate(_QUANTITIES):
        bad = ~np.isfinite(data[:, j])
        if bad.any():
            lineno = lines[int(np.flatnonzero(bad)[0])][0]
            raise ValueError(
                f"the {q} column contains NaN or infinite values (first at line "
                f"{lineno} of {str(p)!r})"
            )
    return data


def load_test(
    path: str | PathLike,
    *,
    displacement_unit: str | None = None,
    force_unit: str | None = None,
    time_unit: str | None = None,
    columns: Sequence | None = None,
    delimiter: str | None = None,
    hysteresis: float | None = None,
    close_tol: float = 0.02,
    drift_tol: float = 0.05,
) -> TestData:
    """Read a CSV of time, displacement and force, convert to SI and split into cycles.

    Lines starting with ``#`` are comments. If the first other line is not numeric it is a
    header. Units are read, never guessed: a unit in brackets at the end of a column name
    (``"time [s]"``, ``"displacement [mm]"``, ``"force [kN]"``) is the column's unit, and a
    unit argument, when given, must agree with it; a column with neither is refused, naming
    the columns found (an SI record read as mm and kN is wrong by 1e3 in u and F).

    Parameters
    ----------
    path : str or path-like
        The CSV file.
    displacement_unit : str, optional, keyword-only
        Unit of the displacement column, one of :data:`DISPLACEMENT_UNITS`; default: the
        header's label.
    force_unit : str, optional, keyword-only
        Unit of the force column, one of :data:`FORCE_UNITS`; default: the header's label.
    time_unit : str, optional, keyword-only
        Unit of the time column, one of :data:`TIME_UNITS`; default: the header's label.
    columns : sequence of 3 str or int, optional, keyword-only
        Names or 0-based indices of the (time, displacement, force) columns. Default: found
        from the header names (``time``/``t``, ``displacement``/``u``/..., ``force``/``F``/
        ``load``), or columns 0, 1, 2 without a header.
    delimiter : str, optional, keyword-only
        Field separator (default: guessed among ``,``, ``;``, tab and whitespace).
    hysteresis, close_tol, drift_tol : keyword-only
        Cycle-splitting options in SI (see :func:`split_cycles`).

    Returns
    -------
    TestData

    Raises
    ------
    ValueError
        A unit neither given nor in the header, unknown or contradicting units, unreadable or
        non-numeric cells, a ragged row, NaN, non-increasing time,
        an all-zero force column, a constant displacement, or fewer than two cycles.
    """
    given = {"time": time_unit, "displacement": displacement_unit, "force": force_unit}
    _check_given_units(given)
    p = Path(path)
    lines = _data_lines(p)
    if delimiter is None:
        first = lines[0][1]
        delimiter = next((d for d in (",", ";", "\t") if d in first), None)
    elif not isinstance(delimiter, str) or len(delimiter) != 1:
        raise ValueError(f"delimiter must be a single character, got {delimiter!r}")

    def fields(line: str) -> list[str]:
        if delimiter is None:
            return line.split()
        return [f.strip() for f in next(csv.reader(io.StringIO(line), delimiter=delimiter))]

    head = fields(lines[0][1])
    try:
        [float(x) for x in head]
        header = None
    except ValueError:
        header = head
        lines = lines[1:]
    if not lines:
        raise ValueError(f"{str(p)!r} has a header but no data rows")
    ncol = len(header) if header is not None else len(head)
    idx = _resolve_columns(header, columns, ncol)
    units = _header_units(header, idx, given)
    ft = _unit_factor("time", units["time"], TIME_UNITS)
    fu = _unit_factor("displacement", units["displacement"], DISPLACEMENT_UNITS)
    ff = _unit_factor("force", units["force"], FORCE_UNITS)
    data = _numbers(lines, fields, idx, p)
    if not np.any(data[:, 2] != 0.0):
        raise ValueError(f"the force column of {str(p)!r} is all zero")
    units = {q: u.strip() for q, u in units.items()}
    return TestData.from_arrays(
        data[:, 0] * ft,
        data[:, 1] * fu,
        data[:, 2] * ff,
        units=units,
        source=str(p),
        hysteresis=hysteresis,
        close_tol=close_tol,
        drift_tol=drift_tol,
    )
