"""Vibration test files in: universal file format (UFF) dataset 58 and stepped-sine CSV.

UFF dataset 58 ("function at nodal DOF", the I-DEAS universal file format written by most
acquisition software; read through the optional ``pyuff`` package, ``pip install
iwan-element[uff]``) holds one function per record: a time series (function type 1) or a
frequency response function (type 4), with the abscissa and ordinate unit labels and the
specific data type of each axis. :func:`read_uff` turns every such record into a
:class:`UffRecord` in SI units: ``t`` [s] with ``y`` for a time series, ready for
:func:`~iwan_element.amplitude_curve` (``amplitude_curve(r.x, r.y, quantity=r.quantity)``),
or ``f`` [Hz] with the complex response per newton for an FRF, ready for
:func:`~iwan_element.stepped_sine_curve`. Units come from the file's labels; a label that
is not known, or that disagrees with the record's specific data type, is refused.

:func:`read_sweep_csv` reads raw stepped-sine sweeps from a CSV file whose header names a
unit per column (``level,f [Hz],F [N],A [m/s^2],phase [rad]``): the columns are found by
their units, not their positions, and converted to SI; the result is the keyword arguments
of :func:`~iwan_element.sweep_curve`. The equations and units are in ``docs/sweeps.md``.
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path

import numpy as np

from ...base.validation import finite_array
from .csv_input import DISPLACEMENT_UNITS, FORCE_UNITS, TIME_UNITS, _column_unit

__all__ = ["UffRecord", "read_uff", "read_sweep_csv", "RESPONSE_UNITS"]

_G = 9.80665
#: Accepted response units: label -> (quantity, factor to SI).
RESPONSE_UNITS = {
    **{u: ("displacement", k) for u, k in DISPLACEMENT_UNITS.items()},
    **{u: ("velocity", k) for u, k in {"m/s": 1.0, "mm/s": 1e-3, "in/s": 0.0254}.items()},
    **{
        u: ("acceleration", k)
        for u, k in {
            "m/s^2": 1.0,
            "m/s2": 1.0,
            "m/s**2": 1.0,
            "mm/s^2": 1e-3,
            "mm/s2": 1e-3,
            "g": _G,
            "in/s^2": 0.0254,
        }.items()
    },
}
_FREQUENCY_UNITS = {"Hz": 1.0, "hz": 1.0, "rad/s": 1.0 / (2 * math.pi)}
_PHASE_UNITS = {"rad": 1.0, "deg": math.pi / 180, "°": math.pi / 180}
#: UFF specific data types (record 8 of dataset 58) of the quantities read here.
_SPEC_TYPE = {
    8: "displacement",
    11: "velocity",
    12: "acceleration",
    13: "force",
    17: "time",
    18: "frequency",
}
_FUNC_TYPE = {1: "time", 4: "frf"}


@dataclass(frozen=True)
class UffRecord:
    """One UFF dataset-58 function in SI units.

    Attributes
    ----------
    kind : {"time", "frf"}
        Time series (UFF function type 1) or frequency response function (type 4).
    x : ndarray
        Time [s] or frequency [Hz].
    y : ndarray
        The response in SI units of ``quantity`` (real) for a time series; the complex
        response per unit force ([m/N], [m/s/N] or [m/s^2/N]) for an FRF.
    quantity : {"displacement", "velocity", "acceleration", "force"}
        What the (numerator of the) ordinate is.
    name : str
        The record's first ID line.
    response, reference : tuple
        ``(node, direction)`` of the response and of the reference (excitation) DOF.
    units : str
        The unit labels as written in the file (abscissa; ordinate; denominator).
    """

    kind: str
    x: np.ndarray
    y: np.ndarray
    quantity: str
    name: str = ""
    response: tuple = (0, 0)
    reference: tuple = (0, 0)
    units: str = ""
    warnings: tuple = field(default_factory=tuple)

    def to_dict(self) -> dict:
        """Plain dictionary (complex values as [real, imag] pairs)."""
        y = self.y.tolist() if self.kind == "time" else [[v.real, v.imag] for v in self.y]
        return {
            "kind": self.kind,
            "x": self.x.tolist(),
            "y": y,
            "quantity": self.quantity,
            "name": self.name,
            "response": list(self.response),
            "reference": list(self.reference),
            "units": self.units,
            "warnings": list(self.warnings),
        }


def _label(raw) -> str:
    s = str(raw or "").strip()
    return "" if s.upper() == "NONE" else s


def _ordinate(label: str, spec: int, where: str):
    """(quantity, factor) of an ordinate unit label, checked against its data type."""
    if label in FORCE_UNITS:
        q, k = "force", FORCE_UNITS[label]
    elif label in RESPONSE_UNITS:
        q, k = RESPONSE_UNITS[label]
    else:
        raise ValueError(
            f"{where}: ordinate unit {label!r} is not known; allowed: "
            f"{sorted(RESPONSE_UNITS) + sorted(FORCE_UNITS)}"
        )
    typed = _SPEC_TYPE.get(int(spec or 0))
    if typed is not None and typed != q:
        raise ValueError(
            f"{where}: ordinate unit {label!r} is a {q} but the record's specific "
            f"data type {spec} says {typed}"
        )
    return q, k


def _split_frf_label(num: str, den: str):
    """Numerator and denominator labels of an FRF ('m/s^2' + 'N', or 'm/s^2/N' alone)."""
    if den:
        return num, den
    m = re.fullmatch(r"\(?(.+?)\)?\s*/\s*(N|kN|lbf)", num)
    if not m:
        raise ValueError(
            f"FRF ordinate unit {num!r} names no force in its denominator "
            "(e.g. 'm/s^2/N' or a denominator label 'N')"
        )
    return m.group(1), m.group(2)


def _record(i, d) -> UffRecord:
    where = f"record {i} (dataset 58, {_label(d.get('id1')) or 'no name'})"
    kind = _FUNC_TYPE.get(int(d.get("func_type", 0)))
    if kind is None:
        raise ValueError(
            f"{where}: function type {d.get('func_type')} is not read (1: time series, 4: FRF)"
        )
    x = finite_array("abscissa", np.real(np.asarray(d["x"])), min_size=2)
    xlab = _label(d.get("abscissa_axis_units_lab"))
    table = TIME_UNITS if kind == "time" else _FREQUENCY_UNITS
    if xlab not in table:
        raise ValueError(
            f"{where}: abscissa unit {xlab!r} is not known for a {kind} record; "
            f"allowed: {sorted(table)}"
        )
    num, den = _label(d.get("ordinate_axis_units_lab")), _label(d.get("orddenom_axis_units_lab"))
    data = np.asarray(d["data"])
    if kind == "time":
        q, k = _ordinate(num, d.get("ordinate_spec_data_type"), where)
        y = k * finite_array("ordinate", np.real(data))
    else:
        num, den = _split_frf_label(num, den)
        q, k = _ordinate(num, d.get("ordinate_spec_data_type"), where)
        if den not in FORCE_UNITS:
            raise ValueError(
                f"{where}: FRF denominator unit {den!r} is not a force; allowed: "
                f"{sorted(FORCE_UNITS)}"
            )
        y = (
            k
            / FORCE_UNITS[den]
            * (
                finite_array("ordinate real part", data.real)
                + 1j * finite_array("ordinate imaginary part", data.imag)
            )
        )
    if y.shape != x.shape:
        raise ValueError(f"{where}: abscissa and ordinate lengths differ ({x.size}, {y.size})")
    warns = (
        ()
        if np.iscomplexobj(data) or kind == "time"
        else ("FRF stored as real values: the phase is lost",)
    )
    return UffRecord(
        kind,
        x * table[xlab],
        y,
        q,
        _label(d.get("id1")),
        (int(d.get("rsp_node", 0)), int(d.get("rsp_dir", 0))),
        (int(d.get("ref_node", 0)), int(d.get("ref_dir", 0))),
        f"{xlab}; {num}" + (f"; {den}" if kind == "frf" else ""),
        warns,
    )


def read_uff(path: str | PathLike, *, kind: str | None = None) -> list:
    """Read the dataset-58 records of a universal file, in SI units.

    Parameters
    ----------
    path : str or path-like
        A UFF file (ASCII or binary 58b).
    kind : {"time", "frf"}, optional, keyword-only
        Keep only time series or only FRFs (default: both).

    Returns
    -------
    list of UffRecord
        In file order; other datasets (units, geometry) are skipped.

    Raises
    ------
    ImportError
        ``pyuff`` is not installed (``pip install iwan-element[uff]``).
    ValueError
        No dataset 58 in the file (or none of ``kind``), a function type other than 1 or 4,
        an unknown unit label or one that contradicts the specific data type.
    """
    if kind not in (None, "time", "frf"):
        raise ValueError(f"kind must be None, 'time' or 'frf', got {kind!r}")
    try:
        import pyuff
    except ImportError as exc:  # pragma: no cover - optional extra
        raise ImportError("read_uff needs pyuff: pip install iwan-element[uff]") from exc
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"path {str(p)!r} is not a file")
    sets = pyuff.UFF(str(p)).read_sets()
    sets = [sets] if isinstance(sets, dict) else list(sets)
    found = [(i, d) for i, d in enumerate(sets) if int(d.get("type", 0)) == 58]
    if not found:
        raise ValueError(f"{p.name}: no dataset 58 (function at nodal DOF) in the file")
    out = [
        _record(i, d)
        for i, d in found
        if kind is None or _FUNC_TYPE.get(int(d.get("func_type", 0))) in (kind, None)
    ]
    if not out:
        held = sorted({str(_FUNC_TYPE.get(int(d.get("func_type", 0)))) for _, d in found})
        raise ValueError(
            f"{p.name}: no dataset 58 of kind={kind!r} in the file; it holds "
            f"{len(found)} record(s) of kind {held}: pass kind=None or the kind "
            "the file holds"
        )
    return out


def _classify(name: str):
    """(role, quantity, factor) of a sweep CSV column from the unit in its header."""
    unit = _column_unit(name)
    bare = re.sub(r"[\[(].*$", "", name).strip().lower()
    if unit is None:
        if bare in ("level", "sweep", "run"):
            return "level", None, 1.0
        raise ValueError(f"column {name!r} has no unit in brackets (e.g. 'f [Hz]')")
    if unit in _FREQUENCY_UNITS:
        return "f", None, _FREQUENCY_UNITS[unit]
    if unit in _PHASE_UNITS:
        return "phase", None, _PHASE_UNITS[unit]
    if unit in FORCE_UNITS:
        return "F", None, FORCE_UNITS[unit]
    if unit in RESPONSE_UNITS:
        q, k = RESPONSE_UNITS[unit]
        return "response", q, k
    raise ValueError(
        f"column {name!r}: unit {unit!r} is not known; allowed: frequency "
        f"{sorted(_FREQUENCY_UNITS)}, force {sorted(FORCE_UNITS)}, response "
        f"{sorted(RESPONSE_UNITS)}, phase {sorted(_PHASE_UNITS)}"
    )


def read_sweep_csv(path: str | PathLike) -> dict:
    """Raw stepped-sine sweeps from a CSV file, as the keyword arguments of ``sweep_curve``.

    The header must give each column's unit in brackets: a frequency (``Hz``, or ``rad/s``,
    converted), a force amplitude (``N``, ``kN``, ``lbf``, ...), one response amplitude
    (displacement, velocity or acceleration: ``m``, ``mm``, ``m/s``, ``m/s^2``, ``g``, ...)
    and a phase (``rad`` or ``deg``); an optional ``level`` (or ``sweep``) column without a
    unit labels the sweeps. Columns are found by unit, in any order.

    Parameters
    ----------
    path : str or path-like
        The CSV file (comma-separated, one header line).

    Returns
    -------
    dict
        ``f`` [Hz], ``F`` [N], ``response`` (SI units of ``quantity``), ``phase`` [rad],
        ``level`` (or None) and ``quantity``: ``sweep_curve(**read_sweep_csv(path))``.

    Raises
    ------
    ValueError
        A column without a known unit, a role given twice or missing, a row with another
        number of fields than the header, non-numeric data.
    """
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"path {str(p)!r} is not a file")
    with p.open(newline="", encoding="utf-8-sig") as fh:
        rows = [r for r in csv.reader(fh) if r and any(c.strip() for c in r)]
    if len(rows) < 2:
        raise ValueError(f"{p.name}: a header line and data rows are needed")
    cols: dict[str, tuple] = {}
    for j, name in enumerate(rows[0]):
        role, q, k = _classify(name.strip())
        if role in cols:
            raise ValueError(f"{p.name}: two {role} columns ({cols[role][3]!r}, {name!r})")
        cols[role] = (j, q, k, name)
    missing = [r for r in ("f", "F", "response", "phase") if r not in cols]
    if missing:
        raise ValueError(f"{p.name}: no column for {missing} (units in the header decide)")
    width = len(rows[0])
    ragged = next((k for k, r in enumerate(rows[1:], start=2) if len(r) != width), None)
    if ragged is not None:
        raise ValueError(
            f"{p.name}: line {ragged} has {len(rows[ragged - 1])} fields where the "
            f"header has {width} ({', '.join(c.strip() for c in rows[0])}); "
            "every row needs one value per column"
        )
    try:
        data = np.array([[float(c) for c in r] for r in rows[1:]])
    except ValueError as exc:
        raise ValueError(f"{p.name}: non-numeric data ({exc})") from None
    out = {role: finite_array(role, data[:, j]) * k for role, (j, _, k, _) in cols.items()}
    out.setdefault("level", None)
    out["quantity"] = cols["response"][1]
    return out
