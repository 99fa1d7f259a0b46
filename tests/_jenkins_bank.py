"""Banks of Jenkins sliders with static/kinetic thresholds, stepped here: the independent
routes the slider-law tests compare with (tests/test_breakaway.py, tests/test_fit_scan.py,
tests/test_effects.py, tests/test_slider_laws.py)."""

import numpy as np


def jenkins_bank(u, k, s, ratio):
    """Force history of parallel Jenkins sliders (stiffness ``k``, sliding stretch ``s``),
    vectorised over the sliders: a stuck slider breaks when its stretch exceeds ``ratio s``,
    slides at ``s`` while the motion keeps its direction, sticks again when it reverses."""
    k, s = np.asarray(k, float), np.asarray(s, float)
    x = np.zeros_like(k)  # slider positions
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


def directional_bank(u, k, up, dn, kin_up=None, kin_dn=None):
    """Parallel Jenkins sliders stepped one by one in plain Python, with static thresholds
    ``up``/``dn`` and kinetic ``kin_up``/``kin_dn`` (stretches [m]; default: the static
    ones) in the two directions (tests/test_effects.py, tests/test_slider_laws.py)."""
    kin_up = up if kin_up is None else kin_up
    kin_dn = dn if kin_dn is None else kin_dn
    out = []
    for i in range(len(k)):
        e, prev, slide, f_i = 0.0, 0.0, 0, []
        for x in u:
            du = x - prev
            prev = x
            d = 1 if du > 0 else -1 if du < 0 else 0
            if d == 0:
                f_i.append(k[i] * e)
                continue
            if slide != d:
                slide = 0
            e_new = e + du
            if slide == 0 and (e_new > up[i] or e_new < -dn[i]):
                slide = d
            if slide == 1:
                e_new = kin_up[i]
            elif slide == -1:
                e_new = -kin_dn[i]
            e = e_new
            f_i.append(k[i] * e)
        out.append(f_i)
    return np.sum(out, axis=0)
