"""Progress bars: the package's one way to show how far a long call is (tqdm, optional).

Every call that can take more than a few seconds (``fit_decay``, ``diagnose``,
``diagnose_many``, ``fit_campaign``, ``run_ensemble``, ``propagate_uncertainty``, the beam
model's ``calibrate``, ``ringdown`` and ``forced_response``) takes ``progress=False``; with
``progress=True`` it shows a tqdm bar with a total (exact, or an upper bound the bar lowers to
the count reached when the call ends) and so an ETA. Bars are off by default and stay silent
under continuous integration (the ``CI`` environment variable set, as every CI service does),
so scripts and test logs are not cluttered. tqdm is an optional extra:
``pip install "iwan-element[progress]"``.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

__all__ = ["progress_bar", "tick", "set_total", "finish"]


def progress_bar(progress, *, total=None, desc: str, unit: str) -> Any:
    """A tqdm bar when ``progress`` is True (and not under CI), else ``None``.

    Parameters
    ----------
    progress : bool
        The caller's ``progress`` argument.
    total : int, optional, keyword-only
        Steps expected (an upper bound is fine: :func:`finish` sets the count reached).
    desc, unit : str, keyword-only
        Label of the bar and name of one step.

    Raises
    ------
    ValueError
        ``progress`` is not a bool.
    ImportError
        ``progress=True`` without tqdm installed.
    """
    if not isinstance(progress, (bool, np.bool_)):
        raise ValueError(f"progress must be True or False, got {progress!r}")
    if not progress or os.environ.get("CI"):
        return None
    try:
        from tqdm.auto import tqdm
    except ImportError:
        raise ImportError(
            "progress=True needs tqdm: pip install 'iwan-element[progress]'"
        ) from None
    return tqdm(total=None if total is None else int(total), desc=desc, unit=unit)


def tick(bar, n: int = 1, *, text: str | None = None) -> None:
    """Advance ``bar`` (``None``: nothing) by ``n`` steps, optionally naming the current
    work; a total that turned out too small grows with the count.
    """
    if bar is None:
        return
    if text is not None:
        bar.set_postfix_str(text, refresh=False)
    if bar.total is not None and bar.n + n > bar.total:
        bar.total = bar.n + n
    bar.update(n)


def set_total(bar, total: int) -> None:
    """Set the expected number of steps once the caller knows it."""
    if bar is not None:
        bar.total = max(int(total), bar.n)
        bar.refresh()


def finish(bar) -> None:
    """Close ``bar`` at the count reached (an upper-bound total is lowered to it)."""
    if bar is None:
        return
    if bar.total is not None and bar.n < bar.total:
        bar.total = bar.n
        bar.refresh()
    bar.close()
