"""Model and statistics of :func:`iwan_element.identify.decays.fit.fit_decay`.

The record's linear processing ``L`` (decimation, zero padding, zero-phase band-pass,
Hilbert transform), the averaged modal Iwan decay passed through it, the log-polar residuals
and their Jacobian, and the covariance for band-passed noise. Equations: the project's
``docs/decay_fit.md``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize, signal
from scipy.integrate import cumulative_simpson
from scipy.interpolate import CubicSpline

from ...fitting import normal_inverse
from ..modal.model import model_curve
from ._filter import _analytic_signal

_GRID = 2000  # log-amplitude grid of the quadrature
_PER_PERIOD = 8.0  # working rate: samples per period of the band's upper edge


class _Problem:
    """Record at the working rate, the linear operator ``L`` (decimation, zero padding,
    band-pass, Hilbert) and the model record that goes through it.
    """

    def __init__(self, yy, fs, band, order, k, conv):
        # working rate: at least 8 samples per period of the band's upper edge. The model is
        # made at the record's rate and decimated by the same resample_poly: its anti-alias
        # filter smears an abrupt release, which leaks into the band (1 % near the start)
        self.q = max(1, int(fs // (_PER_PERIOD * band[1])))
        # resample_poly's own anti-alias filter (Kaiser, beta 5), designed once: it designed
        # it anew at every call (7 % of a Jacobian's time in the decay fit, by cProfile)
        q = self.q
        self.fir = signal.firwin(20 * q + 1, 1.0 / q, window=("kaiser", 5.0)) if q > 1 else None
        self.n_full, self.fs_full = yy.size, fs
        yw = self.decimate(yy)
        self.fs, self.band, self.order, self.k, self.conv = fs / self.q, band, order, k, conv
        self.y, self.n = yw, yw.size
        self.sos, _, _, self.n_trim, self.i_pk = _analytic_signal(yw, self.fs, *band, order)
        self.nfft = int(2 ** math.ceil(math.log2(2 * (self.n + 2 * self.n_trim))))
        self.z = self.apply(yw)
        w, H = signal.sosfreqz(self.sos, worN=8192, fs=self.fs)
        self.bw = float(np.trapezoid(np.abs(H) ** 4, w))  # noise bandwidth [Hz]
        self.span = self.i_s = None
        self.nb = 0  # neighbouring out-of-band modes modelled (set by the fit)
        self.scale = float(np.max(np.abs(yw))) or 1.0

    @property
    def n_nuis(self):
        """Nuisance entries at the end of a parameter vector: four per neighbouring mode
        (frequency [Hz], decay rate [1/s], two amplitudes / ``scale``), then ``ln a0, phi_s``.
        """
        return 4 * self.nb + 2

    def theta(self, x):
        """The curve parameters of the vector ``x`` (without the nuisances)."""
        return x[: x.size - self.n_nuis]

    def decimate(self, Y):
        return signal.resample_poly(Y, 1, self.q, axis=0, window=self.fir) if self.q > 1 else Y

    def apply(self, Y):
        """``L``: the record (column by column) as zero outside its span, padded with zeros
        for the filter's extent at both ends, zero-phase band-pass and Hilbert transform.

        Data and model go through exactly this, so the end effects (an abrupt release or
        end of record) are the same in both; no taper is needed since the padded band-passed
        signal fades out smoothly inside the padding.
        """
        pad = [(self.n_trim, self.n_trim)] + [(0, 0)] * (np.ndim(Y) - 1)
        yf = signal.sosfiltfilt(self.sos, np.pad(Y, pad), axis=0)
        return signal.hilbert(yf, N=self.nfft, axis=0)[self.n_trim : self.n_trim + self.n]

    def _segment(self, thetas, regime, u, X):
        """Quadrature of one smooth piece of the curves for each parameter vector (the rows
        of ``thetas``): amplitudes ``X`` at ``u`` (a uniform grid, decreasing); returns the
        time, phase, ln w and asin(zeta) on it (columns: the rows of ``thetas``), and zeta
        and w of each.
        """
        cv = self.conv
        fz = [
            model_curve(t, X, regime, cv["x_ref"], cv["stiffness"], cv["floor"], "decay")
            for t in thetas
        ]
        f = np.column_stack([np.asarray(c[0], float) for c in fz])
        zeta = np.column_stack([np.asarray(c[1], float) for c in fz])
        if not (
            np.all(np.isfinite(f))
            and np.all(f > 0)
            and np.all(np.isfinite(zeta))
            and np.all(zeta > 0)
            and np.all(zeta < 0.5)
        ):
            raise ValueError("model outside its range")
        w = 2.0 * math.pi * f
        ig = np.hstack([1.0 / (zeta * w), np.sqrt(1.0 - zeta**2) / zeta])
        tq = cumulative_simpson(ig, dx=u[0] - u[1], initial=0.0, axis=0)
        tu, th = tq[:, : len(thetas)], tq[:, len(thetas) :]
        if not np.all(np.diff(tu, axis=0) > 0):
            raise ValueError("time grid not increasing")
        return tu, th, np.log(w), np.arcsin(zeta), zeta, w

    def _cuts(self, lp, ln_a0):
        """The grid's pieces ``(ln a from, to, nodes, first, last)``: one, or two with a node
        at ``ln phi_max = lp`` (:meth:`trajectory`).
        """
        u_end = ln_a0 - self.span
        if u_end < lp < ln_a0 - 1e-9:
            n_a = min(max(int(round(_GRID * (ln_a0 - lp) / self.span)), 5), _GRID - 5)
            return [
                (ln_a0, lp, n_a, 1.0, 1.0 + 1e-12),  # phi_max from above
                (lp, u_end, _GRID - n_a + 1, 1.0 - 1e-12, 1.0),
            ]  # and from below
        return [(ln_a0, u_end, _GRID, 1.0, 1.0)]

    def trajectory(self, theta, regime, ln_a0, t_rel, steps=()):
        """Ln a, theta, ln w and asin(zeta) at ``t_rel`` [s] after the start of the decay,
        shape ``(n, 4)``, and their derivatives by the curve parameters ``steps`` (pairs
        ``(index in theta, step)``) and by ``ln_a0``, shape ``(n, 4, len(steps) + 1)``,
        when any are asked.

        Quadrature in ``u = ln a`` on a fixed grid (cumulative Simpson), cubic spline in time.
        The decay-form damping of the full model jumps at ``X = phi_max`` (the joint's tangent
        loses the sliders at ``phi_max`` at once): a grid node sits there and each side is
        integrated with its own one-sided values, so the trajectory is smooth in ``phi_max``
        (a fixed grid made the residual step whenever ``phi_max`` crossed a node, and finite
        differences then overstated its sensitivity some 50-fold). A curve parameter other
        than ``phi_max`` leaves the grid in ``u`` as it is and moves its nodes in time: the
        quadratures of all the stepped parameter vectors are one call, and at a fixed time
        ``dY = dY_node - (dY/dt) dt_node``, the nodes' sensitivities interpolated in ``u`` at
        ``u(t)`` (linear on the grid: they vary over the decay, error ~1e-6), which saves a
        spline per parameter. Raised by ``d``, ``ln a0`` is passed ``d / (zeta w)`` (at the
        release) later, and the decay follows the base delayed by that time (the grid moves
        with it): ``dY/d ln a0 = -(dY/dt) / (zeta w)``, plus the phase ``w sqrt(1 - zeta**2)
        / (zeta w)`` gained meanwhile.
        """
        thetas = np.tile(np.asarray(theta, float), (len(steps) + 1, 1))
        for c, (j, h) in enumerate(steps):
            thetas[c + 1, j] += h
        hs = np.array([h for _, h in steps])
        lp = theta[4] if regime != "microslip" else np.inf
        pieces, t0, th0, start = [], np.zeros(len(thetas)), np.zeros(len(thetas)), None
        for ua, ub, m, first, last in self._cuts(lp, ln_a0):
            u = np.linspace(ua, ub, m)
            X = np.exp(u)
            X[0] *= first
            X[-1] *= last
            tu, th, lw, asz, zeta, w = self._segment(thetas, regime, u, X)
            tu, th = tu + t0, th + th0
            if start is None:  # ln a0 moves the release along the curve: dt = d ln a0 / zeta w
                start = (zeta[0, 0] * w[0, 0], w[0, 0] * math.sqrt(1.0 - zeta[0, 0] ** 2))
            node = np.hstack([(v[:, 1:] - v[:, :1]) / hs for v in (th, lw, asz, tu)])
            spl = CubicSpline(tu[:, 0], np.column_stack([u, th[:, 0], lw[:, 0], asz[:, 0]]))
            pieces.append((tu[:, 0], spl, ua, (ua - ub) / (m - 1), node))
            t0, th0 = tu[-1], th[-1]
        out, sens = np.empty((t_rel.size, 4)), np.zeros((t_rel.size, 4, hs.size + 1))
        rate = np.zeros((t_rel.size, 4))  # dY/dt
        lo = -np.inf
        for tu, spl, ua, du, node in pieces:
            sel = (t_rel > lo) & (t_rel <= tu[-1]) if lo > -np.inf else t_rel <= tu[-1]
            out[sel] = spl(t_rel[sel])
            if steps:  # the nodes' sensitivities at u(t), linear in u (error ~ du**2 / 8)
                rate[sel] = spl(t_rel[sel], 1)
                s = np.clip((ua - out[sel, 0]) / du, 0.0, tu.size - 1.0)
                i = np.minimum(s.astype(int), tu.size - 2)
                f = (s - i)[:, None]
                nd = (node[i] * (1.0 - f) + node[i + 1] * f).reshape(-1, 4, hs.size)
                sens[sel, 1:, :-1] = nd[:, :3]  # th, ln w, asin(zeta); minus dY/dt dt_node
                sens[sel, :, :-1] -= rate[sel, :, None] * nd[:, 3][:, None, :]
            lo = tu[-1]
        beyond = t_rel > t0[0]
        if np.any(beyond):  # past the grid: continue at the last decay rate and frequency
            dt = t_rel[beyond] - t0[0]
            r, o = zeta[-1] * w[-1], w[-1] * np.sqrt(1 - zeta[-1] ** 2)
            out[beyond, 2:] = [lw[-1, 0], asz[-1, 0]]
            out[beyond, 0] = u[-1] - r[0] * dt
            out[beyond, 1] = th0[0] + o[0] * dt
            rate[beyond, :2] = [-r[0], o[0]]
            dr, do, dt0, dth0, dlw, dasz = (
                (v[1:] - v[0]) / hs for v in (r, o, t0, th0, lw[-1], asz[-1])
            )
            sens[beyond, 0, :-1] = -dt[:, None] * dr + r[0] * dt0
            sens[beyond, 1, :-1] = dt[:, None] * do + dth0 - o[0] * dt0
            sens[beyond, 2:, :-1] = np.stack([dlw, dasz])
        if not steps:
            return out
        sens[:, :, -1] = -rate / start[0]  # from a0 + d: the base, d / (zeta w) later,
        sens[:, 1, -1] += start[1] / start[0]  # after the phase of that time
        return out, sens

    def record(self, x, regime, steps=()):
        """Model record ``a w**k cos(theta + k asin(zeta) + phi_s)`` at the record's rate,
        zero before the start; with ``steps`` (:meth:`trajectory`) also its derivatives by
        those curve parameters, ``ln a0`` and ``phi_s``, shape ``(n_full, len(steps) + 2)``.
        """
        i0 = self.i_s * self.q
        t_rel = np.arange(self.n_full - i0) / self.fs_full
        tr = self.trajectory(self.theta(x), regime, x[-2], t_rel, steps)
        tr, sens = tr if steps else (tr, None)
        u, th, lw, asz = tr.T
        y = np.zeros(self.n_full)
        amp, arg = np.exp(u + self.k * lw), th + self.k * asz + x[-1]
        y[i0:] = amp * np.cos(arg)
        for j in range(self.nb):  # linear out-of-band modes that leak into the band
            f2, s2, c, s = x[x.size - self.n_nuis + 4 * j :][:4]
            wt = 2.0 * math.pi * f2 * t_rel
            y[i0:] += self.scale * np.exp(-s2 * t_rel) * (c * np.cos(wt) + s * np.sin(wt))
        if not steps:
            return y
        c, s = amp * np.cos(arg), amp * np.sin(arg)
        dy = np.zeros((self.n_full, len(steps) + 2))
        dy[i0:, :-1] = c[:, None] * (sens[:, 0] + self.k * sens[:, 2])
        dy[i0:, :-1] -= s[:, None] * (sens[:, 1] + self.k * sens[:, 3])
        dy[i0:, -1] = -s
        return y, dy

    def neighbour_columns(self, x):
        """Exact derivatives of :meth:`record` by the neighbours' four entries each
        (frequency, decay rate, amplitudes), in the order of ``x``.
        """
        i0 = self.i_s * self.q
        t_rel = np.arange(self.n_full - i0) / self.fs_full
        cols = np.zeros((self.n_full, 4 * self.nb))
        for j in range(self.nb):
            f2, s2, c, s = x[x.size - self.n_nuis + 4 * j :][:4]
            wt = 2.0 * math.pi * f2 * t_rel
            ec, es = (
                self.scale * np.exp(-s2 * t_rel) * np.cos(wt),
                self.scale * np.exp(-s2 * t_rel) * np.sin(wt),
            )
            cols[i0:, 4 * j] = 2.0 * math.pi * t_rel * (s * ec - c * es)
            cols[i0:, 4 * j + 1] = -t_rel * (c * ec + s * es)
            cols[i0:, 4 * j + 2], cols[i0:, 4 * j + 3] = ec, es
        return cols


def _polar(z):
    return np.log(np.maximum(np.abs(z), 1e-300)), np.unwrap(np.angle(z))


class _Objective:
    """Log-polar residuals on the samples ``idx`` and their Jacobian (``L`` is linear, so
    ``dz/dx = L(dy/dx)``; ``dy/dx`` from :meth:`_Problem.record`'s sensitivities).
    """

    def __init__(self, prob, regime, idx, ref, bounds, weights=None, envelope=None):
        self.prob, self.regime, self.idx, self.ub = prob, regime, idx, bounds[1]
        self.lb = bounds[0]
        self.sl = slice(idx[0], idx[-1] + 1)
        self.sel = idx - idx[0]
        zd = prob.z[self.sl]
        lnd, phd = _polar(zd)
        # |z| (ln|z| - ln|z_m|) with the data's own |z| as the weight has the mean
        # E|n|**2 / (2 |z|) per sample (the weight and the log error share the noise's
        # in-phase part): a bias that grows as the decay meets the noise and reads as a
        # lower damping there. A given envelope (a previous fit's model, free of this
        # sample's noise) has none: to second order the mean is then (s_i**2 - s_r**2) / 2|z|
        # = 0 for in-band noise, which is circular.
        env = np.abs(zd[self.sel]) if envelope is None else envelope
        self.wgt = env / ref * (1.0 if weights is None else weights)
        self.lnd, self.phd = lnd[self.sel], phd[self.sel]
        self._cache = (None, None, None)

    def _model(self, x):
        if self._cache[0] is not None and np.array_equal(self._cache[0], x):
            return self._cache[1], self._cache[2]
        y = self.prob.record(x, self.regime)
        zm = self.prob.apply(self.prob.decimate(y))[self.sl]
        self._cache = (np.array(x), y, zm)
        return y, zm

    def envelope(self, x):
        """``|z_m|`` of the model ``x`` at the samples."""
        return np.abs(self._model(x)[1][self.sel])

    def resid(self, x):
        try:
            _, zm = self._model(x)
        except ValueError:
            return np.full(2 * self.idx.size, 1e3)
        lnm, phm = _polar(zm)
        dph = self.phd - phm[self.sel]
        dph -= 2.0 * math.pi * np.round(dph[0] / (2.0 * math.pi))
        return np.concatenate([self.wgt * (self.lnd - lnm[self.sel]), self.wgt * dph])

    def _phi_column(self, x, h=1e-3):
        """Derivative of the record by ``ln phi_max``: a central difference over +-1e-3.

        The decay-form damping jumps at ``phi_max``, so the amplitude has a kink at the time
        it passes ``phi_max``; the sampled record depends on ``ln phi_max`` smoothly only
        at scales above that of the kink crossing a sample. A forward difference of 1e-7
        read that fine structure: on benchmark seed 16 the stderr of ``ln phi_max`` came
        out anywhere from 0.004 to 0.03 with the step, while central differences from 1e-5
        to 1e-2 agree on 0.033 (the estimate's error was 0.021).
        """
        xp, xm = np.array(x, dtype=float), np.array(x, dtype=float)
        hp = min(h, max(self.ub[4] - x[4], 0.0))
        hm = min(h, max(x[4] - self.lb[4], 0.0))
        xp[4] += hp
        xm[4] -= hm
        if hp + hm <= 0.0:
            return np.zeros(self.prob.n_full)
        return (self.prob.record(xp, self.regime) - self.prob.record(xm, self.regime)) / (hp + hm)

    def jac(self, x):
        """Jacobian of :meth:`resid`: the record's derivatives by the curve parameters and
        ``ln a0`` from one quadrature of all their steps (:meth:`_Problem.trajectory`), by
        ``ln phi_max`` by differences (:meth:`_phi_column`), by ``phi_s`` and the neighbours
        exactly; ``L`` is linear, so ``dz/dx = L(dy/dx)``.
        """
        nb0 = x.size - self.prob.n_nuis  # neighbours: exact columns
        full = self.regime != "microslip"
        steps = []
        for j in range(nb0):
            h = 1e-7 * max(abs(x[j]), 1e-2)
            if not (full and j == 4):
                steps.append((j, -h if x[j] + h > self.ub[j] else h))
        try:
            _, zm = self._model(x)
            cols = list(self.prob.record(x, self.regime, steps)[1].T)
            if full:
                cols.insert(4, self._phi_column(x))
        except ValueError:
            return np.zeros((2 * self.idx.size, x.size))
        cols = np.column_stack(cols[:nb0] + [self.prob.neighbour_columns(x)] + cols[nb0:])
        dz = self.prob.apply(self.prob.decimate(cols))[self.sl][self.sel] / zm[self.sel, None]
        return -np.vstack([self.wgt[:, None] * dz.real, self.wgt[:, None] * dz.imag])


def _solve(obj, x0, lb, ub):
    width = np.where(np.isfinite(ub - lb), ub - lb, 0.0)
    x0 = np.clip(x0, lb + 1e-9 * width, ub - 1e-9 * width)
    return optimize.least_squares(
        obj.resid,
        x0,
        jac=obj.jac,
        bounds=(lb, ub),
        x_scale="jac",
        method="trf",
        xtol=1e-10,
        ftol=1e-10,
        gtol=1e-10,
        max_nfev=100,
    )


def _noise_correlation(prob, lags):
    """Correlation ``rho(k dt)`` of the analytic signal of white noise after the band-pass
    (``sum_f |H(f)|**4 exp(2 pi i f tau)`` over ``f >= 0``, normalised to 1 at 0).
    """
    nf = max(16384, int(2 ** math.ceil(math.log2(lags + 1))))
    _, H = signal.sosfreqz(prob.sos, worN=nf, fs=prob.fs)  # f_j = j fs / (2 nf)
    P = np.zeros(2 * nf)
    P[:nf] = np.abs(H) ** 4
    return np.fft.ifft(P)[: lags + 1] * (2 * nf) / P.sum()


def _covariance(obj, r, J):
    """Covariance of the least-squares estimate for band-passed white noise.

    The rotated residual ``rr = r_ln + i r_phase`` is the in-band noise ``n`` turned by the
    signal's phase; ``E[rr_i conj(rr_j)] = s2 conj(rho(t_j - t_i)) exp(i (phi_j - phi_i))``.
    Sandwich ``B Omega B``, ``B = (J^T J)^-1``, ``Omega = s2 Re(Jc^H R Jc) / 2`` with
    ``Jc = J_ln + i J_phase`` and ``R`` the correlation above (the estimator's exact
    covariance under that noise model). ``s2`` is the residual's sum of squares over its
    degrees of freedom under the same model, ``m - tr(B Omega / s2)`` (the fit absorbs that
    much of correlated noise; a short record has few independent noise samples, and the
    plain mean square understated the noise by up to half). Also returns the variance
    inflation of a sum of residuals relative to independent samples (the correlation factor)
    and the residual degrees of freedom: ``m - tr(B Omega / s2)`` in samples, and the
    chi-square degrees of freedom of ``s2`` (Satterthwaite: ``2 dof / tau2``, ``tau2 =
    sum_k |rho_k|**2`` the correlation time of the squared noise), on which the standard
    errors' own precision rests.
    """
    m = r.size // 2
    rr = r[:m] + 1j * r[m:]
    Jc = J[:m] + 1j * J[m:]
    step = int(obj.idx[1] - obj.idx[0]) if obj.idx.size > 1 else 1
    lags = min(m - 1, int(math.ceil(20.0 * obj.prob.fs / (obj.prob.bw * step))))
    rho = _noise_correlation(obj.prob, lags * step)[::step]
    omega = (Jc.conj().T @ Jc).real
    kappa, tau2 = 1.0, 1.0
    for k in range(1, lags + 1):
        c = np.conj(rho[k]) * np.exp(1j * (obj.phd[k:] - obj.phd[:-k]))  # C_{i,i+k} / s2
        g = (Jc[:-k].conj() * c[:, None]).T @ Jc[k:]
        omega += g.real + g.real.T  # the lag and its Hermitian transpose
        kappa += 2.0 * (1.0 - k / m) * float(np.mean(c.real))
        tau2 += 2.0 * (1.0 - k / m) * abs(rho[k]) ** 2
    omega *= 0.5
    bread = (
        normal_inverse(J)[0]
        if np.all(np.isfinite(J))  # docs/fitting.md section 1
        else np.full((J.shape[1], J.shape[1]), np.nan)
    )
    dof = m - float(np.trace(bread @ omega))
    s2 = float(np.sum(np.abs(rr) ** 2)) / max(dof, 1.0)
    return bread @ (s2 * omega) @ bread, max(kappa, 1.0), (dof, 2.0 * max(dof, 0.0) / tau2)


def _misfit_ratio(r, lag):
    """Mean square residual over its noise part: half the mean square of differences ``lag``
    samples apart (beyond the noise correlation time, so a slowly varying misfit cancels in
    them); about 1 when the residual is noise only.
    """
    m = r.size // 2
    rr = r[:m] + 1j * r[m:]
    if m <= lag + 2:
        return float("nan")
    d = rr[lag:] - rr[:-lag]
    return float(np.mean(np.abs(rr) ** 2) / max(0.5 * np.mean(np.abs(d) ** 2), 1e-300))


def _local_weights(r, lag):
    """Weights ``<= 1`` that level the local noise of the residual ``r``, and the noise RMS.

    The noise RMS is that of the turned residual ``rr``'s differences ``lag`` samples (two
    correlation times) apart, where a slowly varying misfit cancels (lower quartile of local
    mean squares over eight lags, halved: the transients of other modes at the ends of the
    record are left out). The local noise level is the mean square over two correlation times
    of second differences at half a correlation time: they cancel a misfit that varies over
    the decay time, but keep noise and the leakage of other modes (an out-of-band mode's
    transient after an abrupt start oscillates at the difference frequency). Samples whose
    level is above the median are weighted down by the ratio of RMS values (feasible weighted
    least squares); none is weighted up.
    """
    m = r.size // 2
    rr = r[:m] + 1j * r[m:]
    lag = max(1, min(lag, m // 8))

    def local(d2, win):
        d2 = np.concatenate([d2, np.full(m - d2.size, d2[-1])])
        return np.convolve(d2, np.ones(win), mode="same") / np.convolve(
            np.ones(m), np.ones(win), mode="same"
        )

    first = local(np.abs(rr[lag:] - rr[:-lag]) ** 2, 8 * lag)
    h = max(1, lag // 4)
    second = local(np.abs(rr[2 * h :] - 2.0 * rr[h:-h] + rr[: -2 * h]) ** 2, max(lag, 4))
    med = float(np.median(second))
    return np.sqrt(med / np.maximum(second, med)), math.sqrt(0.5 * float(np.percentile(first, 25)))


def _fit_regime(obj, starts, bounds):
    best = None
    for x0 in starts:
        r = _solve(obj, x0, *bounds)
        if best is None or r.cost < best.cost:
            best = r
    return best
