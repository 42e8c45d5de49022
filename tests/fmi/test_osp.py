"""A second, independent FMI master: OSP libcosim (C++, FMI Library import, its own
nanosecond clock and parallel step loop) runs the vehicle + navigator FMUs (gyro-free,
strapdown, and the integrated INS/GNSS navigator fed by the vehicle's GNSS receiver,
Integer connection included), and the SSP file write_ssp writes.

Truth: our Python master (tests/fmi/test_cosim.py: equal to the cffi pipeline bit for bit)
on the same communication points. libcosim is a Jacobi master like ours (every FMU steps
from the same point with the outputs read after the previous step; the connections are
propagated after initialization), so with the same FMUs, inputs, order and times the
results must be equal bit for bit. Its clock is an int64 count of nanoseconds, handed to
the FMUs as k h_ns / 1e9 with steps t_(k+1) - t_k; on our own clock (t0 + k h, step h)
the times differ by an ulp now and then, and so do the results (shown below)."""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.fmi.master import CoSimulation
from gfins_fmi.fmi.paths import FmuRunError
from gfins_fmi.fmi.system import vehicle_integrated_navigation, vehicle_navigation
from gfins_fmi.fmi.ssp import write_ssp
from gfins_fmi.fmi import osp
from gfins_fmi.sim.vehicle import GnssReceiver, VehicleProfile

REASON = osp.available()
pytestmark = pytest.mark.skipif(REASON is not None, reason=REASON or "")

#: 20 s of seed 001's run, shortened: 1 s at rest, a 3 s start to 15 m/s, 180 deg turns
#: of 4 s at 5 s and 12 s — every navigator input moves
PROFILE = VehicleProfile.seed001(align_s=1.0, accel_s=3.0, turn_times_s=(5.0, 12.0), turn_s=4.0)
STEP_S, STOP_S = 0.01, 20.0
N_STEPS = 2000


#: 5 Hz, epochs 13.7 ms after the IMU samples (the filter splits the interval there),
#: antenna lever arm; no latency: the filter FMU refuses an epoch older than its sample
#: interval as stale, and under a Jacobi master a delayed epoch always is
RECEIVER = GnssReceiver(rate_hz=5.0, offset_s=0.0137, lever_arm_m=(0.3, 1.1, 1.6))


@pytest.fixture(scope="module", params=["gfnav_qin9", "sins", "ins_gnss"])
def case(request):
    """(system, our master's result on libcosim's clock, libcosim's result)."""
    if request.param == "ins_gnss":
        system = vehicle_integrated_navigation(PROFILE, gnss=RECEIVER, step_s=STEP_S,
                                                     stop_s=STOP_S)
    else:
        system = vehicle_navigation(request.param, PROFILE, step_s=STEP_S, stop_s=STOP_S)
    with CoSimulation(system, fmi_version=2) as m:
        m.initialize()
        ours = m.run(points=osp.communication_points(STEP_S, N_STEPS))
    return system, ours, osp.run_libcosim(system)


def test_libcosim_equals_the_python_master_bit_for_bit(case):
    system, ours, theirs = case
    assert sorted(theirs) == sorted(ours)
    assert theirs["vehicle.A" if "vehicle.A" in ours else "vehicle.dtheta"].shape[0] == N_STEPS + 1
    for key in ours:   # (NaN: the GNSS outputs before the first epoch)
        assert np.array_equal(theirs[key], ours[key], equal_nan=True), key
    if "navigator.n_updates" in ours:   # every epoch used: position and velocity
        assert theirs["navigator.n_updates"][-1, 0] == 2 * theirs["vehicle.gnss_valid"].sum() == 200
        assert theirs["navigator.n_rejected"][-1, 0] == 0
    # the navigation really ran: the navigator ends where the vehicle ended, within its
    # error (measured 1.1e-9 rad, 7 mm, gyro-free and SINS; 5.7e-9 rad, 4 cm, INS/GNSS
    # with its 1-2 m GNSS noise; bound 1e-7 rad, 0.6 m)
    assert abs(theirs["navigator.lat"][-1, 0] - theirs["vehicle.lat"][-2, 0]) < 1e-7


def test_on_our_own_clock_the_results_differ_by_the_time_rounding(case):
    """Our master's default clock t0 + k h gives FMU times an ulp away from libcosim's
    k h_ns / 1e9 at some points: the vehicle's truth moves by ulps, which the navigators
    integrate. Measured over 20 s: navigator latitude 3.0e-14 rad (gyro-free, which
    integrates the angular acceleration twice), 0 (SINS and INS/GNSS); bound 1e-12
    rad (6 um)."""
    system, _, theirs = case
    with CoSimulation(system, fmi_version=2) as m:
        m.initialize()
        own = m.run()
    assert not np.array_equal(own["time"], theirs["time"])
    assert np.max(np.abs(own["time"] - theirs["time"])) <= 2 * np.spacing(STOP_S)
    d = np.abs(own["navigator.lat"] - theirs["navigator.lat"])
    print(f"{system.components['navigator'][0]}: |dlat| {d.max():.3g} rad")
    assert d.max() < 1e-12


def test_libcosim_runs_the_ssp_file_of_write_ssp(case, tmp_path):
    """libcosim loads the .ssp archive (FMUs, connections, the components' parameter
    sets) itself: equal to the Python master bit for bit."""
    system, ours, _ = case
    path = write_ssp(system, tmp_path / "vehicle_navigation.ssp")
    theirs = osp.run_libcosim_ssp(path, system.outputs, STOP_S, STEP_S)
    for key in ours:
        assert np.array_equal(theirs[key], ours[key], equal_nan=True), key


def test_refusals_before_libcosim_sees_them(tmp_path):
    """An FMU that refuses its start values would end the process inside libcosim: the
    start values are checked first and the FMU's reason raised; a step that is no whole
    number of nanoseconds is refused."""
    system = vehicle_navigation("sins", PROFILE, step_s=STEP_S, stop_s=1.0)
    system.components["vehicle"][1]["lat0"] = 1.56                  # beyond 89 deg
    with pytest.raises(FmuRunError, match="vehicle refuses its start values.*lat0"):
        osp.run_libcosim(system)
    with pytest.raises(FmuRunError, match="vehicle refuses its start values.*lat0"):
        osp.run_libcosim_ssp(write_ssp(system, tmp_path / "bad.ssp"), system.outputs, 1.0, STEP_S)
    with pytest.raises(ValueError, match="not a whole number of nanoseconds"):
        osp.communication_points(1e-10 / 3, 3)


def test_every_row_of_a_long_run_is_kept():
    """More than the 10 000 samples libcosim's time-series observer keeps by default:
    10 001 rows, in order (the vehicle's time output at each row is the row's time; the
    vehicle adds the step to the previous point, so within an ulp: bound 1e-14 s)."""
    system = vehicle_navigation("sins", PROFILE, step_s=0.001, stop_s=10.0)
    system.outputs = {"vehicle": ["time_s"]}
    theirs = osp.run_libcosim(system)
    assert theirs["vehicle.time_s"].shape == (10_001, 1)
    assert np.array_equal(theirs["time"], osp.communication_points(0.001, 10_000))
    assert np.max(np.abs(theirs["vehicle.time_s"][:, 0] - theirs["time"])) < 1e-14
