"""Identification: test records and units, loop and dissipation fits."""
from .decay_fit import fit_decay  # noqa: E402,F401  (direct fit of a free decay, issue 22)
