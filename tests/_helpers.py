"""Test helpers used by several test modules (one copy each)."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st

from iwan_element import IwanParameters


def log_uniform(lo: float, hi: float):
    """Hypothesis strategy: floats log-uniform in ``[lo, hi]``."""
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: 10.0**e)


#: Random joints over the package's whole parameter range (Fs 1e-2-1e6 N, KT 1e2-1e10 N/m).
params_strategy = st.builds(
    IwanParameters,
    Fs=log_uniform(1e-2, 1e6),
    KT=log_uniform(1e2, 1e10),
    chi=st.floats(-0.95, 2.0),
    beta=st.one_of(st.just(0.0), st.floats(0.0, 5.0)),
)


def stepped_sine(scale: float, per: int, amps):
    """``(t, u)``: one sine cycle per amplitude ``amps`` (times ``scale``), ``per`` samples per
    cycle, time in cycles [s at 1 Hz]."""
    amps = np.asarray(amps, float)
    t = np.linspace(0.0, amps.size, amps.size * per + 1)
    env = np.append(np.repeat(amps * scale, per), amps[-1] * scale)
    return t, env * np.sin(2 * np.pi * t)


def step_element(el, u) -> np.ndarray:
    """Forces [N] of a history-dependent element driven through ``u`` sample by sample
    (``trial`` then ``commit`` at each sample)."""
    F = np.empty(len(u))
    for i, x in enumerate(np.asarray(u, float).tolist()):
        F[i] = el.trial(x)[0]
        el.commit()
    return F


def write_record_csv(
    path, t, u, F, *, header="time [s],displacement [mm],force [kN]", digits=(6, 8, 7), comment=None
):
    """Write a test record in the lab units of the header (mm, kN) and return ``path``."""
    a, b, c = digits
    rows = "\n".join(f"{x:.{a}f},{y:.{b}f},{z:.{c}f}" for x, y, z in zip(t, u * 1e3, F * 1e-3))
    head = (f"{comment}\n" if comment else "") + header + "\n"
    path.write_text(head + rows + "\n")
    return path
