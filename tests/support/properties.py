"""The hypothesis settings of the property-based tests: few or some cases, derandomized (the
same cases every run; a failure prints the falsifying example). Import after
``pytest.importorskip("hypothesis")``: hypothesis is in the test extra."""
from __future__ import annotations

from hypothesis import HealthCheck, settings

FEW = settings(max_examples=6, deadline=None, derandomize=True,
               suppress_health_check=[HealthCheck.too_slow])
SOME = settings(max_examples=15, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow])
