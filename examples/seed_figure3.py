"""Draw the seed paper's Fig. 3: normalised hysteresis loops of the Iwan joint.

Run:  python examples/seed_figure3.py [--out out/seed_figure3.png]

Panel (a): (beta, chi) = (0, 1/2) and (1, 1/2); panel (b): (-1/2, 1) and (1/2, -1/2), with
s0 = 1 and s = -1:0.002:1 as in the paper (eqs. 12, 13 and the corrected eq. 15). The case
beta = -1/2 is non-physical (negative spike stiffness) and is drawn only as a dimensionless
curve; the library warns about it, and this script says so on the figure.
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from iwan_element.plotting import plot_normalized_loops

PANELS = {
    "(a) beta=0, chi=1/2 and beta=1, chi=1/2": [(0.0, 0.5), (1.0, 0.5)],
    "(b) beta=-1/2, chi=1 and beta=1/2, chi=-1/2": [(-0.5, 1.0), (0.5, -0.5)],
}


def main(argv=None) -> Path:
    ap = argparse.ArgumentParser(description="Draw the seed paper's Fig. 3 to PNG.")
    ap.add_argument("--out", type=Path, default=Path("out/seed_figure3.png"), help="PNG path")
    args = ap.parse_args(argv)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.8))
    for ax, (title, cases) in zip(axes, PANELS.items()):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            plot_normalized_loops(cases, ax=ax)
        note = "; ".join(sorted({str(w.message).split(";")[0] for w in caught}))
        ax.set_title(title + ("\n" + note if note else ""), fontsize=9)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=120)
    plt.close(fig)
    print(f"wrote {args.out}")
    return args.out


if __name__ == "__main__":
    main()
