"""Simulation, the truth of tests, benchmarks and studies: closed-form motions with their
exact sensor outputs (``trajectory``), a ground vehicle with its IMU and aiding sensors on
the C core (``vehicle``), the rotating IMU of seed 001 (``rotation``) and simulated drives
with the filter's own noise model (``scenarios``)."""
from gfins_fmi.sim.scenarios import (CONSUMER, NAVIGATION, TACTICAL, SimulatedDrive, simulate_drive,
                                     town_drive)
from gfins_fmi.sim.trajectory import Trajectory, sample
from gfins_fmi.sim.vehicle import (Barometer, GnssReceiver, Odometer, Segment, VehicleProfile,
                                   VehicleRecord, simulate_vehicle)

__all__ = ["Trajectory", "sample", "Segment", "VehicleProfile", "VehicleRecord",
           "simulate_vehicle", "GnssReceiver", "Barometer", "Odometer", "SimulatedDrive",
           "simulate_drive", "town_drive", "TACTICAL", "NAVIGATION", "CONSUMER"]
