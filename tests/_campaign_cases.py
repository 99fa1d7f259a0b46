"""Seeded synthetic campaigns with known parameter laws, shared by tests/test_campaign.py and
benchmarks/bench_campaign.py. The records are made with the package's own elements
(:class:`IwanJoint` wrapped by the effect plug-ins, :func:`build_element`) driven by
:func:`simulate_element_test`, plus white force noise; the campaign fit is never told the laws'
values.

Device: a joint with backlash whose slip force grows linearly with a "tension" condition and
whose shape (chi) changes linearly with a "frequency" condition; phi_max, beta, the gap and
the drag per Fs are constants (the laws' forms: ln phi_max, ln(1 + beta), ln gap,
ln(drag / Fs)). Noise: 0.5 % of the record's Fs.
"""

from __future__ import annotations

import math

import numpy as np

from iwan_element import IwanParameters
from iwan_element.diagnose import simulate_element_test
from iwan_element.effects.engine.evaluate import build_element

#: True laws: quantity -> (intercept, per tension [N/lb or 1/lb], per frequency [1/Hz]).
LAWS = {
    "Fs": (400.0, 20.0, 0.0),
    "log_phi_max": (math.log(2.0e-3), 0.0, 0.0),
    "chi": (-0.6, 0.0, 0.2),
    "log1p_beta": (math.log1p(0.3), 0.0, 0.0),
    "ln(backlash.gap)": (math.log(0.4e-3), 0.0, 0.0),
    "ln(backlash.drag/Fs)": (math.log(0.05), 0.0, 0.0),
}
#: Test conditions of the campaign (tension [lb], frequency [Hz]).
CONDITIONS = tuple(
    {"tension": T, "frequency": f} for T in (10.0, 20.0, 30.0, 40.0) for f in (0.5, 1.0)
)
NAMES = ("backlash",)


def truth(cond):
    """The true quantities at one condition."""
    return {q: a + b * cond["tension"] + c * cond["frequency"] for q, (a, b, c) in LAWS.items()}


def element(cond, *, fs_factor=1.0):
    """The true device at one condition (``fs_factor``: a device off the Fs law)."""
    q = truth(cond)
    q["Fs"] *= fs_factor
    phi, chi, beta = math.exp(q["log_phi_max"]), q["chi"], math.expm1(q["log1p_beta"])
    KT = q["Fs"] * (1 + beta) / (phi * (beta + (chi + 1) / (chi + 2)))
    p = IwanParameters(q["Fs"], KT, chi, beta)
    return build_element(
        p,
        NAMES,
        [
            {
                "gap": math.exp(q["ln(backlash.gap)"]),
                "drag": math.exp(q["ln(backlash.drag/Fs)"]) * q["Fs"],
            }
        ],
    )


def fs_factors(seed, n, fs_scatter):
    """The per-record slip-force factors ``exp(fs_scatter z)``, ``z`` standard normal (a
    stream of its own, so the records' noise does not depend on ``fs_scatter``)."""
    return np.exp(fs_scatter * np.random.default_rng([seed, 7]).standard_normal(n))


def campaign(seed, conditions=CONDITIONS, noise=0.005, odd=None, fs_scatter=0.0):
    """``(records, conditions)`` of one seeded campaign: per condition a test of three
    amplitude blocks (0.6, 1.5, 3 phi_max) of two cycles, 96 samples per cycle; record
    ``odd`` (an index), if given, is a device with 1.3 times the law's Fs; every record's Fs
    is off the law by the factor :func:`fs_factors` (a device that scatters from test to
    test by ``fs_scatter`` in ln Fs, which no condition predicts)."""
    rng = np.random.default_rng(seed)
    recs = []
    factors = fs_factors(seed, len(conditions), fs_scatter)
    for i, c in enumerate(conditions):
        el = element(c, fs_factor=(1.3 if i == odd else 1.0) * factors[i])
        amps = np.array([0.6, 1.5, 3.0]) * math.exp(truth(c)["log_phi_max"])
        d = simulate_element_test(
            el,
            amps,
            cycles=2,
            frequency=c["frequency"],
            samples_per_cycle=96,
            rest_samples=10,
            force_noise=noise * truth(c)["Fs"],
            seed=rng,
        )
        recs.append((d.t, d.u, d.F))
    return recs, [dict(c) for c in conditions]
