"""A specimen's interface from a joint or a modal Iwan fit.

:func:`interface_from_joint` maps a lumped joint (``Fs, KT, chi, beta``, e.g. from
``fit_loops`` of a lap-shear test) onto the distributed interface: ``mu = Fs /
sum(preloads)`` (in a shear test every point slips at ``mu N_i``, and ``sum N_i = sum P``)
and ``k_t = KT / A_contact``; chi and beta carry over. :func:`interface_from_modal_iwan`
maps a modal Iwan model (modal units, Segalman 2005, docs/equations.md section 7,
``w0^2 = K_inf + KT``): ``k_t`` such that the stuck mode's ``w^2`` exceeds that of the
tangentially free lap (``K_inf``, macroslip) by ``KT_modal``, and ``mu`` such that the
points' slip forces weighted by the mode's slip shape ``g_i = du_i/dq`` sum to the modal
macroslip force, ``sum |g_i| mu N_i = Fs_modal`` (an approximation: the points do not all
reach macroslip at once). The calibration from vibration data is
:func:`~iwan_element.models.calibration.vibration.calibrate`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize

from iwan_element import IwanParameters

from ..modal.qsma import linear_modes
from ..reduced.dispatch import contact_points
from ..specimens.specimen import Specimen

__all__ = ["interface_from_joint", "interface_from_modal_iwan"]


def interface_from_joint(specimen: Specimen, joint: IwanParameters) -> Specimen:
    """Distributed interface carrying a lumped joint's parameters (module docstring).

    ``joint`` describes the whole lap in shear (``Fs`` [N], ``KT`` [N/m]), e.g. a loop fit.
    """
    if not isinstance(joint, IwanParameters):
        raise ValueError("joint must be IwanParameters")
    pts = contact_points(specimen.replace(stiffness_pressure_exponent=0.0))
    return specimen.replace(
        friction=joint.Fs / pts.normal_force.sum(),
        stiffness_per_area=joint.KT / pts.area.sum(),
        stiffness_pressure_exponent=0.0,
        chi=joint.chi,
        beta=joint.beta,
    )


def interface_from_modal_iwan(
    specimen: Specimen, modal: IwanParameters, *, mode: int = 1
) -> Specimen:
    """Distributed interface reproducing a modal Iwan joint (modal units, module docstring).

    ``modal.KT`` [1/s^2, i.e. N/m per kg with mass-normalised modes] is the joint's share of
    the mode's stiffness and ``modal.Fs`` its macroslip modal force; the slip shape of the
    stuck mode distributes them over the contact points.
    """
    if not isinstance(modal, IwanParameters):
        raise ValueError("modal must be IwanParameters (modal units)")
    # the joint's modal stiffness is what it adds to the mode, KT_modal = w_stuck^2 - K_inf,
    # with K_inf = w^2 of the tangentially free lap (macroslip); w_stuck rises monotonically
    # with k_t (eigenvalue monotonicity), so k_t follows by bracketing
    k0 = math.log(specimen.interface.stiffness_per_area)
    w_inf, *_ = linear_modes(specimen.replace(stiffness_per_area=math.exp(k0 - 25.0)), mode=mode)

    def modal_stiffness(log_kt):
        sp = specimen.replace(stiffness_per_area=math.exp(log_kt))
        w, phi, _, L, pts = linear_modes(sp, mode=mode)
        return w * w - w_inf * w_inf, float(np.sum(np.abs(L.G @ phi) * pts.normal_force))

    lo, hi = k0 - 8.0, k0 + 8.0
    f_lo, f_hi = modal_stiffness(lo)[0] - modal.KT, modal_stiffness(hi)[0] - modal.KT
    if f_lo > 0 or f_hi < 0:
        raise ValueError(
            f"modal.KT = {modal.KT:.4g} is outside what this interface can carry "
            f"in mode {mode} ({f_lo + modal.KT:.4g} .. {f_hi + modal.KT:.4g})"
        )
    log_kt = optimize.brentq(lambda v: modal_stiffness(v)[0] - modal.KT, lo, hi, xtol=1e-10)
    _, gN = modal_stiffness(log_kt)
    return specimen.replace(
        friction=modal.Fs / gN, stiffness_per_area=math.exp(log_kt), chi=modal.chi, beta=modal.beta
    )
