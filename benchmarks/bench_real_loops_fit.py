"""Plain Iwan loop fit on the real damper records of ``../shared/data/arts-damper``.

The records (a banded rotary friction damper; CC BY-SA 4.0, see the data set's README) have
backlash and a break-away peak after each reversal, which a plain Iwan joint does not have: an
honest fit reports the systematic misfit (a large residual correlation time ``tau``) and widens
its standard errors by ``sqrt(tau)``, and does not call a parameter at a bound or with a
standard error above half its value identified. This prints one row per record: offsets,
parameters with standard errors (``*`` = identified), success, NRMSE, tau and the fit time.
Records are skipped cleanly when the shared data are absent.

Run::

    python benchmarks/bench_real_loops_fit.py [--data ../shared/data/arts-damper] [--markdown]
"""

from __future__ import annotations

import argparse
import math
import time
import warnings
from pathlib import Path

import numpy as np

from iwan_element import fit_loops
from iwan_element.identify.loops.result import IdentifiabilityWarning

_ROOT = Path(__file__).resolve().parents[1]
# ../shared next to the project (a checkout in /work/main or a worktree in /work/wt/<name>)
DEFAULT = next(
    (
        c
        for c in (
            _ROOT.parent / "shared" / "data" / "arts-damper",
            _ROOT.parent.parent / "shared" / "data" / "arts-damper",
        )
        if c.is_dir()
    ),
    _ROOT.parent / "shared" / "data" / "arts-damper",
)


def _pm(v, se, ident=None, fmt="{:.4g}"):
    s = fmt.format(v) + (" ± " + fmt.format(se) if math.isfinite(se) else " ± n/a")
    return s + ("*" if ident else "")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", type=Path, default=DEFAULT, help="folder with the CSV records")
    ap.add_argument("--markdown", action="store_true", help="print a Markdown table")
    a = ap.parse_args(argv)
    files = sorted(a.data.glob("*.csv")) if a.data.is_dir() else []
    if not files:
        print(f"no records under {a.data} (the shared data are absent): skipped")
        return
    head = [
        "record",
        "dF0 [N]",
        "du0 [um]",
        "Fs [N]",
        "KT [kN/mm]",
        "chi",
        "beta",
        "success",
        "NRMSE %",
        "tau",
        "noise F [N]",
        "time [s]",
    ]
    rows = []
    for f in files:
        d = np.loadtxt(f, delimiter=",", skiprows=1)
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IdentifiabilityWarning)
            r = fit_loops(d[:, 0], d[:, 1], d[:, 2])
        dt = time.perf_counter() - t0
        p, se, idf = r.joint, r.stderr, r.identified
        (f0, sf0), (u0, su0) = r.offsets["force"], r.offsets["displacement"]
        rows.append(
            [
                f.stem,
                _pm(f0, sf0),
                _pm(u0 * 1e6, su0 * 1e6),
                _pm(p.Fs, se["Fs"], idf["Fs"]),
                _pm(p.KT * 1e-6, se["KT"] * 1e-6, idf["KT"]),
                _pm(p.chi, se["chi"], idf["chi"], "{:.3f}"),
                _pm(p.beta, se["beta"], idf["beta"], "{:.3f}"),
                str(r.success),
                f"{100 * r.nrmse:.2f}",
                f"{r.noise['tau']:.3g}",
                f"{r.noise['force']:.3g}",
                f"{dt:.2f}",
            ]
        )
    if a.markdown:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
        for row in rows:
            print("| " + " | ".join(row) + " |")
    else:
        w = [max(len(h), *(len(r[k]) for r in rows)) for k, h in enumerate(head)]
        print("  ".join(h.ljust(w[k]) for k, h in enumerate(head)))
        for row in rows:
            print("  ".join(c.ljust(w[k]) for k, c in enumerate(row)))
    print(
        "* = identified (finite std. error <= half the value, chi: of chi + 1, not at a bound); "
        "std. errors are widened by sqrt(tau)"
    )


if __name__ == "__main__":
    main()
