"""Simulation, the truth of tests, benchmarks and studies: closed-form motions with their
exact sensor outputs (``trajectory``), a ground vehicle with its IMU and aiding sensors on
the C core (``vehicle``), the rotating IMU of seed 001 (``rotation``) and simulated drives
with the filter's own noise model (``scenarios``).

Import from the modules: this package's ``__init__`` imports nothing (``import gfins_fmi``
loads only what its own names need).
"""
