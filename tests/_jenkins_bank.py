"""A bank of Jenkins sliders with static/kinetic thresholds, stepped here: the independent
route the break-away tests compare with (tests/test_breakaway.py, tests/test_fit_scan.py)."""
import numpy as np


def jenkins_bank(u, k, s, ratio):
    """Force history of parallel Jenkins sliders (stiffness ``k``, sliding stretch ``s``),
    vectorised over the sliders: a stuck slider breaks when its stretch exceeds ``ratio s``,
    slides at ``s`` while the motion keeps its direction, sticks again when it reverses."""
    k, s = np.asarray(k, float), np.asarray(s, float)
    x = np.zeros_like(k)                  # slider positions
    slide = np.zeros(k.size, bool)
    direc = np.zeros(k.size)
    out = np.empty(len(u))
    for i, ui in enumerate(u):
        e = ui - x
        keep = slide & (e * direc >= s)
        x[keep] = ui - direc[keep] * s[keep]
        slide &= keep
        brk = ~slide & (np.abs(e) > ratio * s)
        direc[brk] = np.sign(e[brk])
        x[brk] = ui - direc[brk] * s[brk]
        slide |= brk
        out[i] = float(np.sum(k * (ui - x)))
    return out
