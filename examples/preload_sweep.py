"""Preload sweep of the example lap-jointed beam: the family of f(X), zeta(X) curves.

Each preload is one ensemble task: the quasi-static modal analysis (QSMA) of the first
bending mode of ``iwan_element.models.specimens.presets.preset("example")`` (two 200 x 40 x 10 mm
steel beams, one M16 bolt, clamped-free) with the bolt preload changed. In the specimen
model the preload sets the normal force of each contact point through the pressure cone, and
so its slip force ``mu N``; the tangential stiffness follows the contact area (see
``models/specimens/contact.py``). The runs go to local processes by default or to a Dask cluster.

    python examples/preload_sweep.py                     # 8 preloads, local processes
    python examples/preload_sweep.py --quick             # 3 preloads, serial (test suite)
    python examples/preload_sweep.py --friction 0.2 0.3 0.4      # preload x friction grid
    python examples/preload_sweep.py --bolts 1 2         # preload x bolt count grid
    python examples/preload_sweep.py --scheduler tcp://scheduler:8786
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from iwan_element.models.specimens import preset
from iwan_element.models.studies import specimen_curve_task

from iwan_element.ensemble import parameter_grid, run_ensemble


def quiet_task(params, rng, **kwargs):
    """specimen_curve_task without Exudyn's solver banner on stdout."""
    with contextlib.redirect_stdout(io.StringIO()):
        return specimen_curve_task(params, rng, **kwargs)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="3 preloads, 6 amplitudes, serial")
    ap.add_argument("--preloads", type=float, nargs="+", default=None, help="[N]")
    ap.add_argument("--friction", type=float, nargs="+", default=None)
    ap.add_argument("--bolts", type=int, nargs="+", default=None, help="bolt counts")
    ap.add_argument("--scheduler", default=None, help="Dask scheduler address")
    ap.add_argument("--out", default="preload_sweep.png")
    args = ap.parse_args(argv)

    specimen = preset("example")
    preloads = args.preloads or (
        [5e3, 15e3, 30e3] if args.quick else [2.5e3, 5e3, 7.5e3, 10e3, 15e3, 20e3, 30e3, 40e3]
    )
    axes = {"preload": preloads}
    if args.friction:
        axes["friction"] = args.friction
    if args.bolts:
        axes["n_bolts"] = args.bolts
    sets = parameter_grid(**axes)
    amplitudes = np.geomspace(1e-6, 1e-3, 6 if args.quick else 16)
    task = functools.partial(quiet_task, specimen=specimen, amplitude=amplitudes)
    client = None
    executor = "serial" if args.quick else None
    if args.scheduler:
        from distributed import Client

        client = Client(args.scheduler)
        executor = client
    try:
        res = run_ensemble(task, sets, executor=executor, seed=0, progress=not args.quick)
    finally:
        if client is not None:
            client.close()
    print(res.report())

    fig, (ax_f, ax_z) = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    colors = plt.cm.viridis(np.linspace(0, 0.9, len(res.rows)))
    for row, c in zip(res.rows, colors):
        if not np.all(np.isfinite(row["frequency"])):
            continue  # a failed task (listed in the report)
        label = ", ".join(
            f"{k} {v / 1e3:g} kN" if k == "preload" else f"{k} {v:g}"
            for k, v in row.items()
            if k in axes
        )
        ax_f.plot(row["amplitude"], row["frequency"], "-o", ms=3, color=c, label=label)
        ax_z.plot(row["amplitude"], row["damping_ratio"], "-o", ms=3, color=c)
    for a in (ax_f, ax_z):
        a.set_xscale("log")
        a.set_xlabel("transverse displacement amplitude at the sensor [m]")
    ax_z.set_yscale("log")
    ax_f.set_ylabel("frequency of mode 1 [Hz]")
    ax_z.set_ylabel("damping ratio [-]")
    ax_f.legend(fontsize=7)
    fig.suptitle(
        f"{specimen.name} specimen, QSMA: family of curves over "
        f"{', '.join(axes)} ({len(sets)} runs, {res.executor})"
    )
    out = Path(args.out)
    fig.savefig(out, dpi=120)
    plt.close(fig)
    csv = res.to_csv(out.with_suffix(".csv"))
    print(f"saved {out} and {csv}")
    return {"result": res, "figure": out, "csv": csv}


if __name__ == "__main__":
    main()
