"""A test read from a file, with its units: a loop test from CSV (:func:`load_test`), a
sweep from CSV (:func:`read_sweep_csv`), a ring-down or sweep told apart by its header
(:func:`read_vibration_csv`) or Universal File Format records (:func:`read_uff`),
and the unit checks of vibration data (damping in percent, frequency in rad/s).

Imports :mod:`iwan_element.base` and :mod:`..loops` (the test record it builds) only.
"""

from .csv_input import load_test
from .formats import UffRecord, read_sweep_csv, read_uff
from .units import check_damping_ratio, check_frequency_ratio
from .vibration import file_kind, read_vibration_csv

__all__ = [
    "load_test",
    "read_uff",
    "UffRecord",
    "read_sweep_csv",
    "read_vibration_csv",
    "file_kind",
    "check_damping_ratio",
    "check_frequency_ratio",
]
