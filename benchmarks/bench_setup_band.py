"""The two-bolt aluminium beam from its description: modes 1 and 2 with the test setup in the
model (a shaker's moving mass on its stinger 85 mm from the clamp, a clamp that is not rigid)
and the band the setup's physical ranges give (``models.updating.prior_band``: each value
drawn from its prior, the 2.5, 50 and 97.5 % quantiles of each mode's stuck frequency).

    python benchmarks/bench_setup_band.py [--draws 200] [--seed 0]
"""

from __future__ import annotations

import argparse
import sys
import time

from iwan_element.models.updating import prior_band

from iwan_element import models


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args(argv)
    spec = models.preset("two-bolt-aluminium")
    print(spec.setup.describe())
    print("  reference:", spec.setup.reference)
    bare = models.natural_frequencies(spec.replace(setup=models.Setup()), n_modes=2)
    print(f"without the setup (rigid clamp, no shaker): {bare[0]:.2f}, {bare[1]:.2f} Hz")
    t0 = time.perf_counter()
    band = prior_band(
        spec, parameters=("attachments", "boundary"), modes=(1, 2), n=a.draws, rng=a.seed
    )
    print(
        f"with the setup, {a.draws} draws from the setup's ranges "
        f"({time.perf_counter() - t0:.1f} s):"
    )
    for r, b in band.items():
        q = b["quantiles"]
        print(
            f"  mode {r}: nominal {b['nominal']:.2f} Hz, median {q[0.5]:.2f}, 95 % band "
            f"{q[0.025]:.2f} .. {q[0.975]:.2f} Hz"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
