"""Transient ring-down of a lap-jointed specimen in Exudyn: the independent route to f(X), zeta(X).

The specimen is held in the static deflection that the modal load ``alpha M phi`` produces
(the joints loaded along their virgin curves, so the Iwan elements start virgin at those
slips) and released from rest at ``t = 0``. Exudyn integrates the geometrically nonlinear
Cable2D beams with the history-dependent Iwan element of every contact point
(generalized-alpha with spectral radius 1, i.e. the trapezoidal rule: no numerical
damping). The mode's response is separated by modal filtering, ``q(t) = phi^T M x(t)``,
and expressed at the sensor (``X = (S phi) q``); frequency and damping against amplitude
follow from the package's free-decay route, :func:`iwan_element.amplitude_curve` (band-pass
``(0.5, 1.5)`` times the stuck frequency, Hilbert envelope and phase, straight-line fits in
windows of ``n_periods``; ``docs/free_decay.md``), the same route a measured ring-down takes.
The trapezoidal rule lengthens the period by a known amount (``w_num h / 2 =
arctan(w h / 2)``); the frequencies are corrected for it (``docs/beam_tests.md``).

The damping floor of the specimen is applied as stiffness-proportional beam damping
``beta`` chosen so that the stuck linear mode has ``zeta = damping_floor``
(``zeta = beta phi^T K_beams phi / (2 w)``).

The specimen's vibration effects on this mode (``specimen.effects``, modal form, amplitudes
at the sensor; ``docs/vibration_effects.md``) act as a modal force: their elements
(``EFFECTS[name]`` around a zero-force element, joint values from ``modal_to_joint`` with
unit modal mass in sensor units) are driven by the sensor-scaled modal coordinate
``Y = s q``, ``q = phi^T M x``, ``s = S phi``, and apply ``-M phi F(Y) / s`` to the beams
(an Exudyn ``ObjectGenericODE2`` with its exact Jacobian ``M phi phi^T M F'(Y)``), which the
mass-orthogonality of the modes keeps on this mode. Their work is ``(1/s^2) int F dY``.
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field, replace

import exudyn as exu
import numpy as np

from exudyn.itemInterface import ObjectGenericODE2

from iwan_element import AmplitudeCurve, amplitude_curve
from iwan_element.core.progress import finish, progress_bar, tick
from iwan_element.core.result_shape import ResultShape, panels
from iwan_element.core.serialize import json_safe
from iwan_element.core.validation import check_scalar
from iwan_element.effects import EFFECTS

from .assembly import build_specimen_model
from .qsma import static_modal_load
from .solver import floor_damping, solver_settings
from .specimens import Specimen

__all__ = ["RingdownResult", "ringdown"]


#: Largest relative energy-balance error a ring-down may show and still be a success.
ENERGY_TOL = 1e-3


@dataclass(frozen=True)
class RingdownResult(ResultShape):
    """Result of :func:`ringdown`, with the package's result shape (``report``, ``to_dict``,
    ``warnings``, ``success``, ``plot(ax=None)`` on three panels: the mode's response against
    time, then the decay's frequency and damping against amplitude).

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s] from the release.
    sensor : ndarray, shape (n,)
        Transverse displacement at the sensor point [m] (all modes).
    modal : ndarray, shape (n,)
        The mode's contribution at the sensor, ``(S phi) q(t)`` [m].
    curve : AmplitudeCurve
        Frequency and damping against amplitude from the decay (``method="ringdown"``).
    energy : dict of ndarray
        ``t``, ``kinetic``, ``strain``, ``springs``, ``joint_stored``, ``joint_dissipated``,
        ``floor_dissipated``, ``effect_stored``, ``effect_dissipated`` [J] (filled when
        ``record_energy``; the effect terms stay empty without effects).
        ``floor_dissipated`` is the work of the damping floor's stiffness-proportional beam
        damping, ``beta v^T K_b v`` integrated with the step's mean velocity (the
        trapezoidal rule's own damping work); zero without a floor.
    initial_energy : float
        Elastic energy at the release [J] (beams, springs, joints).
    wall_time : float
        Seconds spent in ``SolveDynamic``.
    metadata : dict
        ``h`` [s], ``steps``, ``extra_steps`` (how many more steps the solver took, cutting
        them where the interface slips hard; the records are then interpolated onto the
        nominal step), ``beam_damping`` [s], ``n_points``, ``effects``,
        ``kinetic_at_release`` [J] and ``joint_quadrature_error`` [-]: with
        ``record_energy``, the joints' exact work minus the trapezoidal work of their
        recorded forces, over the release energy; the time integrator's share of the energy
        balance (it converges with ``steps_per_period``), else None.
    warnings : tuple of str
        The decay curve's warnings, and an energy balance off by more than
        :data:`ENERGY_TOL` (when recorded).
    """

    plot_panels = 3

    t: np.ndarray
    sensor: np.ndarray
    modal: np.ndarray
    curve: AmplitudeCurve
    energy: dict
    initial_energy: float
    wall_time: float
    metadata: dict = field(default_factory=dict)

    @property
    def max_energy_error(self) -> float | None:
        """Largest relative energy-balance error [-], or None when energy was not recorded."""
        return float(np.max(np.abs(self.energy_error()))) if len(self.energy["t"]) else None

    @property
    def success(self) -> bool:
        """True when the decay gave at least three curve points and the energy balance (when
        recorded) closes to :data:`ENERGY_TOL`."""
        err = self.max_energy_error
        return bool(len(self.curve) >= 3 and (err is None or err <= ENERGY_TOL))

    def report(self) -> str:
        """Human-readable account."""
        m, c = self.metadata, self.curve
        lines = [f"Exudyn ring-down: {m['steps']} steps of {m['h']:.4g} s "
                 f"({self.t[-1]:.4g} s, {self.wall_time:.3g} s wall), {m['n_points']} contact "
                 f"points" + (f", effects {' + '.join(m['effects'])}" if m["effects"] else "")]
        if len(c):
            lines.append(f"  curve: {len(c)} points, {c.amplitude.min():.3g}-"
                         f"{c.amplitude.max():.3g} m, f {c.frequency.min():.6g}-"
                         f"{c.frequency.max():.6g} Hz, zeta {100 * c.damping_ratio.min():.3g}-"
                         f"{100 * c.damping_ratio.max():.3g} %")
        err = self.max_energy_error
        lines.append("  energy balance: " + ("not recorded" if err is None else
                                             f"max relative error {err:.2e}; the joints' "
                                             "trapezoidal work is off their exact work by "
                                             f"{m['joint_quadrature_error']:.2e}"))
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-safe summary: the curve, the energy balance and the run's metadata."""
        return json_safe({"curve": self.curve.to_dict(), "duration": float(self.t[-1]),
                          "initial_energy": self.initial_energy,
                          "max_energy_error": self.max_energy_error,
                          "wall_time": self.wall_time, "metadata": self.metadata,
                          "success": self.success, "warnings": list(self.warnings)})

    def plot(self, ax=None):
        """The mode's response at the sensor against time, then the decay's frequency and
        damping against amplitude, on ``ax = (ax_t, ax_f, ax_z)`` (a new figure if
        ``None``; :mod:`iwan_element.core.result_shape`); returns the artists."""
        ax_t, ax_f, ax_z = panels(ax, 3, figsize=(6, 8))
        arts = ax_t.plot(self.t, self.modal, lw=0.6, label="mode at the sensor")
        ax_t.set_xlabel("time [s]")
        ax_t.set_ylabel("displacement [m]")
        return arts + self.curve.plot((ax_f, ax_z), label="ring-down")

    def energy_error(self) -> np.ndarray:
        """Relative energy balance error over time (needs ``record_energy``):
        ``(kinetic + strain + springs + stored + dissipated) / E0 - 1``, the dissipated
        energy of the joints, the damping floor and the effects."""
        e = self.energy
        total = e["kinetic"] + e["strain"] + e["springs"] + e["joint_stored"] + e["joint_dissipated"]
        total = total + e["floor_dissipated"]
        if e.get("effect_stored") is not None and len(e["effect_stored"]):
            total = total + e["effect_stored"] + e["effect_dissipated"]
        return total / self.initial_energy - 1.0


class _Zero:
    """A zero-force element following the joint element protocol (the base the modal
    effects wrap)."""

    force = displacement = work = stored_energy = dissipated_energy = 0.0

    def trial(self, u, v=0.0):
        return 0.0, 0.0

    def commit(self):
        pass

    def revert(self):
        pass

    def reset(self):
        pass


class _FloorWork:
    """Work done by the stiffness-proportional beam damping ``C = beta K_b`` (free
    coordinates): per step ``h v_m^T C v_m`` with ``v_m`` the mean of the step's end
    velocities, which is the damping work of the trapezoidal rule exactly and of any
    second-order scheme to ``O(h^2)`` [J]."""

    def __init__(self, beta: float, L):
        self.beta, self.Kb = beta, L.Kb
        self.t = self.v = None
        self.total = 0.0

    def step(self, t: float, v: np.ndarray) -> float:
        """Cumulative work up to time ``t`` [s] with the free velocities ``v`` [m/s]."""
        if self.beta > 0.0 and self.t is not None and t > self.t:
            vm = 0.5 * (v + self.v)
            self.total += (t - self.t) * self.beta * float(vm @ self.Kb @ vm)
        self.t, self.v = t, v.copy()
        return self.total


class _ModalEffects:
    """The specimen's effects on one mode as a modal force on the beams (module docstring)."""

    def __init__(self, specimen: Specimen, mode: int, L, phi, omega0: float):
        el = _Zero()
        self.names = []
        for e in specimen.effects:
            if e.mode == mode:
                cls = EFFECTS[e.name]
                el = cls(el, **cls.modal_to_joint(e.parameters, modal_mass=1.0,
                                                  slip_per_amplitude=1.0, omega0=omega0))
                self.names.append(e.name)
        self.el = el
        self.s = float(L.S @ phi)
        self.a_free = L.M @ phi
        self.free = L.free

    def attach(self, mbs, nodes, n_coordinates: int):
        """Add the ObjectGenericODE2 on ``nodes`` (4 ODE2 coordinates each)."""
        idx = np.concatenate([np.arange(mbs.GetNodeODE2Index(n), mbs.GetNodeODE2Index(n) + 4)
                              for n in nodes])
        a = np.zeros(n_coordinates)
        a[self.free] = self.a_free
        self.a = a[idx]
        self.aa = np.outer(self.a, self.a)
        el, s, av = self.el, self.s, self.a

        def force(mbs_, t, item, q, q_t):
            F, _ = el.trial(s * float(av @ np.asarray(q)), s * float(av @ np.asarray(q_t)))
            return (-av * (F / s)).tolist()

        def jacobian(mbs_, t, item, q, q_t, f_q, f_v):
            F, K = el.trial(s * float(av @ np.asarray(q)), s * float(av @ np.asarray(q_t)))
            c = sum(getattr(x, "c", 0.0) for x in self._stack())
            return self.aa * (K * f_q + c * f_v)

        n = idx.size
        mbs.AddObject(ObjectGenericODE2(nodeNumbers=list(nodes), massMatrix=np.zeros((n, n)),
                                        forceUserFunction=force, jacobianUserFunction=jacobian))

    def _stack(self):
        el = self.el
        while not isinstance(el, _Zero):
            yield el
            el = el.inner

    def start(self, Y0: float, n: int = 400) -> float:
        """Drive the elements from rest to ``Y0`` (virgin loading, as the static release
        state); returns their work on the beams' modal coordinate [J]."""
        for y in np.linspace(0.0, Y0, n + 1)[1:]:
            self.el.trial(float(y), 0.0)
            self.el.commit()
        return self.el.work / self.s ** 2

    def commit(self, x_free, v_free):
        self.el.trial(self.s * float(self.a_free @ x_free), self.s * float(self.a_free @ v_free))
        self.el.commit()

    def energy(self) -> tuple[float, float]:
        """(stored, dissipated) [J] on the beams' modal coordinate."""
        s2 = self.s ** 2
        return self.el.stored_energy / s2, self.el.dissipated_energy / s2


def _roundoff_force(L, specimen: Specimen) -> float:
    """Round-off level [N] of the residual norm of the specimen model (amplitude-independent).

    Exudyn forms the elastic forces from absolute nodal positions (up to the specimen's span
    ``2 L_beam - overlap`` from the origin), so each force carries a round-off of about
    ``eps k_max span`` with ``k_max`` the largest diagonal entry of ``K0`` (the axial
    stiffness of a beam element or a normal contact spring); the residual norm over the
    ``n`` coordinates is bounded by ``sqrt(n)`` times that. Measured on the Brake-Reuss model:
    the Newton residual stalls at 1e-6 to 2.5e-6 N whatever the amplitude, time step, normal
    stiffness or slip; this bound gives 1.4e-5 N.
    """
    K = L.K0.toarray() if hasattr(L.K0, "toarray") else np.asarray(L.K0)
    span = 2.0 * specimen.beam_length - specimen.overlap
    return float(np.finfo(float).eps * np.max(np.abs(np.diag(K))) * span * math.sqrt(K.shape[0]))


def _check_args(specimen, amplitude, cycles, steps_per_period) -> float:
    """Checks of :func:`ringdown`'s arguments; returns ``cycles`` as a float."""
    if not isinstance(specimen, Specimen):
        raise ValueError(f"specimen must be a Specimen, got {type(specimen).__name__}")
    if not (isinstance(amplitude, (int, float)) and math.isfinite(amplitude) and amplitude > 0):
        raise ValueError(f"amplitude must be a finite displacement > 0 [m], got {amplitude!r}")
    if isinstance(steps_per_period, bool) or not isinstance(steps_per_period, int) \
            or steps_per_period < 16:
        raise ValueError(f"steps_per_period must be an integer >= 16, got {steps_per_period!r}")
    return check_scalar("cycles", cycles, low=2.0, low_open=True)


def _initial_energy(model, st, eff) -> tuple:
    """``(kinetic, total)`` energy [J] at the release: the beams' strain energy, the springs',
    the joint's (the virgin backbone work at the initial slips) and the effects'."""
    from iwan_element import backbone_work
    kin0, pot0 = model.beam_energy()
    u0 = np.abs(st["slip"][0])
    e_joint0 = float(sum(backbone_work(u, p) for u, p in zip(u0, model.points.params)))
    e0 = pot0 + model.spring_energy() + e_joint0
    if eff is not None:
        e0 += eff.start(eff.s * float(eff.a_free @ st["x"][0]))
    return kin0, e0


def _decay_curve(t, modal, h, f0, n_periods, *, notes) -> AmplitudeCurve:
    """Frequency and damping of the modal decay by :func:`iwan_element.amplitude_curve`
    (displacement, band ``(0.5, 1.5) f0`` around the stuck frequency ``f0`` [Hz], windows
    of ``n_periods``, no second extraction: the record is noise-free), the trapezoidal
    rule's period error removed (``w_true = tan(w h / 2) 2 / h``)."""
    c = amplitude_curve(t, modal, quantity="displacement", band=(0.5 * f0, 1.5 * f0),
                        n_periods=n_periods, compare=False)
    f_true = np.tan(np.pi * c.frequency * h) / (np.pi * h)
    return dataclasses.replace(c, frequency=f_true, method="ringdown",
                               notes=f"{notes}; {c.notes}" if c.notes else notes)


def ringdown(specimen: Specimen, *, mode: int = 1, amplitude: float, cycles: float = 30,
             steps_per_period: int = 64, n_periods: float = 3.0, record_energy: bool = False,
             joint_elements: bool = False, progress: bool = False) -> RingdownResult:
    """Release the specimen from a static deflection in a mode's load shape; let it ring down.

    Parameters
    ----------
    specimen : Specimen
    mode : int, keyword-only
        Elastic mode number (1: lowest).
    amplitude : float, keyword-only
        Initial displacement amplitude at the sensor point [m] (> 0).
    cycles : float, keyword-only
        Duration in periods of the stuck linear mode (> 2).
    steps_per_period : int, keyword-only
        Time steps per period (>= 16).
    n_periods : float, keyword-only
        Periods per frequency/damping window of :func:`iwan_element.amplitude_curve`
        (range [3, 1000]; default 3, the most points a short record gives).
    record_energy : bool, keyword-only
        Record the energy terms every step (slower).
    joint_elements : bool, keyword-only
        Use one Python ``IwanJoint`` connector per point (reference route) instead of the
        compiled interface law.
    progress : bool, keyword-only
        Show a tqdm bar over the time steps with its ETA; needs tqdm.

    Returns
    -------
    RingdownResult

    Notes
    -----
    Newton (modified Newton, relative tolerance 1e-10) stops when the residual norm falls
    below ``max(1e-7 F, F_ro)`` [N]: ``F = max |K0 x0|``, the largest elastic force of the
    release state, scales with the amplitude; ``F_ro = eps k_max span sqrt(n)`` is the
    amplitude-independent round-off of the residual (:func:`_roundoff_force`). Below about
    10 um on the Brake-Reuss beam ``1e-7 F`` fell under the round-off (residual stalling at
    1e-6 to 2.5e-6 N), Newton never converged and the step was cut without end; with the
    bound the 2 um run takes seconds and agrees with QSMA (``tests/test_qsma.py``).
    No discontinuous iteration is involved (one per step, Exudyn's default): the compiled
    law is an explicit function of the slip given the committed state, which changes only
    in the post-step of an accepted step. The stall is round-off, not the modified Newton:
    it stays with the time step (24 to 96 steps/period), the normal stiffness (/10) and with
    stuck joints (friction 1e3).
    """
    cycles = _check_args(specimen, amplitude, cycles, steps_per_period)
    n_periods = check_scalar("n_periods", n_periods, low=3.0, high=1000.0)
    st = static_modal_load(specimen, [amplitude], mode=mode)
    L, phi, w0 = st["system"], st["phi"], st["omega0"]
    beta = floor_damping(specimen, mode=mode)
    e_keys = ("t", "kinetic", "strain", "springs", "joint_stored", "joint_dissipated",
              "floor_dissipated", "effect_stored", "effect_dissipated")
    floor_work = _FloorWork(beta, L)
    energy = {k: [] for k in e_keys}
    coords, times = [], []
    handle = {"bar": None}
    eff = _ModalEffects(specimen, mode, L, phi, w0) if any(
        e.mode == mode for e in specimen.effects) else None

    def post_step(mbs_, t):
        times.append(t)
        if handle["bar"] is not None and len(times) % 50 == 0:
            tick(handle["bar"], 50)
        coords.append(mbs_.systemData.GetODE2Coordinates())
        if eff is not None:
            eff.commit(coords[-1][L.free], np.asarray(
                mbs_.systemData.GetODE2Coordinates_t())[L.free])
            if record_energy:
                es, ed = eff.energy()
                energy["effect_stored"].append(es)
                energy["effect_dissipated"].append(ed)
        if record_energy:
            model = handle["model"]
            energy["floor_dissipated"].append(floor_work.step(
                t, np.asarray(mbs_.systemData.GetODE2Coordinates_t())[L.free]))
            kin, pot = model.beam_energy()
            energy["t"].append(t)
            energy["kinetic"].append(kin)
            energy["strain"].append(pot)
            energy["springs"].append(model.spring_energy())
        return True

    model = build_specimen_model(specimen, tangential="iwan", beam_damping=beta,
                                 post_step=post_step, joint_elements=joint_elements)
    handle["model"] = model
    mbs = model.mbs
    if eff is not None:
        eff.attach(mbs, model.nodes, L.n_coordinates)
        mbs.Assemble()
    x0 = np.zeros(L.n_coordinates)
    x0[L.free] = st["x"][0]
    mbs.systemData.SetODE2Coordinates(x0, configuration=exu.ConfigurationType.Initial)
    mbs.systemData.SetODE2Coordinates(x0, configuration=exu.ConfigurationType.Current)
    kin0, e0 = _initial_energy(model, st, eff)
    h = 2 * math.pi / (w0 * steps_per_period)
    n = int(round(cycles * steps_per_period))
    sim = solver_settings(force_scale=float(np.max(np.abs(L.K0 @ st["x"][0]))))
    newton = sim.timeIntegration.newton
    newton.absoluteTolerance = max(newton.absoluteTolerance, _roundoff_force(L, specimen))
    sim.timeIntegration.numberOfSteps = n
    sim.timeIntegration.endTime = n * h
    t0 = time.perf_counter()
    handle["bar"] = progress_bar(progress, total=n + 1, desc="ringdown", unit="step")
    try:
        mbs.SolveDynamic(sim)
        tick(handle["bar"], len(times) % 50)          # the steps since the last tick
    finally:
        finish(handle["bar"])
    wall = time.perf_counter() - t0
    quad = _joint_records(model.interface, energy, e0) if record_energy else None
    X = np.array(coords)[:, L.free]
    t, (sensor, modal), cut = _on_step_grid(
        np.array(times), [X @ L.S, (X @ (L.M @ phi)) * float(L.S @ phi)], h, n)
    curve = _decay_curve(t, modal, h, w0 / (2 * math.pi), n_periods, notes=(
        f"{specimen.name}: Exudyn transient, mode {mode}, {steps_per_period} steps/period, "
        f"released from {amplitude:.3g} m at the sensor; modal filtering"
        + (f"; with {' + '.join(eff.names)}" if eff else "")))
    return _checked(RingdownResult(
        t=t, sensor=sensor, modal=modal, curve=curve,
        energy={k: np.array(v) for k, v in energy.items()}, initial_energy=e0, wall_time=wall,
        metadata={"h": h, "steps": n, "extra_steps": cut, "beam_damping": beta,
                  "n_points": len(model.points),
                  "effects": tuple(eff.names) if eff else (), "kinetic_at_release": kin0,
                  "joint_quadrature_error": quad},
        warnings=tuple(curve.warnings) + _cut_warning(cut, n, w0 * h)))


def _on_step_grid(times, signals, h, n):
    """Signals recorded once per accepted step (at ``times`` [s]) on the nominal grid
    ``k h``, ``k = 0..n``: ``(t, signals, cut)``. Where the interface slips hard,
    Exudyn cuts the step (measured: 1,689 accepted steps instead of 512 on the two-bolt
    aluminium beam released from 500 um); the records are then interpolated linearly onto the
    grid (``cut``: how many steps more than ``n`` were taken). Read as if every record were one
    nominal step apart, they had stretched the time scale: the decay came out at half its
    frequency."""
    t = np.arange(n + 1) * h
    if times.size == n + 1 and np.allclose(times, t, rtol=0.0, atol=1e-9 * h):
        return t, list(signals), 0
    return t, [np.interp(t, times, y) for y in signals], int(times.size - 1 - n)


def _cut_warning(cut: int, n: int, wh: float) -> tuple:
    """The warning of a ring-down whose solver took ``cut`` steps more than its ``n``
    nominal ones (``wh``: the nominal step times the linear frequency [rad])."""
    if not cut:
        return ()
    return (f"the solver took {cut} steps more than the {n} nominal ones (the interface "
            "slipping hard); the records were interpolated onto the nominal step, whose "
            f"trapezoidal period correction (up to {wh * wh / 12:.1e} of the frequency) is "
            "applied as if no step had been cut: give more steps_per_period for a frequency "
            "closer than that",)


def _joint_records(itf, energy: dict, e0: float) -> float:
    """Fill the joints' stored and dissipated energy into ``energy`` from the interface's
    records, and return their exact work minus the trapezoidal work ``sum (F_n + F_n+1) du / 2``
    of the same slips and forces, over the release energy ``e0`` [-]: the time integrator's
    quadrature error of the hysteretic forces, which is what the energy balance measures
    when the bookkeeping is right."""
    # the interface commits after the user post-step of the same step: its records (one per
    # accepted step, and one at t = 0) line up with ours
    m = len(energy["t"])
    energy["joint_stored"] = list(itf.stored_energy_history[-m:])
    energy["joint_dissipated"] = list(itf.dissipated_energy_history[-m:])
    u, F, W = itf.slip_history[-m:], itf.force_history[-m:], itf.work_history[-m:]
    trap = float(np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(u, axis=0)))
    return (float(W[-1] - W[0]) - trap) / e0


def _checked(out: RingdownResult) -> RingdownResult:
    """The result with a warning when its recorded energy balance is off by more than
    :data:`ENERGY_TOL`."""
    err = out.max_energy_error
    if err is not None and err > ENERGY_TOL:
        out = replace(out, warnings=out.warnings + (
            f"the energy balance is off by {err:.2g} of the release energy (more than "
            f"{ENERGY_TOL:g}; the time integrator's quadrature of the joint forces accounts for "
            f"{out.metadata['joint_quadrature_error']:.2g}): refine steps_per_period",))
    return out
