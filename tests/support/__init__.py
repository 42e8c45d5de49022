"""Helpers shared by the tests (``from support.truth import ...``): the repository's paths
(``paths``), truth that does not come from the code under test (``truth``), simulated
drives and records for the integrated navigator (``drives``), the C smoother's raw
outputs (``smoothing``) and command-line helpers (``commands``). The folder tests/ is on
sys.path through tests/conftest.py."""
