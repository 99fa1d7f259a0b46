"""The one shape every result object of the package has.

Every fit, curve, diagnosis, ensemble and uncertainty result offers (the contract checked by
``tests/test_api_shape.py`` on every public result class):

* ``report() -> str``: a human-readable summary opening with the verdict line, units in
  brackets;
* ``to_dict() -> dict``: JSON-safe (``json.dumps(..., allow_nan=False)`` works);
* ``warnings``: a tuple of str, what the data could not support;
* ``success``: bool, whether the result can be used as it stands;
* ``plot(ax=None)``: draws the result and returns the list of matplotlib artists. The axes
  contract is one for all: ``ax`` is ``None`` (a new figure with the result's
  ``plot_panels`` panels), one Axes (results with one panel) or a sequence of
  ``plot_panels`` Axes (:func:`panels`);
* ``verdict() -> str``: the report's first line, ``success`` in a tester's words: "usable"
  or "NOT usable: <reasons>" (:meth:`ResultShape.failure_reasons`);
* ``_repr_html_()``: the result in a notebook as HTML tables: the verdict on top, then
  the tables of :meth:`ResultShape._tables` (parameters, goodness of fit, data), then the
  warnings;
* ``to_dataframe(table=None)``: one of those tables as a ``pandas.DataFrame``, by default
  the first, the main one (pandas is imported only then: ``pip install
  "iwan-element[pandas]"``). Column titles read ``name [unit]``, SI, ``[-]`` for a
  dimensionless number (:func:`~iwan_element.base.columns.column`); captions are the
  tables' fixed titles.

:class:`ResultShape` supplies the notebook representation, the data frames and the panel
count from one hook, :meth:`ResultShape._tables` (titled rows built from what the class
exposes); each class supplies the rest.
"""

from __future__ import annotations

import html
import itertools
import math
import numbers
import textwrap
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from .columns import column, title_of, unit_label

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.axes import Axes

__all__ = [
    "column",
    "ResultShape",
    "panels",
    "axes_or_new",
    "table_lines",
    "unit_label",
    "format_value",
    "value_stderr",
    "parameter_rows",
    "html_table",
    "wrap",
    "PARAMETER_COLUMNS",
]

#: Rows an HTML table shows before it shows only its ends.
HTML_ROWS = 40

#: Column titles of a parameter table (:func:`parameter_rows`).
PARAMETER_COLUMNS = ("parameter", "value", "std. error", "unit", "status")


def format_value(x, digits: int = 6) -> str:
    """A number for a table: ``digits`` significant digits, exponent notation outside
    1e-3 .. 1e5 (no ``33366692.9``), ``nan`` and ``inf`` spelled; other values as ``str``.
    """
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, numbers.Real):
        return str(x)
    x = float(x)
    if not math.isfinite(x):
        return str(x)
    if x != 0.0 and not 1e-3 <= abs(x) < 1e5:
        return f"{x:.{max(digits - 2, 1)}e}"
    return f"{x:.{digits}g}"


def wrap(text: str, *, width: int = 92, indent: str = "  ") -> list[str]:
    """A long report line wrapped to ``width`` columns, continuation lines indented."""
    return textwrap.wrap(text, width=width, subsequent_indent=indent, break_on_hyphens=False) or [
        text
    ]


def value_stderr(pairs) -> dict:
    """``{name: {"value": v, "stderr": se}}`` from ``{name: (v, se)}`` or ``{name: v}``
    (stderr ``None`` when not given or not finite): the one layout of offsets and other
    estimated quantities in every ``to_dict``.
    """

    def num(x):
        return float(x) if x is not None and math.isfinite(float(x)) else None

    out = {}
    for k, v in pairs.items():
        v, se = v if isinstance(v, (tuple, list)) else (v, None)
        out[str(k)] = {"value": num(v), "stderr": num(se)}
    return out


def parameter_rows(params) -> list:
    """Rows of :data:`PARAMETER_COLUMNS` for a ``ParameterTable`` (anything with
    ``parameters`` holding ``name, value, stderr, unit, status``).
    """
    return [
        (p.name, float(p.value), float(p.stderr), unit_label(p.unit), p.status)
        for p in params.parameters
    ]


@dataclass(frozen=True, eq=False, kw_only=True)
class ResultShape:
    """Base of the package's result classes (frozen dataclasses): the ``warnings`` field
    (keyword-only, a tuple of str, empty by default), ``plot_panels`` (how many Axes ``plot``
    draws on) and ``_repr_html_`` (the report in a notebook).
    """

    plot_panels: ClassVar[int] = 1
    #: ``{to_dict key: (title, unit[, scale])}``: the class's own column and quantity
    #: titles, over the shared :data:`~iwan_element.base.columns.QUANTITIES`.
    COLUMNS: ClassVar[dict] = {}
    warnings: tuple = ()

    if TYPE_CHECKING:  # every result defines these (a field or a property; a method)

        @property
        def success(self) -> bool:
            """True when the result can be used as it stands."""
            ...

        def to_dict(self) -> dict:
            """The result as plain Python values (JSON-ready)."""
            ...

    def _fold_failures(self) -> None:
        """In ``__post_init__`` of a result with a ``failures`` field: ``failures`` and
        ``warnings`` made tuples of str, each failure also among the warnings (once), so a
        reader of the warnings alone sees why the result is not usable.
        """
        failures = tuple(str(w) for w in getattr(self, "failures", ()))
        object.__setattr__(self, "failures", failures)
        object.__setattr__(
            self,
            "warnings",
            tuple(str(w) for w in self.warnings)
            + tuple(w for w in failures if w not in self.warnings),
        )

    def failure_reasons(self) -> tuple:
        """Why ``success`` is False, each reason in a tester's words (empty when it is True).
        The base reads the result's ``failures`` (the reasons its maker stated where it
        decided ``success``), else the warnings; a class whose verdict has its own reasons
        (a parameter the data do not identify, a misfit beyond the noise) states them.
        """
        if self.success:
            return ()
        return (
            tuple(getattr(self, "failures", ()))
            or tuple(self.warnings)
            or ("the result did not meet its own success rule",)
        )

    def verdict(self) -> str:
        """One line: whether the result can be used as it stands, and if not, why."""
        reasons = self.failure_reasons()
        return "usable" if not reasons else "NOT usable: " + "; ".join(reasons)

    def _tables(self) -> list:
        """The result's tables, ``[(title, column titles, rows), ...]``: what the notebook
        shows and :meth:`to_dataframe` returns. The default reads what the class exposes:
        its ``params`` (a ``ParameterTable``) as "parameters", the ``rows`` of its
        ``to_dict()`` (one dict per row) as "rows", its flat numeric lists of one length as
        "data" (one column each; the longest group, lists of other lengths after it, titled
        by their columns), and its scalar ``to_dict()`` entries as "goodness of fit and run"
        (quantity, value). Columns and quantities are titled by :attr:`COLUMNS` and the
        shared :data:`~iwan_element.base.columns.QUANTITIES` (``name [unit]``, a fraction
        shown in % where the title says so). Classes with data of their own (curves, bands,
        time series) put those first: the first table is the main one.
        """
        out: list[tuple[str, tuple, list]] = []
        params = getattr(self, "params", None)
        if params is not None and hasattr(params, "parameters") and len(params.parameters):
            out.append(("parameters", PARAMETER_COLUMNS, parameter_rows(params)))
        d = self.to_dict()
        out += self._row_table(d.get("rows"))
        columns: dict[int, list[str]] = {}  # keys of the numeric lists, by length
        for k, v in d.items():
            if k != "rows" and isinstance(v, list) and v and all(_number(x) for x in v):
                columns.setdefault(len(v), []).append(k)
        for i, (_, keys) in enumerate(sorted(columns.items(), reverse=True)):
            titled = [title_of(k, self.COLUMNS) for k in keys]
            rows = [
                tuple(_scaled(x, s) for x, (_, s) in zip(r, titled))
                for r in zip(*(d[k] for k in keys))
            ]
            out.append(
                (
                    "data" if i == 0 else ", ".join(t for t, _ in titled),
                    tuple(t for t, _ in titled),
                    rows,
                )
            )
        stats = [
            (k, v)
            for k, v in d.items()
            if k not in ("warnings", "success")
            and (
                isinstance(v, (numbers.Real, bool))
                or v is None
                or (isinstance(v, str) and len(v) <= 200)
            )
        ]
        if stats:
            out.append(
                ("goodness of fit and run", ("quantity", "value"), self._quantity_rows(stats))
            )
        return out

    def _row_table(self, rows) -> list:
        """``[("rows", titles, rows)]`` from a list of dicts (one per row), or ``[]``."""
        if not (isinstance(rows, list) and rows and all(isinstance(r, dict) for r in rows)):
            return []
        keys = tuple(
            dict.fromkeys(k for r in rows for k, v in r.items() if not isinstance(v, (dict, list)))
        )
        titled = [title_of(k, self.COLUMNS) for k in keys]
        return [
            (
                "rows",
                tuple(t for t, _ in titled),
                [tuple(_scaled(r.get(k), s) for k, (_, s) in zip(keys, titled)) for r in rows],
            )
        ]

    def _quantity_rows(self, pairs) -> list:
        """``(title, value)`` rows of a quantity table from ``(to_dict key, value)`` pairs:
        titles and scales of :meth:`COLUMNS` and the shared quantities.
        """
        out = []
        for k, v in pairs:
            title, scale = title_of(k, self.COLUMNS)
            out.append((title, _scaled(v, scale)))
        return out

    def to_dataframe(self, table: str | None = None) -> pd.DataFrame:
        """One of the result's tables (:meth:`_tables`) as a ``pandas.DataFrame``.

        Parameters
        ----------
        table : str, optional
            Its title; default the first (the parameters, or the data of a curve).

        Raises
        ------
        ValueError
            No table of that title (the message lists them).
        ImportError
            pandas is not installed (``pip install "iwan-element[pandas]"``).
        """
        tables = self._tables()
        titles = [t for t, _, _ in tables]
        if table is None and tables:
            table = titles[0]
        if table not in titles:
            raise ValueError(f"table must be one of {titles}, got {table!r}")
        try:
            import pandas as pd
        except ImportError:
            raise ImportError(
                "to_dataframe needs pandas: pip install 'iwan-element[pandas]'"
            ) from None
        _, cols, rows = tables[titles.index(table)]
        return pd.DataFrame([list(r) for r in rows], columns=list(cols))

    def _repr_html_(self) -> str:
        """The verdict, the tables and the warnings as HTML (a notebook's display)."""
        ok = "usable" if self.success else "NOT usable"
        color = "#1a7f37" if self.success else "#b42318"
        parts = [
            f'<div class="iwan-result"><p><b>{html.escape(type(self).__name__)}</b>: '
            f'<span style="color:{color}">{html.escape(self.verdict() or ok)}</span></p>'
        ]
        for title, cols, rows in self._tables():
            parts.append(html_table(title, cols, rows))
        if self.warnings:
            parts.append(
                "<p><b>warnings</b></p><ul>"
                + "".join(f"<li>{html.escape(str(w))}</li>" for w in self.warnings)
                + "</ul>"
            )
        return "".join(parts) + "</div>"


def _number(x) -> bool:
    return x is None or (isinstance(x, numbers.Real) and not isinstance(x, (bool, np.bool_)))


def _scaled(x, scale: float):
    """``x * scale`` for a number (``scale`` 100: a fraction shown in %), else ``x``."""
    if scale == 1.0 or x is None or not _number(x):
        return x
    return float(x) * scale


def html_table(title: str, columns, rows) -> str:
    """One titled HTML table; numbers right-aligned and formatted (:func:`format_value`)."""
    head = "".join(f"<th>{html.escape(str(c))}</th>" for c in columns)
    body = []
    rows = list(rows)
    cut = len(rows) > HTML_ROWS
    if cut:  # a long table shows its ends (to_dataframe has every row)
        n = len(rows)
        gap = (f"... {n - HTML_ROWS} rows more in to_dataframe()",) + ("...",) * (len(columns) - 1)
        rows = rows[: HTML_ROWS - 5] + [gap] + rows[-5:]
    for r in rows:
        cells = []
        for v in r:
            num = isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_))
            text = "" if v is None else format_value(v) if num else str(v)
            align = ' style="text-align:right"' if num else ""
            cells.append(f"<td{align}>{html.escape(text)}</td>")
        body.append("<tr>" + "".join(cells) + "</tr>")
    return (
        f"<table><caption>{html.escape(title)}</caption><thead><tr>{head}</tr></thead>"
        f"<tbody>{''.join(body)}</tbody></table>"
    )


def table_lines(columns, rows, *, indent: int = 2) -> list[str]:
    """The lines of a fixed-width table in a report: a header, then one line per row.

    Parameters
    ----------
    columns : sequence of (str, str)
        ``(title, format spec)`` per column; the spec is Python's (``"<26"``, ``"9.4g"``,
        ``"11.4e"``), and the title takes its width and alignment (right unless the spec
        starts with ``<`` or ``^``).
    rows : iterable of sequences
        The values of each row, one per column.
    indent : int, keyword-only
        Spaces before each line.
    """
    pad = " " * indent
    heads = []
    for title, spec in columns:
        align = spec[0] if spec[:1] in ("<", ">", "^") else ">"
        width = "".join(itertools.takewhile(str.isdigit, spec.lstrip("<>^")))
        heads.append(format(title, f"{align}{width}"))
    out = [pad + " ".join(heads)]
    for row in rows:
        out.append(pad + " ".join(format(v, spec) for v, (_, spec) in zip(row, columns)))
    return out


def panels(ax, n: int, *, figsize=None, sharex: bool = False) -> list:
    """The ``n`` Axes a result draws on, from its ``ax`` argument (the contract above).

    Raises
    ------
    TypeError
        ``ax`` is neither ``None``, one Axes (``n == 1``) nor a sequence of ``n`` Axes.
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, grid = plt.subplots(  # constrained: labels and legends fit inside the figure
            n,
            1,
            sharex=sharex,
            squeeze=False,
            figsize=figsize or (6.0, 3.2 * n),
            layout="constrained",
        )
        return list(grid[:, 0])
    if hasattr(ax, "plot"):
        if n != 1:
            raise TypeError(
                f"ax must be None or a sequence of {n} Axes (this result draws "
                f"{n} panels), got one Axes"
            )
        return [ax]
    try:
        axs = list(ax)
    except TypeError:
        raise TypeError(
            f"ax must be None, one Axes or a sequence of {n} Axes, got {type(ax).__name__}"
        ) from None
    if len(axs) != n or not all(hasattr(a, "plot") for a in axs):
        raise TypeError(f"ax must be a sequence of {n} Axes for this result, got {len(axs)} items")
    return axs


def axes_or_new(ax) -> Axes:
    """One matplotlib Axes: ``ax`` itself, or a new figure's if ``None`` (the one-panel case
    of the axes contract, :func:`panels`).
    """
    if ax is None:
        try:
            import matplotlib.pyplot  # noqa: F401
        except ImportError as exc:  # pragma: no cover - depends on the environment
            raise ImportError("plotting needs matplotlib: pip install matplotlib") from exc
    return panels(ax, 1, figsize=(6.4, 4.8))[0]
