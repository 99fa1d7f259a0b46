"""Identification: test records and units, loop and dissipation fits."""
from .decay_fit import fit_decay  # noqa: E402,F401  (direct fit of a free decay, issue 22)
from .decay_modes import free_decay_modes  # noqa: E402,F401  (linear targets, issue 41)
from .frf_modes import frf_modes, sweep_modes  # noqa: E402,F401
from .modal_targets import ModalTargets, ModeTarget, mac  # noqa: E402,F401
