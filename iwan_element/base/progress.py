"""Progress bars: the package's one way to show how far a long call is (tqdm, optional).

Every call that can take more than a few seconds (``fit_decay``, ``diagnose``,
``diagnose_many``, ``fit_campaign``, ``run_ensemble``, ``propagate_uncertainty``, the beam
model's ``calibrate``, ``ringdown`` and ``forced_response``) takes ``progress=False``; with
``progress=True`` it shows a tqdm bar with a total fixed when it opens, and so an ETA. The total
is exact or, where the work depends on the data (an optimiser's evaluations, the selection's
rounds), the call's budget: the ETA is then an upper bound, and the steps the call did not
need are counted done when it ends (:func:`complete`), so the bar never changes its total.
Bars are off by default and stay silent under continuous integration (the ``CI`` environment
variable set, as every CI service does), so scripts and test logs are not cluttered. tqdm is an
optional extra: ``pip install "iwan-element[progress]"``.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

__all__ = ["progress_bar", "tick", "complete", "finish"]


def progress_bar(progress, *, total=None, desc: str, unit: str) -> Any:
    """A tqdm bar when ``progress`` is True (and not under CI), else ``None``.

    Parameters
    ----------
    progress : bool
        The caller's ``progress`` argument.
    total : int, optional, keyword-only
        Steps expected, fixed for the bar's life: exact, or the call's budget (the steps it
        may take at most; :func:`complete` counts those it did not need).
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
    work; the count stops at the total (which never changes).
    """
    if bar is None:
        return
    if text is not None:
        bar.set_postfix_str(text, refresh=False)
    if bar.total is not None:
        n = min(n, int(bar.total) - bar.n)
    if n > 0:
        bar.update(n)


def complete(bar, text: str = "the rest not needed") -> None:
    """Count the steps of ``bar``'s budget the call did not need as done (it ended early: an
    optimiser converged, the selection stopped), so that the bar ends at its fixed total.
    """
    if bar is None or bar.total is None or bar.n >= bar.total:
        return
    bar.set_postfix_str(text, refresh=False)
    bar.update(int(bar.total) - bar.n)


def finish(bar) -> None:
    """Close ``bar`` (``None``: nothing) where it is: its total is never changed, so a call
    that failed shows how far it came.
    """
    if bar is not None:
        bar.close()
