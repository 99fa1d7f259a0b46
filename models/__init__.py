"""Models built on iwan_element's public API; installed as ``iwan_element.models``.

* :mod:`iwan_element.models.jointed_beam` - the two-beam bolted lap joint in Exudyn;
* ``example_test_30kN.csv`` - a SYNTHETIC quasi-static test of the seed paper's specimen
  (see ``README.md`` here and ``make_example_test.py``); :func:`example_test_path` finds it.
"""
from importlib import resources
from pathlib import Path

__all__ = ["example_test_path"]


def example_test_path() -> Path:
    """Path of the shipped synthetic example test record (CSV: time [s], mm, kN)."""
    return Path(str(resources.files(__name__).joinpath("example_test_30kN.csv")))
