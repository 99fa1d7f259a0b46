"""Where a loop misfit lies (part of the cycle, amplitudes, direction)."""

from __future__ import annotations

import math

import numpy as np

from ...effects import EFFECTS

__all__: list[str] = []


def _locate(t, u, F, Fm, r, cycles, sigma, tau) -> tuple[str, dict]:
    """A sentence saying where the residual exceeds the noise, and the numbers behind it."""
    s2 = sigma * sigma
    ratio = float(np.mean(r**2) / s2)
    region, cyc_ratio, amp_list = _cycle_regions(u, r, cycles, s2)
    names = ("just after the reversals", "mid-stroke", "at the ends of the stroke")
    reg: dict[str, float] = {}
    for k, nm in enumerate(names):
        m = region == k
        if m.sum() >= 5:
            reg[nm] = float(np.mean(r[m] ** 2) / s2)
    parts = [
        f"the residual is {math.sqrt(ratio):.2g} x the noise (RMS {math.sqrt(ratio) * sigma:.3g} N "
        f"vs {sigma:.3g} N)"
    ]
    if reg:
        worst = max(reg, key=reg.__getitem__)
        parts.append(
            f"largest {worst} ({math.sqrt(reg[worst]):.2g} x noise there"
            + ", ".join([""] + [f"{math.sqrt(v):.2g} x {k}" for k, v in reg.items() if k != worst])
            + ")"
        )
    amps = np.array(amp_list)
    cr = np.array(cyc_ratio)
    _amplitude_parts(amps, cr, cycles, tau, parts)
    shares = _pattern_parts(t, u, Fm, r, s2, parts)
    sentence = "; ".join(parts) + "."
    sentence = sentence[0].upper() + sentence[1:]
    return sentence, {
        "ratio": ratio,
        "regions": reg,
        "pattern_shares": {k.split(" (")[0].replace("{}", "..."): v[0] for k, v in shares.items()},
    }


def _cycle_regions(u, r, cycles, s2):
    """Each sample's part of the stroke (0 just after a reversal, 1 mid-stroke, 2 at the
    end; -1 outside the cycles), and each cycle's residual power over the noise's and
    amplitude.
    """
    region = np.full(u.size, -1)
    cyc_ratio, amp_list = [], []
    for c in cycles:
        sl = slice(c.start, c.stop)
        uu = u[sl]
        imin = int(np.argmin(uu))
        # displacement travelled since the last turning point, relative to the stroke
        d = np.where(np.arange(uu.size) <= imin, uu[0] - uu, uu - uu[imin]) / max(2 * c.u0, 1e-300)
        region[sl] = np.where(d < 0.15, 0, np.where(d > 0.85, 2, 1))
        rr = r[sl]
        cyc_ratio.append(float(np.mean(rr**2) / s2))
        amp_list.append(c.u0)
    return region, cyc_ratio, amp_list


def _amplitude_parts(amps, cr, cycles, tau, parts):
    """Append to ``parts`` at which amplitudes the residual exceeds the noise."""
    if amps.size:
        levels = np.unique(np.round(amps / amps.max(), 2))
        grp = {lv: cr[np.round(amps / amps.max(), 2) == lv].mean() for lv in levels}
        thresh = 1.0 + 3.0 * math.sqrt(
            2.0 * tau / max(np.mean([c.stop - c.start for c in cycles]), 1)
        )
        bad = [lv for lv, v in grp.items() if v > thresh]
        if bad and len(bad) == len(grp):
            top = max(grp, key=grp.__getitem__)
            parts.append(f"at every amplitude, most at u0 = {top * amps.max() * 1e3:.3g} mm")
        elif bad:
            parts.append(
                "at amplitudes u0 = "
                + ", ".join(f"{b * amps.max() * 1e3:.3g}" for b in bad)
                + " mm"
                + (
                    " (the largest)"
                    if min(bad) > np.median(levels)
                    else " (the smallest)"
                    if max(bad) < np.median(levels)
                    else ""
                )
            )
        else:
            parts.append("spread over all amplitudes")


def _pattern_parts(t, u, Fm, r, s2, parts):
    """Append to ``parts`` the patterns carrying at least a quarter of the excess residual
    power; return each pattern's ``(share, coefficient)``.
    """
    # patterns: the share of the excess residual power each one carries
    excess = max(float(r @ r) - u.size * s2, 1e-300)
    pats = {}
    af = np.abs(Fm)
    pats[
        "the measured force is {} than the model in one direction and {} in the other "
        "(a forward/back asymmetry)"
    ] = af
    if t is not None:
        pats["the loops are {} than the model (a force in phase with the velocity)"] = np.gradient(
            u
        )
    tc = np.arange(u.size) - 0.5 * u.size
    pats["the force changes from cycle to cycle ({} cycles carry more force than the model)"] = (
        Fm * tc
    )
    shares = {}
    for text, g in pats.items():
        gg = float(g @ g)
        if gg <= 0:
            continue
        coef = float(g @ r) / gg
        share = coef * coef * gg / excess
        shares[text] = (share, coef)
        if share >= 0.25:
            if "asymmetry" in text:
                hi = "higher" if coef > 0 else "lower"
                parts.append(text.format(hi + " (F > 0)", "higher" if coef < 0 else "lower"))
            elif "loops" in text:
                parts.append(text.format("wider" if coef > 0 else "narrower"))
            else:
                parts.append(text.format("late" if coef > 0 else "early"))
    return shares


def _check_candidates(candidates, default):
    if candidates is None:
        return default
    if isinstance(candidates, str):
        raise ValueError("candidates must be a sequence of effect names, not a string")
    cand = tuple(candidates)
    bad = [c for c in cand if c not in EFFECTS]
    if bad or not cand or len(set(cand)) != len(cand):
        raise ValueError(f"candidates must be distinct names of {sorted(EFFECTS)}, got {cand!r}")
    return cand
