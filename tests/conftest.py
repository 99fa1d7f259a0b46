"""Shared test configuration: the hypothesis settings profiles.

The number of examples is bounded so that the suite stays fast: ``ci`` (default, 40 examples,
no deadline, derandomised) or ``long`` (1000 examples), chosen with the environment variable
``IWAN_HYPOTHESIS_PROFILE`` (or any count with ``IWAN_HYPOTHESIS_EXAMPLES``, which
``benchmarks/bench_properties.py`` sets). Shared helpers and strategies live in
``tests/_helpers.py`` (one copy each).
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

settings.register_profile(
    "ci",
    max_examples=40,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile(
    "long", max_examples=1000, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
if os.environ.get("IWAN_HYPOTHESIS_EXAMPLES"):
    settings.register_profile(
        "custom",
        max_examples=int(os.environ["IWAN_HYPOTHESIS_EXAMPLES"]),
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow],
    )
    settings.load_profile("custom")
else:
    settings.load_profile(os.environ.get("IWAN_HYPOTHESIS_PROFILE", "ci"))
