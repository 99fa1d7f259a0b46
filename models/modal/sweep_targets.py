"""Linear targets of a stepped-sine level that is not linear: :func:`sweep_level_targets`.

A force-controlled level of a jointed structure spans a range of amplitudes (the Brake-Reuss
beam's lowest level: 11-94 um at the drive point, where the hammer-calibrated joint already
softens mode 1 by 0.1-0.4 % and raises its damping by up to 65 %). A linear single-mode fit
(:func:`~iwan_element.sweep_modes`) then reads the joint's amplitude dependence as a
distorted resonance and biases the modal constant (on that level: 0.461 against 0.500 1/kg,
``docs/linear_update.md`` section 7). Here every point is read at its own measured
amplitude through the specimen's own amplitude dependence (the single nonlinear mode of
``docs/sweeps.md`` section 1):

    H(W) = c / (w_s^2 rho(X)^2 e^(2 delta) - W^2 + 2 i zeta(X) e^eps w_s rho(X) e^delta W) + B(W)

* ``rho(X) = f(X) / f_stuck`` and ``zeta(X)``: the specimen's mode by QSMA
  (:func:`~.qsma.modal_amplitude_curve`, its joint as calibrated) at the point's modal
  amplitude ``X = |H - B| F`` at the sensor;
* ``w_s``: the specimen's stuck natural frequency; ``delta``: the level's frequency offset
  from it (the same at every amplitude), so that ``f_s e^delta`` is the linear (stuck)
  frequency the level implies: the frequency target of
  :func:`~iwan_element.models.updating.linear_update`;
* ``eps``: the level's damping relative to the specimen's at every amplitude;
* ``c``: the drive-point modal constant [1/kg]: the modal-constant target;
* ``B(W)``: the specimen's other modes at the drive point (rigid-body mass lines and the
  higher modes, from its reduced model): not fitted.

Least squares of the relative complex residual ``(H_model - H) / |H|``
(:func:`iwan_element.fitting.minimize`), standard errors ``s^2 (J^T J)^-1``
(:func:`iwan_element.fitting.covariance`; the points' errors taken as independent). The
frequency offset is fitted again on the points below and above the median amplitude with
``c`` and ``eps`` held: its drift says how far the specimen's softening differs from the
level's, and a drift beyond 3 stderr marks the target not linear (its stderr then holds the
drift, as :func:`~iwan_element.free_decay_modes` does for a ring-down window).
"""

from __future__ import annotations

import math

import numpy as np

from iwan_element import ModalTargets, ModeTarget
from iwan_element.fitting import covariance, minimize
from iwan_element.identify.sweeps.frf_modes import sweep_receptance

from ..reduced.dispatch import check_specimen
from ..reduced.model import reduced_model
from ..specimens.specimen import Specimen
from .qsma import modal_amplitude_curve

__all__ = ["sweep_level_targets", "drive_point_modes"]

_MISFIT = 0.05  # relative rms misfit above which the specimen's amplitude dependence fails


def drive_point_modes(specimen, W, *, mode: int = 1, n_modes: int = 8) -> tuple:
    """``(c, B)``: the drive-point modal constant [1/kg] of ``mode`` and the real
    receptance [m/N] of every other mode of the specimen's reduced model (rigid-body mass
    lines, the kept modes undamped and the residual flexibility) at circular frequencies
    ``W`` [rad/s], sensor over excitation.
    """
    red = reduced_model(specimen, n_modes=n_modes)
    r = red.mode_index(mode)
    sysm = red.system
    ys, ye = sysm.modes[-2], sysm.modes[-1]
    W = np.asarray(W, float)
    R = sysm.residual
    B = np.full(W.shape, 0.0 if R is None else float(R[-2, -1]))
    for k in range(sysm.omega.size):
        if k != r:
            B += ys[k] * ye[k] / (sysm.omega[k] ** 2 - W**2)
    return float(ys[r] * ye[r]), B


class _Level:
    """The points, the specimen's curve at their amplitudes and the model's receptance."""

    def __init__(self, specimen, pts, mode, n_modes):
        self.W = 2.0 * math.pi * pts["f"]
        self.H = pts["H"]
        self.c0, self.B = drive_point_modes(specimen, self.W, mode=mode, n_modes=n_modes)
        self.X = np.abs(self.H - self.B) * pts["F"]
        grid = np.geomspace(self.X.min() / 1.2, self.X.max() * 1.2, 48)
        cur = modal_amplitude_curve(specimen, mode=mode, amplitude=grid)
        self.f_s = reduced_model(specimen, n_modes=n_modes).frequency(mode)
        self.zeta_lin = float(specimen.floor(mode))
        lx = np.log(self.X)
        self.rho = np.interp(lx, np.log(cur.amplitude), cur.frequency) / self.f_s
        self.zeta = np.interp(lx, np.log(cur.amplitude), cur.damping_ratio)
        self.curve_warnings = tuple(cur.warnings)

    def receptance(self, c, delta, eps, keep=slice(None)):
        wr = 2 * math.pi * self.f_s * self.rho[keep] * math.exp(delta)
        W = self.W[keep]
        return c / (wr**2 - W**2 + 2j * self.zeta[keep] * math.exp(eps) * wr * W) + self.B[keep]

    def residual(self, x, keep=slice(None)):
        r = (self.receptance(x[0] * self.c0, x[1], x[2], keep) - self.H[keep]) / np.abs(
            self.H[keep]
        )
        return np.concatenate([r.real, r.imag])


def _fit(lv: _Level):
    sol = minimize(
        lv.residual,
        np.array([1.0, 0.0, 0.0]),
        np.array([0.2, -0.1, -3.0]),
        np.array([5.0, 0.1, 3.0]),
        method="trf",
        max_nfev=400,
        x_scale=np.array([0.05, 1e-3, 0.1]),
    )
    r = lv.residual(sol.x)
    cov = covariance(sol.jac, r)
    return sol, r, cov


def _drift(lv: _Level, x):
    """The frequency offset refitted on the points below and above the median amplitude
    (``c`` and ``eps`` held): ``(upper - lower, its stderr)``.
    """
    med = np.median(lv.X)
    out = []
    for keep in (lv.X <= med, lv.X > med):

        def res(d, keep=keep):
            return lv.residual(np.array([x[0], d[0], x[2]]), keep)

        sol = minimize(
            res, np.array([x[1]]), np.array([-0.1]), np.array([0.1]), method="trf", max_nfev=200
        )
        cov = covariance(sol.jac, res(sol.x))
        out.append((float(sol.x[0]), float(cov.stderr[0])))
    return out[1][0] - out[0][0], math.hypot(out[0][1], out[1][1])


def sweep_level_targets(
    specimen: Specimen,
    f,
    F,
    response,
    phase,
    *,
    quantity: str = "acceleration",
    level=None,
    mode: int = 1,
    n_modes: int = 8,
    label: str = "level",
) -> ModalTargets:
    """Linear targets of one stepped-sine level read through the specimen's amplitude
    dependence (module docstring): the linear (stuck) frequency the level implies and its
    drive-point modal constant, for :func:`~iwan_element.models.updating.linear_update`.

    Parameters
    ----------
    specimen : Specimen or SolidSpecimen
        Its joint as calibrated (e.g. on a hammer record) and the test's setup; its
        excitation and sensor are the sweep's drive and response points.
    f, F, response, phase : array_like, shape (n,)
        Drive frequency [Hz], fundamental force [N], fundamental response amplitude in SI
        units of ``quantity`` and its phase relative to the force [rad]
        (:func:`~iwan_element.sweep_modes`).
    quantity : {"acceleration", "velocity", "displacement"}, keyword-only
    level : array_like, optional, keyword-only
        Sweep label per point (:func:`~iwan_element.sweep_modes`).
    mode : int, keyword-only
        Elastic mode of the specimen the level excites (1: lowest).
    n_modes : int, keyword-only
        Elastic modes of the reduced model (the others as residual flexibility).
    label : str, keyword-only

    Returns
    -------
    ModalTargets
        One mode, ``source="sweep"``: ``frequency`` the stuck-equivalent linear frequency
        ``f_s e^delta`` [Hz], ``modal_constant`` ``c`` [1/kg], ``damping_ratio`` the
        specimen's linear floor times ``e^eps`` [-], each with its stderr; the frequency
        offset's drift between the lower and upper half of the amplitudes and the
        ``linear`` flag; ``amplitude_range`` of the points [m]. ``warnings``: a misfit above
        5 % rms (the specimen's amplitude dependence does not describe the level) and the
        curve's own (amplitudes beyond the joint's calibrated range).
    """
    check_specimen(specimen)
    pts = sweep_receptance(f, F, response, phase, level=level, quantity=quantity)
    lv = _Level(specimen, pts, mode, n_modes)
    sol, r, cov = _fit(lv)
    x, se = sol.x, cov.stderr
    rms = math.sqrt(float(r @ r) / max(r.size - 3, 1))
    drift, drift_se = _drift(lv, x)
    warns = list(lv.curve_warnings)
    if rms > _MISFIT:
        warns.append(
            f"the specimen's amplitude dependence fits the level to only {100 * rms:.2g} % "
            "rms: its joint does not describe these amplitudes, or the level is not one "
            "nonlinear mode"
        )
    f_lin = lv.f_s * math.exp(x[1])
    target = ModeTarget(
        index=1,
        label=str(label),
        frequency=f_lin,
        frequency_std=f_lin * se[1],
        damping_ratio=lv.zeta_lin * math.exp(x[2]),
        damping_ratio_std=lv.zeta_lin * math.exp(x[2]) * se[2],
        modal_constant=x[0] * lv.c0,
        modal_constant_std=se[0] * lv.c0,
        window=(float(pts["f"].min()), float(pts["f"].max())),
        amplitude_range=(float(lv.X.min()), float(lv.X.max())),
        frequency_drift=f_lin * drift,
        frequency_drift_std=f_lin * drift_se,
        linear=bool(abs(drift) <= 3 * drift_se),
        method="single nonlinear mode through the specimen's amplitude dependence",
    )
    notes = (
        f"{specimen.name}: {pts['f'].size} points, {pts['note']}; the specimen's mode {mode} "
        f"(stuck {lv.f_s:.6g} Hz, modal constant {lv.c0:.4g} 1/kg) at each point's "
        f"amplitude: frequency offset {100 * x[1]:+.3f} +- {100 * se[1]:.3f} % (drift "
        f"{100 * drift:+.3f} +- {100 * drift_se:.3f} % from the lower to the upper half of "
        f"the amplitudes), damping x {math.exp(x[2]):.3f} +- {se[2] * math.exp(x[2]):.3f}; "
        f"rms relative misfit {rms:.2g}"
    )
    return ModalTargets(modes=(target,), source="sweep", notes=notes, warnings=tuple(warns))
