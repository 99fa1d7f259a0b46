"""One model of a friction damper over its test campaign, and a prediction of an untested record.

The ARTS banded rotary friction damper (CC BY-SA 4.0 records in ../shared/data/arts-damper
and arts-damper-ds2, see their READMEs for source and citation) was tested at several band
tensions [lb] and drive frequencies [Hz], in two campaigns a year apart. A damper designer
needs one model of the device valid over these conditions, and its behaviour at a condition
that was not tested. ``fit_campaign``:

1. diagnoses every record on its own (the README's recipe: a 20 Hz low-pass removes the rig's
   ringing), which names the effects each record shows (backlash, a direction-dependent grip);
2. fits one model of the device to all records at once, each parameter a law linear in the
   conditions (here: the slip force Fs linear in band tension and frequency, the other
   parameters constant over this small subset), with the force offset and the joint's
   starting state fitted per record as nuisances;
3. states each law coefficient with its standard error.

The held-out record is then predicted from its conditions alone (its force offset read from
its rest samples, a sensor zero) and compared with its measurement. Two figures are saved:
``campaign_parameters.png`` (the parameters against band tension and frequency: each record's
own estimate and the campaign law with its 95 % band) and ``campaign_prediction.png``.

The default (quick, about a minute and a half on one core) fits four dataset-1 records and
predicts a fifth; ``--all`` fits every other given record of both campaigns (28; tens of
minutes, use ``--jobs``) with per-campaign laws (docs/campaign.md section 8.2). The band of
the prediction carries the record-to-record scatter the campaign shows about its laws, not
only the laws' own uncertainty.

    python examples/damper_campaign.py [--out out/] [--all] [--jobs 2]
"""

import argparse
import re
import sys
from pathlib import Path

import numpy as np
from scipy.signal import butter, sosfiltfilt

from iwan_element import fit_campaign

ROOT = Path(__file__).resolve().parents[1]
ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--out", default="out", help="folder for the PNGs")
ap.add_argument("--all", action="store_true", help="every given record of both campaigns")
ap.add_argument("--jobs", type=int, default=1, help="local processes for the diagnoses")
args = ap.parse_args()

shared = next(
    (
        p / "shared" / "data"
        for p in (ROOT.parent, ROOT.parent.parent, Path.cwd().parent)
        if (p / "shared" / "data" / "arts-damper").is_dir()
    ),
    None,
)
if shared is None:
    print(
        "the damper records (../shared/data/arts-damper, CC BY-SA 4.0) are not here: nothing to do"
    )
    sys.exit(0)


def conditions(path):
    """Band tension [lb], frequency [Hz] and, with ``--all``, campaign (0: 2022, 1: 2023),
    nominal stroke [in] (dataset-1: about 1 in) and the products the per-campaign laws use,
    from the file name.
    """
    ds, f, T, a = re.match(
        r"ds(\d)_(\d+(?:p\d+)?)Hz_(\d+)lb(?:_(\d+(?:p\d+)?)in)?", path.stem
    ).groups()
    c = {"tension": float(T), "frequency": float(f.replace("p", "."))}
    if args.all:
        k = float(int(ds) - 1)
        c.update(
            campaign=k,
            stroke=float(a.replace("p", ".")) if a else 1.0,
            campaign_x_tension=k * c["tension"],
            tension_squared=c["tension"] ** 2,
            campaign_x_tension_squared=k * c["tension"] ** 2,
        )
    return c


#: ``--all``: per-campaign laws (docs/campaign.md section 8.2 says why): the slip force in
#: tension per campaign with a curvature, rate and stroke; the asymmetry in tension per
#: campaign, rate and stroke; the gap in campaign, tension and stroke; the drag in campaign
#: and tension; the shape only as far as the records determine it.
CAMPAIGN_LAWS = {
    "Fs": (
        "campaign",
        "tension",
        "campaign_x_tension",
        "tension_squared",
        "campaign_x_tension_squared",
        "frequency",
        "stroke",
    ),
    "asymmetric_slip.asymmetry": (
        "campaign",
        "tension",
        "campaign_x_tension",
        "frequency",
        "stroke",
    ),
    "ln(backlash.gap)": ("campaign", "tension", "stroke"),
    "ln(backlash.drag/Fs)": ("campaign", "tension"),
    "log_phi_max": ("campaign", "tension", "campaign_x_tension"),
    "log1p_beta": ("campaign",),
    "chi": (),
}


def load(path):
    return tuple(np.loadtxt(path, delimiter=",", skiprows=1).T)


held_out = shared / "arts-damper" / "ds1_1Hz_35lb.csv"
if args.all:
    files = sorted((shared / "arts-damper").glob("*.csv")) + sorted(
        (shared / "arts-damper-ds2").glob("*.csv")
    )
    files.remove(held_out)
    laws, opts = CAMPAIGN_LAWS, {"effects": ("backlash", "asymmetric_slip")}
else:
    files = [
        shared / "arts-damper" / f"ds1_{f}_{T}lb.csv" for f in ("0p5Hz", "1Hz") for T in (25, 70)
    ]
    laws = {"Fs": ("tension", "frequency"), "log_phi_max": (), "chi": (), "log1p_beta": ()}
    opts = {"candidates": ("backlash", "asymmetric_slip"), "max_effects": 2}  # quicker
fit = fit_campaign(
    [load(p) for p in files],
    [conditions(p) for p in files],
    names=[p.stem for p in files],
    laws=laws,
    lowpass=20.0,
    jobs=args.jobs,
    **opts,
)
print(fit.report())

# the held-out record, from its conditions alone: same low-pass, displacement from the rest
# position, force offset = the force read at rest (a sensor zero, not a device property)
t, u, F = load(held_out)
sos = butter(4, 20.0, fs=1.0 / float(np.median(np.diff(t))), output="sos")
u, F = sosfiltfilt(sos, u), sosfiltfilt(sos, F)
rest = slice(0, 50)  # the first 50 ms, before the motion starts
pred = fit.predict(
    conditions(held_out),
    t,
    u - u[rest].mean(),
    F0=float(F[rest].mean()),
    rng=np.random.default_rng(0),
)
band = np.abs(F) < 0.25 * np.abs(F).max()
rms = float(np.sqrt(np.mean((F - pred.force)[band] ** 2)))
print(
    f"predicted {held_out.stem} from {pred.conditions}: Fs = {pred.values['Fs']:.0f} N; "
    f"RMS misfit where |F| < 0.25 max|F|: {rms:.0f} N; whole record "
    f"{100 * np.sqrt(np.mean((F - pred.force) ** 2)) / np.ptp(F):.1f} % of the force range"
    + "".join(f"; {w}" for w in pred.warnings)
)

import matplotlib  # noqa: E402

matplotlib.use("Agg")
from matplotlib.figure import Figure  # noqa: E402

out = Path(args.out)
out.mkdir(parents=True, exist_ok=True)
shown = [q for q in ("Fs", "ln(backlash.gap)", "asymmetric_slip.asymmetry") if q in fit.laws]
fig = Figure(figsize=(9, 3 * len(shown)))
axes = fig.subplots(len(shown), 2, squeeze=False)
for row, q in zip(axes, shown):
    fit.plot(row[0], quantity=q, condition="tension")
    fit.plot(row[1], quantity=q, condition="frequency")
    row[0].set_xlabel("band tension [lb]")
    row[1].set_xlabel("drive frequency [Hz]")
fig.tight_layout()
fig.savefig(out / "campaign_parameters.png", dpi=110)

fig = Figure(figsize=(7, 5))
ax = fig.subplots()
pred.plot(ax, measured=F)
ax.set_title(f"{held_out.stem}: predicted from the campaign, not fitted", fontsize=9)
fig.tight_layout()
fig.savefig(out / "campaign_prediction.png", dpi=110)
print(f"wrote {out / 'campaign_parameters.png'} and {out / 'campaign_prediction.png'}")
