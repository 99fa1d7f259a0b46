"""Prediction bands from a fit's uncertainty: the shipped example test, fitted and propagated.

1. Fit the four Iwan parameters to the shipped (synthetic) quasi-static test record with
   ``fit_loops``; the fit returns standard errors and correlations.
2. Sample parameter sets from that covariance (in the fit's coordinates ln Fs, ln KT, chi,
   ln(1 + beta), rejecting draws outside the model's range).
3. Run each set through a single-mode structure carrying the joint (mass 10 kg, a parallel
   spring of half the joint's stiffness, 0.1 % viscous floor): the closed-form frequency and
   damping against amplitude and the peak of a transient run under a harmonic force at the
   linear frequency.
4. Save the bands (5 %-95 %) as a figure and the sampled runs as CSV.

    python examples/uncertainty_bands.py                 # 200 samples on local processes
    python examples/uncertainty_bands.py --quick         # 16 samples, serial (the test suite)
    python examples/uncertainty_bands.py --scheduler tcp://scheduler:8786   # on a Dask cluster
    python examples/uncertainty_bands.py --inflate 20    # what a 20x wider covariance means

The synthetic record is nearly noise-free, so the bands of the fit itself are narrow (tenths
of a per cent); ``--inflate`` scales the standard errors to show how a poorer test widens them.
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from iwan_element.models import example_test_path

import iwan_element as ie


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="16 samples, serial, short transient")
    ap.add_argument("--samples", type=int, default=200)
    ap.add_argument("--force", type=float, default=400.0, help="forcing amplitude [N]")
    ap.add_argument(
        "--inflate",
        type=float,
        default=1.0,
        help="scale the fit's standard errors by this factor (>= 1)",
    )
    ap.add_argument(
        "--scheduler", default=None, help="address of a Dask scheduler (default: local processes)"
    )
    ap.add_argument("--out", default="uncertainty_bands.png")
    args = ap.parse_args(argv)

    data = ie.load_test(example_test_path())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ie.IdentifiabilityWarning)
        fit = ie.fit_loops(t=data.t, u=data.u, F=data.F)  # keywords: safe for any order
    print(fit.report())
    unc = ie.ParameterUncertainty.from_fit(fit)
    if args.inflate != 1.0:
        if args.inflate < 1.0:
            raise SystemExit("--inflate must be >= 1")
        unc = ie.ParameterUncertainty(
            unc.nominal,
            unc.names,
            unc.mean,
            unc.cov * args.inflate**2,
            source=f"{unc.source}, std. errors x {args.inflate:g}",
            warnings=unc.warnings,
        )
    system = ie.SingleModeSystem(mass=10.0, stiffness=0.5 * fit.joint.KT, zeta0=1e-3)
    amplitudes = np.geomspace(1e-6, 1.5 * fit.joint.phi_max, 12 if args.quick else 30)
    client = None
    executor = "serial" if args.quick else None
    if args.scheduler:
        from distributed import Client

        client = Client(args.scheduler)
        executor = client
    try:
        bands = ie.propagate_uncertainty(
            unc,
            system=system,
            amplitude=amplitudes,
            n_samples=16 if args.quick else args.samples,
            force=args.force,
            cycles=8 if args.quick else 30,
            seed=2026,
            executor=executor,
            progress=not args.quick,
        )
    finally:
        if client is not None:
            client.close()
    print(bands.report())
    fig, axes = plt.subplots(2, 3, figsize=(13, 7.5), layout="constrained")
    bands.plot(ax=axes[0])
    bands.plot(ax=axes[1], relative=True)  # the same bands as % of the nominal curve
    axes[1, 2].clear()  # (its peak panel repeats the one above)
    axes[1, 2].axis("off")
    axes[1, 2].text(
        0,
        0.5,
        "\n".join(
            [
                f"fit: {bands.uncertainty.source}",
                f"nominal {fit.joint}".replace(", ", ",\n  "),
                f"system: m = {system.mass:g} kg, K_inf = "
                f"{system.stiffness:.3g} N/m, zeta0 = {system.zeta0:g}",
            ]
        ),
        fontsize=8,
        va="center",
    )
    fig.suptitle(
        f"Iwan joint fitted to the example test: {100 * bands.level:.0f} % prediction "
        f"bands ({bands.frequency.shape[0]} samples, {bands.ensemble.executor})"
    )
    out = Path(args.out)
    fig.savefig(out, dpi=120)
    plt.close(fig)
    csv = bands.ensemble.to_csv(out.with_suffix(".csv"))
    print(f"saved {out} and {csv}")
    return {"bands": bands, "figure": out, "csv": csv}


if __name__ == "__main__":
    main()
