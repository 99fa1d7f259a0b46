"""Real harmonic coefficients, their samples over one period, and the condensed residual.

A periodic signal with the harmonics ``h`` of :class:`Harmonics` is stored as real
coefficients ``(a_0 | a_h, b_h, ...)``: ``y(tau) = a_0 + sum_h a_h cos(h tau) + b_h sin(h tau)``,
``tau = W t``. Its complex amplitude is ``Y_h = a_h - i b_h`` (so ``y = Re sum Y_h e^{i h tau}``),
and its ``N`` samples over one period are ``E c`` (``P`` projects samples back: the AFT's DFT).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..core.masing import KT, PM, B
from ..core.periodic import periodic_harmonic_jacobian, periodic_rows

__all__ = ["Harmonics", "check_harmonics", "element_loop"]


def element_loop(element, y, v) -> tuple[NDArray[np.float64], float]:
    """Steady-loop force of a history-dependent element over one period of samples.

    The element is reset, loaded to the sample of the largest ``|y|`` (its first loading)
    and driven through one period from there: for the elements the modal effects use
    (elastic, viscous, Masing banks of Jenkins sliders) the loop then closes on itself, as
    the joints' do (:mod:`iwan_element.core.periodic`). Returns the force samples and the
    period's dissipation [J].
    """
    N = y.size
    k0 = int(np.argmax(np.abs(y)))
    element.reset()
    element.trial(float(y[k0]), float(v[k0]))
    element.commit()
    d0 = float(getattr(element, "dissipated_energy", 0.0))
    F = np.empty(N)
    for j in range(1, N + 1):
        m = (k0 + j) % N
        F[m] = element.trial(float(y[m]), float(v[m]))[0]
        element.commit()
    return F, float(getattr(element, "dissipated_energy", 0.0)) - d0


def check_harmonics(harmonics, samples) -> tuple[tuple, int]:
    """Validated ``(harmonics, samples)``: an int ``H`` means every harmonic ``0..H``, a
    sequence the harmonics it lists (it must hold the fundamental ``1``; ``(1, 3, 5)`` keeps
    the odd ones, enough for an odd joint law without static load). ``samples`` per period
    (default the power of two ``>= 8 H``, at least 64: the force has kinks at the
    reversals).
    """
    if isinstance(harmonics, bool):
        raise ValueError(
            f"harmonics must be an int >= 1 or a sequence of ints >= 0, got {harmonics!r}"
        )
    if isinstance(harmonics, (int, np.integer)):
        if harmonics < 1:
            raise ValueError(f"harmonics must be >= 1, got {harmonics!r}")
        hs = tuple(range(0, int(harmonics) + 1))
    else:
        try:
            hs = tuple(sorted({int(h) for h in harmonics}))
        except (TypeError, ValueError):
            raise ValueError(
                f"harmonics must be an int >= 1 or a sequence of ints >= 0, got {harmonics!r}"
            ) from None
        if not hs or hs[0] < 0 or 1 not in hs or any(h != int(h) for h in harmonics):
            raise ValueError(
                f"harmonics must contain the fundamental 1 and only ints >= 0, got {harmonics!r}"
            )
    if samples is None:
        samples = max(64, 1 << int(np.ceil(np.log2(8 * max(hs)))))
    if (
        isinstance(samples, bool)
        or not isinstance(samples, (int, np.integer))
        or samples < 2 * max(hs) + 1
    ):
        raise ValueError(f"samples must be an int >= 2 H + 1 = {2 * max(hs) + 1}, got {samples!r}")
    return hs, int(samples)


@dataclass(frozen=True, eq=False)
class Harmonics:
    """The harmonics kept, the samples per period, and the transforms between them."""

    harmonics: tuple
    samples: int
    E: np.ndarray = field(init=False, repr=False)
    dE: np.ndarray = field(init=False, repr=False)
    P: np.ndarray = field(init=False, repr=False)
    cols: tuple = field(init=False, repr=False)

    def __post_init__(self):
        tau = 2.0 * np.pi * np.arange(self.samples) / self.samples
        E, dE, P, cols = [], [], [], []
        for h in self.harmonics:
            if h == 0:
                cols.append((0, len(E), None))
                E.append(np.ones_like(tau))
                dE.append(np.zeros_like(tau))
                P.append(np.ones_like(tau) / self.samples)
            else:
                cols.append((h, len(E), len(E) + 1))
                E += [np.cos(h * tau), np.sin(h * tau)]
                dE += [-h * np.sin(h * tau), h * np.cos(h * tau)]
                P += [2.0 * np.cos(h * tau) / self.samples, 2.0 * np.sin(h * tau) / self.samples]
        object.__setattr__(self, "E", np.array(E).T)
        object.__setattr__(self, "dE", np.array(dE).T)
        object.__setattr__(self, "P", np.array(P))
        object.__setattr__(self, "cols", tuple(cols))

    @property
    def n_coefficients(self) -> int:
        """Number of real coefficients per signal (cosine and sine of each harmonic) [-]."""
        return self.E.shape[1]

    def complex(self, c: np.ndarray) -> np.ndarray:
        """Complex amplitudes ``(..., n_h)`` of real coefficients ``(..., nc)``."""
        out = np.empty(c.shape[:-1] + (len(self.cols),), complex)
        for k, (_h, ia, ib) in enumerate(self.cols):
            out[..., k] = c[..., ia] if ib is None else c[..., ia] - 1j * c[..., ib]
        return out

    def real(self, Z: np.ndarray) -> np.ndarray:
        """Real coefficients of complex amplitudes (the inverse of :meth:`complex`)."""
        out = np.empty(Z.shape[:-1] + (self.n_coefficients,))
        for k, (_h, ia, ib) in enumerate(self.cols):
            out[..., ia] = Z[..., k].real
            if ib is not None:
                out[..., ib] = -Z[..., k].imag
        return out

    def nonlinear_forces(
        self, system, cz, W, *, jacobian=True
    ) -> tuple[NDArray[np.float64], NDArray[np.float64] | None, NDArray[np.float64]]:
        """AFT of the nonlinear coordinates' forces from their coefficients ``cz`` (n_z, nc):
        the joints' deficits ``g = F(z) - KT z`` on their exact steady loops (exact
        Jacobian) with any force beside a joint (``system.joint_forms``, compiled, exact
        Jacobian), then the element ports' ``gain F(y, y')``: compiled with the exact
        Jacobian where the element states its periodic form (:meth:`_form`), otherwise on
        the steady loop of the element stepped sample by sample (:func:`element_loop`;
        Jacobian by forward differences: the elements' tangents alone leave out their
        reversal columns, and Newton then failed on the measured Brake-Reuss sweeps).
        Returns ``(cg, dcg/dcz or None, dissipation per period [J] per coordinate)``.
        """
        nj = len(system.joints)
        Z = cz[:nj] @ self.E.T
        F, K, A, D = periodic_rows(system.constants, Z)
        cg = np.empty_like(cz)
        cg[:nj] = (F - system.KT[:, None] * Z) @ self.P.T
        J = periodic_harmonic_jacobian(K, A, self.P, self.E, shift=system.KT) if jacobian else None
        if system.form_batch is not None:
            self._joint_forms(system.form_batch, cz, Z, W, cg, D, J)
        else:
            for i, form in enumerate(system.joint_forms):
                if form is not None:
                    f, d, Jf = self._form(form, cz[i], W, jacobian)
                    cg[i] += f
                    D[i] += d
                    if J is not None:
                        J[i] += Jf
        if not system.ports:
            return cg, J, D
        De = np.empty(len(system.ports))
        Je = np.zeros((len(system.ports),) + J.shape[1:]) if J is not None else None
        for k, port in enumerate(system.ports):
            c = cz[nj + k]
            if port.form is not None:
                f, d, Jk = self._form(port.form, c, W, jacobian)
                cg[nj + k], De[k] = port.gain * f, port.gain * d
                if Je is not None:
                    Je[k] = port.gain * Jk
                continue
            f, De[k] = self._port(port, c, W)
            cg[nj + k] = f
            if Je is not None:
                h = 1e-7 * max(float(np.abs(c).max()), 1e-300)
                for d in range(c.size):
                    cp = c.copy()
                    cp[d] += h
                    Je[k, :, d] = (self._port(port, cp, W)[0] - f) / h
        return cg, (np.concatenate([J, Je]) if jacobian else None), np.concatenate([D, De])

    def _joint_forms(self, batch, cz, Z, W, cg, D, J) -> None:
        """Add the joints' forms (``system.form_batch``) to their force coefficients
        ``cg``, dissipation ``D`` and Jacobian ``J`` (None: none), all joints at once: one
        walk of every Masing row on its joint's slip ``Z`` (rows that stay elastic over the
        period taken as their line, as :meth:`~iwan_element.core.periodic.PeriodicForm.loop`
        does), the rows' tangents summed per joint (the rows of one joint share its reversal
        chain) into one exact Jacobian call, then the laws (the same as :meth:`_form`, joint
        by joint).
        """
        joints, C, owner, shift, laws = batch
        Zf = Z[joints]
        n, N = Zf.shape
        sh = shift.copy()
        force = np.zeros((n, N))
        tangent = np.zeros((n, N))
        anchor = np.full((n, N), -1, np.int64)
        Dj = np.zeros(n)
        if owner.size:
            elastic = (C[:, B] == 0.0) & (C[:, PM] >= np.abs(Zf).max(axis=1)[owner])
            sh -= np.bincount(owner[elastic], C[elastic, KT], n)
            act = ~elastic
            if act.any():
                o = owner[act]
                F, K, A, Dr = periodic_rows(C[act], Zf[o])
                sel = (o[None, :] == np.arange(n)[:, None]).astype(float)
                force, tangent, Dj = sel @ F, sel @ K, sel @ Dr
                ks, first = np.unique(o, return_index=True)
                anchor[ks] = A[first]
        force -= sh[:, None] * Zf
        dZ = cz[joints] @ self.dE.T
        lf = np.zeros((n, N))
        lu, lv = np.zeros((n, N)), np.zeros((n, N))
        for k, law in laws:
            f, fu, fv = law(Zf[k], W * dZ[k])
            lf[k] += f
            lu[k] += fu
            lv[k] += fv
        cg[joints] += (force + lf) @ self.P.T
        D[joints] += Dj + 2.0 * np.pi / self.samples * np.sum(lf * dZ, axis=1)
        if J is not None:
            Jf = periodic_harmonic_jacobian(tangent, anchor, self.P, self.E, shift=sh)
            Jf += np.einsum("cn,kn,nd->kcd", self.P, lu, self.E)
            Jf += W * np.einsum("cn,kn,nd->kcd", self.P, lv, self.dE)
            J[joints] += Jf

    def _form(self, form, c, W, jacobian):
        """Force coefficients, dissipation [J] and (with ``jacobian``) the exact Jacobian of
        a force stated in the compiled kernel's terms (a
        :class:`~iwan_element.core.periodic.PeriodicForm`) on a coordinate with
        coefficients ``c``: its Masing rows on their steady loop
        (:func:`~iwan_element.core.periodic.periodic_rows`, the joints' kernel) with the
        reversal columns of their sample Jacobian, its history-free laws ``f(y, y')`` with
        ``P (f_y E + W f_v E')``; the laws' dissipation is the work of their force over the
        period, ``(2 pi / N) sum f dy/dtau``.
        """
        y, dy = self.E @ c, self.dE @ c
        lp = form.loop(y, W * dy)
        D = lp.dissipation + 2.0 * np.pi / self.samples * float(lp.law_force @ dy)
        if not jacobian:
            return self.P @ lp.force, D, None
        J = periodic_harmonic_jacobian(
            lp.tangent[None], lp.anchor[None], self.P, self.E, shift=np.array([lp.shift])
        )[0]
        J += self.P @ (lp.law_du[:, None] * self.E + W * lp.law_dv[:, None] * self.dE)
        return self.P @ lp.force, D, J

    def _port(self, port, c, W):
        """Force coefficients and dissipation of an element port with coefficients ``c``."""
        F, D = element_loop(port.element, self.E @ c, W * (self.dE @ c))
        return port.gain * (self.P @ F), port.gain * D

    def linear_operator(self, H_list, rows, cols_) -> NDArray[np.float64]:
        """The real 4-D operator ``L[p, c, q, c']`` of the complex port receptances
        ``H_list[k][rows][:, cols_]`` (one per kept harmonic ``k``).
        """
        nr, nq = len(rows), len(cols_)
        nc = self.n_coefficients
        L = np.zeros((nr, nc, nq, nc))
        for k, (_h, ia, ib) in enumerate(self.cols):
            H = H_list[k][np.ix_(rows, cols_)]
            if ib is None:
                L[:, ia, :, ia] = H.real
            else:
                L[:, ia, :, ia] = H.real
                L[:, ia, :, ib] = H.imag
                L[:, ib, :, ia] = -H.imag
                L[:, ib, :, ib] = H.real
        return L
