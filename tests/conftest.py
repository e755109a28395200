"""Hypothesis profiles.

``make test`` (and CI) run the property tests derandomized: the same examples on every run
for a given Hypothesis version and test, so a red run is reproducible and main does not turn
red by luck. ``make fuzz`` (HYPOTHESIS_PROFILE=explore) runs them again and again with new
random examples; whatever it finds becomes a plain regression test. Neither profile has a
deadline: timing is for bench/, and a loaded 2-core CI machine must not fail a property.
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

settings.register_profile("repeatable", derandomize=True, database=None, deadline=None,
                          print_blob=True)
settings.register_profile("explore", deadline=None, print_blob=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "repeatable"))
