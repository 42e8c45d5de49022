"""The FMUs from Python: where the shipped FMUs are and their validation (``paths``), the
generic fmpy runner (``runner``), the per-model runners (``models``), the integrated
navigator's FMU parameters and driver (``ins_gnss``), and co-simulation: systems and their
builders (``system``), the Python master (``master``), SSP files (``ssp``), container FMUs
(``container``), the cffi references and comparisons (``reference``) and OSP libcosim as a
second master (``osp``). See docs/fmu.md and docs/cosim.md."""
from gfins_fmi.fmi.container import run_container, write_container
from gfins_fmi.fmi.ins_gnss import InsGnssDriver, ins_gnss_fmu_parameters, run_ins_gnss_fmu
from gfins_fmi.fmi.master import CoSimulation
from gfins_fmi.fmi.models import run_accel9_fmu, run_gfnav_fmu, run_sins_fmu
from gfins_fmi.fmi.paths import MODELS, FmuRunError, fmu_path, validate
from gfins_fmi.fmi.reference import (compare_runners, differences_from_direct, direct_navigation,
                                     integrated_recording, navigation_errors)
from gfins_fmi.fmi.runner import FmuLog, FmuSlave, run_fmu
from gfins_fmi.fmi.ssp import run_ssp, write_ssp
from gfins_fmi.fmi.system import (AIDING_VARIABLES, NAVIGATORS, Connection, InitialError, System,
                                  integrated_example, vehicle_integrated_navigation,
                                  vehicle_navigation)

__all__ = ["MODELS", "FmuRunError", "fmu_path", "validate", "FmuLog", "FmuSlave", "run_fmu",
           "run_accel9_fmu", "run_sins_fmu", "run_gfnav_fmu", "ins_gnss_fmu_parameters",
           "InsGnssDriver", "run_ins_gnss_fmu", "System", "Connection", "vehicle_navigation",
           "vehicle_integrated_navigation", "InitialError", "integrated_example", "NAVIGATORS",
           "AIDING_VARIABLES", "CoSimulation", "write_ssp", "run_ssp", "write_container",
           "run_container", "direct_navigation", "integrated_recording", "navigation_errors",
           "differences_from_direct", "compare_runners"]
