"""Helpers shared by the tests (``from support.truth import ...``): the repository's paths
(``paths``), truth that does not come from the code under test (``truth``), simulated
drives and records for the integrated navigator (``drives``) and command-line helpers
(``commands``). The folder tests/ is on sys.path through tests/conftest.py."""
