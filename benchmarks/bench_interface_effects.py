"""The transient's cost of the vibration effects in the joint (the interface's Python route).

Run:  python benchmarks/bench_interface_effects.py {plain,joint}

The two-mode ring-down of ``tests/test_interface_effects.py`` (Brake-Reuss beam, 24 contact
points, modes 1 and 2 released together from 60 and 3 um, 0.16 s at 32 steps a period):
``plain``, the compiled Iwan law at every point; ``joint``, every point's Iwan element with
the four effects around it (a pin at the bolts, a spread patch, a cubic spring, a dashpot;
one Python connector a point). Time the two side by side with ``farm-bench -n 3 --vs
"python benchmarks/bench_interface_effects.py plain" -- python
benchmarks/bench_interface_effects.py joint``.

Prints the steps taken and the largest energy error.
"""

from __future__ import annotations

import argparse

from iwan_element.models import InterfaceEffect

from iwan_element import models

EFFECTS = (
    InterfaceEffect("pinning_stiffness", values={"k_p": 7.8e7, "delta": 6.8e-8}),
    InterfaceEffect("macroslip_onset", values={"k_2": 5e7, "u_s": 1.27e-7, "shape": 0.45}),
    InterfaceEffect("hardening", values={"k3": 1.7e20}),
    InterfaceEffect("viscous_damping", values={"c": 1.7e4}),
)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("interface", choices=("plain", "joint"))
    a = ap.parse_args(argv)
    s = models.preset("brake-reuss").replace(n_points=24, modal_damping=(1.3e-3, 9.6e-4))
    if a.interface == "joint":
        s = s.replace(interface_effects=EFFECTS)
    r = models.ringdown(
        s, amplitude={1: 60e-6, 2: 3e-6}, duration=0.16, steps_per_period=32, record_energy=True
    )
    print(f"{a.interface}: {r.metadata['steps']} steps, energy error {r.max_energy_error:.1e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
