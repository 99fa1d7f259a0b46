"""The prediction of a vibration diagnosis (:class:`.result.VibrationDiagnosis`) at new
amplitudes: the named effects' modal forms on a base curve, with linearised 1-sigma bands
from the fitted values' covariance.
"""

from __future__ import annotations

import math

import numpy as np

from ...effects import EFFECTS


def _apply(names, parameters, X, f, z, zeta0):
    """The named effects' modal forms on a base curve, in order."""
    for n in names:
        f, z = EFFECTS[n].modal_form(X, f, z, zeta0, **parameters[n])
    return f, z


def predicted_curve(diag, amplitude, base):
    """The augmented model's frequency and damping at ``amplitude`` [m] with 1-sigma bands
    (:meth:`.result.VibrationDiagnosis.predict`), an ``AmplitudeCurve``.
    """
    from ...base.validation import finite_array
    from ...identify.modal.curves import AmplitudeCurve

    X = finite_array("amplitude", amplitude, ndim=1, min_size=1)
    if np.any(X <= 0):
        raise ValueError("amplitude must be > 0 [m]")
    warns = []
    lo, hi = float(diag.amplitude.min()), float(diag.amplitude.max())
    out = (X < lo * (1 - 1e-9)) | (X > hi * (1 + 1e-9))
    if base is None:
        o = np.argsort(diag.amplitude)
        lx = np.log(diag.amplitude[o])
        fb = np.exp(np.interp(np.log(X), lx, np.log(diag.predicted_frequency[o])))
        zb = np.exp(np.interp(np.log(X), lx, np.log(diag.predicted_damping_ratio[o])))
        if out.any():
            warns.append(
                f"{int(out.sum())} amplitudes outside the diagnosed range {lo:.3g} .. "
                f"{hi:.3g} m: the base prediction is held at its end values there; "
                "pass base= (the model's curve at these amplitudes)"
            )
    else:
        if not np.allclose(np.asarray(base.amplitude), X, rtol=1e-9, atol=0.0):
            raise ValueError("base must be the model's curve at exactly these amplitudes")
        fb, zb = np.asarray(base.frequency, float), np.asarray(base.damping_ratio, float)
    if out.any():
        warns.append(
            f"the fitted effects ({', '.join(diag.effects) or 'none'}) are "
            f"extrapolated beyond the diagnosed amplitudes {lo:.3g} .. {hi:.3g} m "
            f"(up to {max(X.max() / hi, lo / X.min()):.3g} x beyond)"
        )
    z0 = float(diag.details.get("predicted_zeta0", 0.0))
    f, z = _apply(diag.effects, diag.parameters, X, fb, zb, z0)
    sf, sz = _bands(diag, X, fb, zb, z0, f, z)
    return AmplitudeCurve(
        X,
        f,
        z,
        frequency_std=sf,
        damping_ratio_std=sz,
        method="diagnosis",
        notes="prediction + " + (" + ".join(diag.effects) or "nothing"),
        warnings=tuple(warns),
    )


def _bands(diag, X, fb, zb, z0, f, z):
    """Linearised 1-sigma bands [Hz], [-] from the covariance of the fitted values."""
    keys = [(n, k) for n in diag.effects for k in diag.parameters[n]]
    C = diag.covariance
    if not keys or C is None or C.shape != (len(keys), len(keys)):
        return np.zeros_like(f), np.zeros_like(z)
    G = np.empty((2 * X.size, len(keys)))
    for j, (n, k) in enumerate(keys):
        v = diag.parameters[n][k]
        h = max(1e-6 * abs(v), 1e-6 * math.sqrt(max(C[j, j], 0.0)), 1e-300)
        p = {a: dict(b) for a, b in diag.parameters.items()}
        p[n][k] = v + h
        f1, z1 = _apply(diag.effects, p, X, fb, zb, z0)
        G[:, j] = np.concatenate([np.log(f1 / f), np.log(z1 / z)]) / h
    var = np.einsum("ij,jk,ik->i", G, C, G)
    s = np.sqrt(np.maximum(var, 0.0))
    return f * s[: X.size], z * s[X.size :]
