"""The specimen in the frequency domain: harmonic balance, continuation and nonlinear modes.

Every route reads the specimen's one reduced model (:func:`~iwan_element.models.reduced.
reduced_model`: stuck modes with their own floors, residual flexibility, the contact points'
exact Iwan elements on the slips) and the engine of :mod:`iwan_element.harmonic`
(``docs/harmonic_balance.md``). The specimen's interface effects (``specimen.interface_effects``,
physical form) sit beside each contact point's joint on its slip, in the compiled kernel
with exact Jacobians. The specimen's modal vibration effects (``specimen.effects``, e.g.
from ``VibrationDiagnosis.augment``) act as in the transient (:mod:`.transient`): their
time-domain elements (``EFFECTS[name]`` with the joint values of ``modal_to_joint`` at unit
modal mass in sensor units) on the sensor-scaled modal coordinate ``Y = s q_r`` of their
mode, ``s = S phi_r``, loading the mode with ``-F(Y)/s``: an element port of the modal
system with mode shape ``s`` on mode ``r`` and gain ``1/s^2``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from iwan_element import AmplitudeCurve
from iwan_element.harmonic import FrequencyResponse, ModalSystem, trace
from iwan_element.harmonic import harmonic_balance as _hb_system
from iwan_element.harmonic.basis import Harmonics, check_harmonics
from iwan_element.harmonic.nlmode import epmc_branch
from iwan_element.harmonic.system import ElementPort

from ..reduced.dispatch import check_specimen
from ..reduced.model import reduced_model
from ..specimens.specimen import Specimen
from .effects import effect_stack
from .interface import interface_laws
from .limits import macroslip_report, size_limit, size_warnings
from .qsma import extrapolation_warnings, resolve_interface_effects

__all__ = ["harmonic_balance", "frequency_response", "nonlinear_mode", "specimen_system"]


def specimen_system(specimen: Specimen, *, n_modes: int = 8) -> ModalSystem:
    """The specimen's modal system: its reduced model, its interface effects beside each
    contact point's joint (``joint_forms``: each point's effect stack in the compiled kernel's
    terms, :meth:`~iwan_element.models.modal.interface.InterfaceLaws.forms`), and its modal
    effects as element ports.
    """
    specimen = resolve_interface_effects(specimen)
    red = reduced_model(specimen, n_modes=n_modes)
    sysm = red.system
    laws = interface_laws(specimen)
    if laws is not None:
        forms = laws.forms()
        if any(f is None for f, st in zip(forms, laws.stacks) if st):
            raise ValueError(
                f"interface_effects {list(laws.names)}: every effect in the joint must state "
                "its periodic form (Effect.periodic_form) for the frequency-domain routes"
            )
        sysm = replace(sysm, joint_forms=forms)
    ports, rows = [], []
    nz = sysm.n_z
    for mode in sorted({e.mode for e in specimen.effects}):
        r = red.mode_index(mode)
        s = float(sysm.modes[nz, r])
        el, names = effect_stack(specimen, mode, float(sysm.omega[r]))
        row = np.zeros(sysm.omega.size)
        row[r] = s
        ports.append(ElementPort(el, 1.0 / (s * s), label=f"mode {mode}: {' + '.join(names)}"))
        rows.append(row)
    return sysm.with_ports(ports, rows) if ports else sysm


def _check(specimen):
    check_specimen(specimen)


def _with_range_warnings(specimen, response):
    """The response with a warning where its converged amplitudes leave the specimen's (or an
    effect's) calibrated range or its size (:func:`~.limits.size_warnings`), as QSMA and the
    nonlinear modes warn, and not usable where the whole lap is fully slipped
    (:func:`~.limits.macroslip_report`; where each bolt is, the engine's own warning says).
    """
    ok = response.converged
    X = response.amplitude[ok]
    warns = (
        extrapolation_warnings(specimen, X)
        + size_warnings(specimen, X, what="response amplitude", given=False)
        if X.size
        else []
    )
    failures = []
    if response.slip_ratio is not None and X.size:
        _, failures = macroslip_report(
            specimen, response.slip_ratio[ok], response.frequency[ok], unit="Hz", what="frequencies"
        )
    failures += _runaway(specimen, response)
    if not warns and not failures:
        return response
    return replace(
        response,
        warnings=tuple(response.warnings) + tuple(warns),
        failures=tuple(response.failures) + tuple(failures),
    )


def _runaway(specimen, response) -> list:
    """A failure naming the likely cause when points that did not converge left their last
    iterate beyond the specimen's size (:func:`~.limits.size_limit`): the load drives the lap
    past macroslip, where only the floor damping bounds the response, so tracing a turning
    point by continuation (the engine's own advice) cannot help.
    """
    bad = ~np.asarray(response.converged, bool)
    X = np.asarray(response.amplitude, float)[bad]
    X = X[np.isfinite(X)]
    lim = size_limit(specimen)
    if not X.size or X.max() <= lim:
        return []
    return [
        f"{int((X > lim).sum())} of {bad.size} frequencies stopped with their last iterate "
        f"at {X.max():.3g} m, {X.max() / lim:.3g} x the beam's size ({lim * 1e3:.3g} mm): at "
        "this force the lap is driven past macroslip, where nothing but the floor damping "
        "bounds the slip, so no response of the joint is there to find: lower the force"
    ]


def harmonic_balance(
    specimen: Specimen,
    *,
    frequency,
    force,
    harmonics=(1, 3, 5),
    samples=None,
    n_modes: int = 8,
    progress: bool = False,
) -> FrequencyResponse:
    """Steady forced response of the specimen at given frequencies and forces.

    Parameters
    ----------
    specimen : Specimen
        The force acts transversely at ``specimen.excitation.position``; the amplitude and
        phase are read at ``specimen.sensor_position``.
    frequency : array_like, shape (n,)
        Excitation frequencies [Hz], solved in the order given (each from its neighbour).
    force : float or array_like, shape (n,)
        Fundamental force amplitude [N], one value or one per frequency (a response-
        controlled test varies it).
    harmonics : int or sequence of int, keyword-only
        Harmonics kept (default 1, 3, 5: an odd joint law without static load).
    samples : int, optional, keyword-only
        AFT samples per period.
    n_modes : int, keyword-only
        Elastic modes kept in the reduced model (the rest as residual flexibility).
    progress : bool, keyword-only
        Show a tqdm bar with its ETA (silent under CI).

    Returns
    -------
    FrequencyResponse
        ``amplitude`` [m] and ``phase`` [rad] of the sensor's fundamental displacement, every
        harmonic, per point ``converged`` and the energy per period. ``warnings``: converged
        amplitudes outside the specimen's calibrated (or documented) range (or above an
        effect's) or its size, and the bolts whose contact is fully slipped (with the
        frequencies); a whole lap fully slipped makes it not usable
        (:mod:`~iwan_element.models.modal.limits`).
    """
    _check(specimen)
    return _with_range_warnings(
        specimen,
        _hb_system(
            specimen_system(specimen, n_modes=n_modes),
            frequency=frequency,
            force=force,
            harmonics=harmonics,
            samples=samples,
            progress=progress,
        ),
    )


def frequency_response(
    specimen: Specimen,
    *,
    force: float,
    band,
    harmonics=(1, 3, 5),
    samples=None,
    n_modes: int = 8,
    step: float = 0.02,
) -> FrequencyResponse:
    """The frequency response curve at one force level [N] over ``band`` (start, end) [Hz],
    traced by pseudo-arclength continuation through its turning points
    (:func:`iwan_element.harmonic.trace`); warned as :func:`harmonic_balance`.
    """
    _check(specimen)
    return _with_range_warnings(
        specimen,
        trace(
            specimen_system(specimen, n_modes=n_modes),
            force=force,
            band=band,
            harmonics=harmonics,
            samples=samples,
            step=step,
        ),
    )


def nonlinear_mode(
    specimen: Specimen,
    *,
    amplitude=None,
    mode: int = 1,
    harmonics=(1, 3, 5),
    samples=None,
    n_modes: int = 8,
    progress: bool = False,
) -> AmplitudeCurve:
    """Amplitude-dependent frequency and damping of a mode by EPMC.

    Parameters
    ----------
    specimen : Specimen
    amplitude : array_like, optional
        Fundamental displacement amplitudes at the sensor [m] (default: 20 log-spaced over
        ``specimen.amplitude_range``).
    mode : int, keyword-only
        Elastic mode (1: lowest); it must be among the ``n_modes`` kept.
    harmonics, samples, n_modes, progress : keyword-only
        As :func:`harmonic_balance`.

    Returns
    -------
    AmplitudeCurve
        ``method="epmc"``; frequency [Hz] and damping ratio ``xi / (2 W)`` [-] (the floor
        and the joints' and effects' dissipation), ready for ``diagnose_vibration`` and
        ``calibrate``. ``warnings``: amplitudes where Newton did not converge, outside the
        specimen's calibrated (or documented) range or its size, and the bolts whose contact
        is fully slipped (:mod:`~iwan_element.models.modal.limits`); a whole lap fully
        slipped makes it not usable (``failures``).
    """
    _check(specimen)
    if amplitude is None:
        lo, hi = specimen.amplitude_range  # [m]
        X = np.geomspace(lo, hi, 20)
    else:
        X = np.atleast_1d(np.asarray(amplitude, dtype=float))
        if X.ndim != 1 or X.size == 0 or not np.all(np.isfinite(X)) or np.any(X <= 0):
            raise ValueError("amplitude must be a non-empty 1-D sequence of finite values > 0 [m]")
    red = reduced_model(specimen, n_modes=n_modes)
    r = red.mode_index(mode)
    basis = Harmonics(*check_harmonics(harmonics, samples))
    out = epmc_branch(specimen_system(specimen, n_modes=n_modes), basis, X, r, progress=progress)
    warns = []
    bad = ~out["converged"]
    if bad.all():
        raise ValueError(
            f"EPMC converged at none of the {X.size} amplitudes of mode {mode}; "
            "give amplitudes closer to the specimen's amplitude_range"
        )
    if bad.any():
        warns.append(
            f"EPMC did not converge at {int(bad.sum())} of {X.size} amplitudes "
            f"({X[bad].min():.3g} .. {X[bad].max():.3g} m); those points are left "
            "out"
        )
    ok = ~bad
    slipped, failures = macroslip_report(
        specimen, out["slip_ratio"][ok], X[ok], unit="m", what="amplitudes"
    )
    warns += extrapolation_warnings(specimen, X[ok]) + size_warnings(specimen, X) + slipped
    return AmplitudeCurve(
        X[ok],
        out["frequency"][ok],
        out["damping_ratio"][ok],
        method="epmc",
        notes=(
            f"{specimen.name}: mode {mode} by EPMC, harmonics {basis.harmonics}, "
            f"{basis.samples} samples per period, {red.system.notes}; largest energy "
            f"error per period {np.nanmax(np.abs(out['energy_error'][ok])):.1e}"
        ),
        warnings=tuple(warns),
        failures=tuple(failures),
    )
