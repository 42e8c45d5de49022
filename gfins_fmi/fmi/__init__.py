"""The FMUs from Python: where the shipped FMUs are and their validation (``paths``), the
generic fmpy runner (``runner``), the per-model runners (``models``), the integrated
navigator's FMU parameters and driver (``ins_gnss``), and co-simulation: systems and their
builders (``system``), the Python master (``master``), SSP files (``ssp``), container FMUs
(``container``), the cffi references and comparisons (``reference``) and OSP libcosim as a
second master (``osp``). See docs/fmu.md and docs/cosim.md.

Import from the modules: this package's ``__init__`` imports nothing (``import gfins_fmi``
loads only what its own names need).
"""
