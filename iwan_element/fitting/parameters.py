"""Fitted parameters: :class:`Parameter` and the table a fit result carries as ``params``.

Modelled on the parameter objects of lmfit (Newville et al., LMFIT: Non-Linear Least-Square
Minimization and Curve-Fitting for Python, Zenodo 2014, doi:10.5281/zenodo.11813): each
parameter carries its value with its standard error, bounds, unit and what the fit concluded
about it (docs/fitting.md, section 6). Unlike lmfit's, both are immutable results, not
the fit's input.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..base.result_shape import (
    PARAMETER_COLUMNS,
    html_table,
    parameter_rows,
    table_lines,
    unit_label,
)
from ..base.serialize import json_safe

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["Parameter", "ParameterTable"]


@dataclass(frozen=True)
class Parameter:
    """One fitted (or held) parameter.

    Attributes
    ----------
    name : str
        Identifier, unique in its table.
    value : float
        Fitted (or held) value [``unit``]; finite.
    stderr : float
        Standard error [``unit``], ``>= 0``; NaN when the data do not determine it or it was
        held fixed.
    lower, upper : float
        Search range [``unit``] (``-inf``/``inf``: unbounded), ``lower <= value <= upper``.
    unit : str
        SI unit (``"1"`` or ``""``: dimensionless).
    identified : bool
        The data determine it (:func:`iwan_element.fitting.verdict`).
    nuisance : bool
        Fitted so the others are right (a sensor offset, a starting state), of no interest
        in itself.
    fixed : bool
        Given, not fitted.
    """

    name: str
    value: float
    stderr: float = math.nan
    lower: float = -math.inf
    upper: float = math.inf
    unit: str = ""
    identified: bool = False
    nuisance: bool = False
    fixed: bool = False

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"name must be a non-empty str, got {self.name!r}")
        for k in ("value", "stderr", "lower", "upper"):
            v = getattr(self, k)
            if isinstance(v, (bool, str)) or not np.isscalar(v) or np.iscomplexobj(v):
                raise ValueError(f"{self.name}: {k} must be a real number, got {v!r}")
            object.__setattr__(self, k, float(v))
        if not math.isfinite(self.value):
            raise ValueError(f"{self.name}: value must be finite, got {self.value}")
        if not (math.isnan(self.stderr) or 0.0 <= self.stderr < math.inf):
            raise ValueError(
                f"{self.name}: stderr must be >= 0 and finite, or NaN (not "
                f"determined), got {self.stderr}"
            )
        if math.isnan(self.lower) or math.isnan(self.upper) or self.lower > self.upper:
            raise ValueError(
                f"{self.name}: bounds must be ordered, lower <= upper, got "
                f"[{self.lower}, {self.upper}]"
            )
        if not self.lower <= self.value <= self.upper:
            raise ValueError(
                f"{self.name}: value {self.value:g} must lie in its bounds "
                f"[{self.lower:g}, {self.upper:g}]"
            )
        for k in ("identified", "nuisance", "fixed"):
            v = getattr(self, k)
            if not isinstance(v, (bool, np.bool_)):
                raise ValueError(f"{self.name}: {k} must be True or False, got {v!r}")
            object.__setattr__(self, k, bool(v))
        if not isinstance(self.unit, str):
            raise ValueError(f"{self.name}: unit must be a str, got {self.unit!r}")

    @property
    def status(self) -> str:
        """The report's status column; it follows ``identified``, ``nuisance`` and ``fixed``."""
        if self.fixed:
            return "given (not fitted)"
        if self.nuisance:
            return "nuisance (fitted)" if self.identified else "nuisance, not determined"
        return "identified" if self.identified else "NOT identified"

    def to_dict(self) -> dict:
        """JSON-safe dict (NaN and inf become None)."""
        return json_safe(
            {
                "name": self.name,
                "value": self.value,
                "stderr": self.stderr,
                "lower": self.lower,
                "upper": self.upper,
                "unit": self.unit,
                "identified": self.identified,
                "nuisance": self.nuisance,
                "fixed": self.fixed,
            }
        )


@dataclass(frozen=True, eq=False)
class ParameterTable:
    """Immutable, ordered mapping ``name -> Parameter``: a fit result's ``params``.

    ``table[name]``, ``name in table``, ``iter(table)`` (names), ``len``, ``keys()`` and
    ``items()`` work as for a dict; ``values``, ``stderr`` and ``identified`` are dict views
    (properties, so ``table.values["Fs"]`` is the value of ``Fs``).

    Parameters
    ----------
    parameters : iterable of Parameter
        In the order of the report; names must be unique.
    correlation : array_like, shape (n, n), optional
        Correlation matrix in the same order (NaN where a parameter has no standard error).
    """

    parameters: tuple
    correlation: np.ndarray | None = field(default=None, repr=False)
    _index: dict[str, int] = field(init=False, repr=False)  # name -> position

    def __post_init__(self):
        ps = tuple(self.parameters)
        if not all(isinstance(p, Parameter) for p in ps):
            raise ValueError("parameters must be Parameter objects")
        names = [p.name for p in ps]
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise ValueError(f"parameter names must be unique, repeated: {dup}")
        object.__setattr__(self, "parameters", ps)
        object.__setattr__(self, "_index", {n: k for k, n in enumerate(names)})
        if self.correlation is not None:
            c = np.array(self.correlation, float)
            if c.shape != (len(ps), len(ps)):
                raise ValueError(
                    f"correlation must have shape ({len(ps)}, {len(ps)}), got {c.shape}"
                )
            c.setflags(write=False)
            object.__setattr__(self, "correlation", c)

    def __getitem__(self, name: str) -> Parameter:
        return self.parameters[self._index[name]]

    def __iter__(self):
        return (p.name for p in self.parameters)

    def __len__(self) -> int:
        return len(self.parameters)

    def __contains__(self, name) -> bool:
        return name in self._index

    def keys(self) -> tuple:
        """Parameter names in order."""
        return self.names

    def items(self) -> Iterator[tuple[str, Parameter]]:
        """``(name, Parameter)`` pairs in order."""
        return ((p.name, p) for p in self.parameters)

    def get(self, name: str, default=None) -> Parameter | Any:
        """The parameter ``name``, or ``default``."""
        return self[name] if name in self._index else default

    @property
    def names(self) -> tuple:
        """Parameter names in order."""
        return tuple(self)

    @property
    def values(self) -> dict:
        """``{name: value}`` (a new dict)."""
        return {p.name: p.value for p in self.parameters}

    @property
    def stderr(self) -> dict:
        """``{name: stderr}`` (a new dict; NaN: not determined)."""
        return {p.name: p.stderr for p in self.parameters}

    @property
    def identified(self) -> dict:
        """``{name: identified}`` (a new dict)."""
        return {p.name: p.identified for p in self.parameters}

    def array(self, names=None) -> np.ndarray:
        """Values of ``names`` (default all) as a new array, in that order."""
        return np.array([self[n].value for n in (names or self.names)], float)

    def report(self) -> str:
        """One row per parameter: name [unit], value, std. error, status."""
        labels = [f"{p.name} [{unit_label(p.unit)}]" for p in self.parameters]
        width = max([16] + [len(s) for s in labels])
        errors = [
            "" if p.fixed else f"{p.stderr:.4g}" if math.isfinite(p.stderr) else "n/a"
            for p in self.parameters
        ]
        return "\n".join(
            table_lines(
                [
                    ("parameter", f"<{width}"),
                    ("value", "12.6g"),
                    ("std. error", ">12"),
                    ("  status", "<"),
                ],
                [
                    (lab, p.value, se, f"  {p.status}")
                    for lab, p, se in zip(labels, self.parameters, errors)
                ],
            )
        )

    def to_dict(self) -> dict:
        """JSON-safe dict: ``{"parameters": [...], "correlation": ...}``."""
        return json_safe(
            {"parameters": [p.to_dict() for p in self.parameters], "correlation": self.correlation}
        )

    def _repr_html_(self) -> str:
        return html_table("parameters", PARAMETER_COLUMNS, parameter_rows(self))

    def to_dataframe(self) -> pd.DataFrame:
        """The table as a ``pandas.DataFrame`` (one row per parameter: value, std. error,
        unit, status; pandas imported only here: ``pip install "iwan-element[pandas]"``).
        """
        try:
            import pandas as pd
        except ImportError:
            raise ImportError(
                "to_dataframe needs pandas: pip install 'iwan-element[pandas]'"
            ) from None
        return pd.DataFrame(parameter_rows(self), columns=list(PARAMETER_COLUMNS))
