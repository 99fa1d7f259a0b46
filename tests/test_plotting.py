"""Plot functions: ax=None makes a figure, artists are returned, nothing is shown."""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import pytest

from iwan_element import IwanParameters
from iwan_element.plotting import plot_loop, plot_normalized_loops


def test_normalized_loops_returns_three_lines_per_case():
    lines = plot_normalized_loops([(0.0, 0.5), (1.0, 0.5)])
    assert len(lines) == 6
    plt.close("all")


def test_nonphysical_case_warns_and_draws():
    fig, ax = plt.subplots()
    with pytest.warns(UserWarning, match="non-physical"):
        lines = plot_normalized_loops([(-0.5, 1.0)], ax=ax)
    assert all(line.axes is ax for line in lines)
    plt.close(fig)


def test_plot_loop_units():
    p = IwanParameters(1000.0, 1e6, -0.5, 0.2)
    fig, ax = plt.subplots()
    (line,) = plot_loop(1e-4, p, ax=ax, label="loop")
    x, y = line.get_data()
    assert abs(max(x) - 0.1) < 1e-12  # mm
    assert max(y) < 1.0  # kN, below Fs = 1 kN
    plt.close(fig)
