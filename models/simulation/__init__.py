"""A specimen simulated in Exudyn: the host (its linear system as one generic body, the
contact points' Iwan elements on slip coordinates), the solver settings, ring-downs after a
release or a hammer impact, the coupling of modes ringing together, the stepped-sine forced
response and the quasi-static machine test.
"""

from .coupling import ModeCouplingResult, compare_curves, mode_coupling, plot_curve_pairs
from .forced import ForcedResponseResult, forced_response, prewarp
from .host import HostModel, build_host, port_basis
from .impact import Impact
from .machine import QuasiStaticResult, quasi_static_test
from .modal_force import ModalEffects
from .ringdown_result import ENERGY_TOL, RingdownResult, decay_curve, with_energy_warning
from .solver import solver_settings
from .transient import check_solid_release, ringdown

__all__ = [
    "build_host",
    "HostModel",
    "port_basis",
    "solver_settings",
    "ringdown",
    "RingdownResult",
    "check_solid_release",
    "ENERGY_TOL",
    "with_energy_warning",
    "decay_curve",
    "Impact",
    "ModalEffects",
    "mode_coupling",
    "ModeCouplingResult",
    "compare_curves",
    "plot_curve_pairs",
    "forced_response",
    "ForcedResponseResult",
    "prewarp",
    "quasi_static_test",
    "QuasiStaticResult",
]
