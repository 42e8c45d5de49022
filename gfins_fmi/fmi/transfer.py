"""The transfer-alignment FMU (``gfins_transfer_align``, issue 24) from Python: its start
values from the batch API's objects (:func:`transfer_fmu_parameters`) and a record run
through it with fmpy as the master (:func:`run_transfer_fmu`), row for row what
:func:`gfins_fmi.estimation.transfer.transfer_align` computes (tests: bit for bit, FMI
2.0 and 3.0). Co-simulations of a host, its master INS and the slave: docs/cosim.md.
"""
from __future__ import annotations

import pathlib

import numpy as np

from gfins_fmi._lib import as_rows
from gfins_fmi.estimation.config import FilterConfig, InitialState
from gfins_fmi.estimation.settings import fmu_settings
from gfins_fmi.estimation.transfer import MATCHING, MasterErrors, master_measurements
from gfins_fmi.fmi.paths import FmuRunError, fmu_path
from gfins_fmi.fmi.runner import FmuLog, FmuSlave

__all__ = ["transfer_fmu_parameters", "run_transfer_fmu", "TRANSFER_OUTPUTS"]

#: the FMU's float outputs a run collects, in this order
TRANSFER_OUTPUTS = ("time_s", "q", "v", "lat", "lon", "h", "std", "sensors", "mount", "mount_std", "lever",
                    "lever_std", "time_offset", "time_offset_std", "flexure_angles", "nis")
#: InitialState's std blocks -> the FMU's std0_* parameters
_STD_PARAMETERS = {
    "velocity_std_m_s": "std0_vel", "position_std_m": "std0_pos", "attitude_std_rad": "std0_att",
    "gyro_bias_std_rad_s": "std0_gyro_bias", "accel_bias_std_m_s2": "std0_accel_bias",
    "gyro_scale_std": "std0_gyro_scale", "accel_scale_std": "std0_accel_scale",
    "master_mount_std_rad": "std0_mount", "master_lever_std_m": "std0_lever",
    "master_time_offset_std_s": "std0_time_offset"}


def _three(value) -> list:
    return [float(x) for x in np.broadcast_to(np.asarray(value, float), (3,))]


def transfer_fmu_parameters(config: FilterConfig, initial: InitialState, *,
                            matching: str = "velocity+attitude", position: bool = False,
                            master_errors: MasterErrors = MasterErrors()) -> dict:
    """Start values (FMI 3.0 names, SI) that make the FMU the batch API's filter: the
    configuration field by field from the C struct (the settings table's FMU rows, the
    transfer ones included), the slave's start and its stds, the matching and the
    master's errors. The barometer and odometer stds are the configuration's (the FMU's
    rule, InitialState's default)."""
    if not isinstance(config, FilterConfig) or not isinstance(initial, InitialState):
        raise TypeError("config must be a FilterConfig and initial an InitialState")
    if matching not in MATCHING:
        raise ValueError(f"matching must be one of {MATCHING}; got {matching!r}")
    initial.covariance(config)            # the batch API's checks of the initial stds
    c = config._c()
    params = {}
    for st in fmu_settings(transfer=True):
        owner, _, member = st.member.rpartition(".")
        value = getattr(getattr(c, owner) if owner else c, member)
        params[st.short] = [float(x) for x in value] if st.kind == "vector" else value
    blocks = initial.std_blocks(config)
    params.update({p: blocks[k] for k, p in _STD_PARAMETERS.items()})
    nav = initial.nav
    sensors = np.zeros(16) if initial.sensors is None else np.asarray(initial.sensors, float)
    params.update(q0=np.asarray(nav.q_bn, float).tolist(), v0=np.asarray(nav.v_n_m_s, float).tolist(),
                  lat0=float(nav.lat_rad), lon0=float(nav.lon_rad), h0=float(nav.h_m),
                  sensors0=sensors.tolist(), start_from_master=int(bool(initial.attitude_from_master)),
                  match_attitude=int(matching == "velocity+attitude"),
                  match_position=int(bool(position)),
                  master_vel_std=_three(master_errors.velocity_std_m_s),
                  master_att_std=_three(master_errors.attitude_std_rad),
                  master_pos_std=_three(master_errors.position_std_m))
    return params


def run_transfer_fmu(slave_imu, master, master_rate_rad_s=None, *, config: FilterConfig,
                     initial: InitialState, matching: str = "velocity+attitude", position: bool = False,
                     master_errors: MasterErrors = MasterErrors(), fmi_version: int = 2,
                     path: str | pathlib.Path | None = None, parameters: dict | None = None) -> dict:
    """Run a slave record and its master through the transfer-alignment FMU (fmpy master):
    one doStep per slave sample at its time (with increments a first step at
    ``initial.nav.t_s`` starts the run), each master epoch delivered in the step of the
    first sample whose time reaches it (within 1e-9 s), as the batch API's gf_ins_run
    takes it. ``parameters``: more start values (FMI 3.0 names) over those of
    :func:`transfer_fmu_parameters`. Returns {output name: (n, k) array} of
    :data:`TRANSFER_OUTPUTS`, row k the state after slave sample k (the rows of
    ``transfer_align``'s solution).

    Raises
    ------
    FmuRunError
        The FMU refused its parameters or a step (its log attached).
    """
    from fmpy.fmi1 import FMICallException   # lazy: fmpy (~30 ms) only where an FMU runs
    params = transfer_fmu_parameters(config, initial, matching=matching, position=position,
                                     master_errors=master_errors)
    params.update(parameters or {})
    t = np.asarray(slave_imu.t_s, float)
    n = len(t)
    imu = np.c_[as_rows("imu.gyro", slave_imu.gyro, 3, "rad"), as_rows("imu.accel", slave_imu.accel, 3, "m/s")]
    if config.input != "increments":
        raise ValueError("run_transfer_fmu takes increments (FilterConfig.input = 'increments')")
    t0 = float(initial.nav.t_s)
    if not t[0] > t0:
        raise ValueError(f"slave_imu.t_s[0] = {t[0]!r} s must be after initial.nav.t_s = {t0!r} s")
    times = np.r_[t0, t]
    h = np.r_[np.diff(times), times[-1] - times[-2]]
    meas = master_measurements(master, master_rate_rad_s, matching=matching, position=position,
                               errors=master_errors, t_from_s=t0 + 1e-9, t_to_s=t[-1])
    epochs = meas[meas["type"] == meas["type"][0]] if len(meas) else meas
    k = np.searchsorted(t + 1e-9, epochs["t_s"], side="left")   # the sample that reaches each epoch
    if np.any(np.diff(k) == 0):
        raise ValueError("two master epochs fall into one slave sample's interval: the FMU takes one per step")
    at = np.full(n + 1, -1)
    at[k + 1] = np.arange(len(epochs))
    euler = np.asarray(master.euler_rad, float)
    rec = {float(x): i for i, x in enumerate(np.asarray(master.t_s, float))}
    log = FmuLog(None)
    try:
        slave = FmuSlave(pathlib.Path(path) if path else fmu_path("transfer_align", fmi_version),
                         fmi_version, log, False)
    except FMICallException as exc:
        raise FmuRunError(f"the transfer_align FMU could not be instantiated: {exc}", log.messages) from exc
    try:
        g_imu = slave.group(["dtheta", "dv"])
        g_valid = slave.group(["master_valid"])
        g_master = slave.group(["master_time_s", "master_euler", "master_vel", "master_lat", "master_lon",
                                "master_h", "master_rate"])
        g_out = slave.group(TRANSFER_OUTPUTS)
        try:
            slave.initialize(float(times[0]), float(times[-1] + h[-1]), params)
        except FMICallException as exc:
            raise FmuRunError(f"the transfer_align FMU refused its parameters: {exc} FMU log: "
                              f"{'; '.join(log.messages)}", log.messages) from exc
        out = np.full((n + 1, g_out[1]), np.nan)
        valid = None
        for s in range(n + 1):
            if s >= 1:
                slave.set_group(g_imu, imu[s - 1])
            j = int(at[s])
            if int(j >= 0) != valid:
                valid = int(j >= 0)
                slave.set_group(g_valid, [valid])
            if j >= 0:
                e = epochs[j]
                i = rec[float(e["t_s"])]
                slave.set_group(g_master, [e["t_s"], *euler[i], *master.v_enu_m_s[i], master.lat_rad[i],
                                           master.lon_rad[i], master.h_m[i], *e["aux"]])
            try:
                slave.slave.doStep(currentCommunicationPoint=float(times[s]), communicationStepSize=float(h[s]))
            except FMICallException as exc:
                raise FmuRunError(f"the transfer_align FMU failed at slave sample {s - 1}: {exc} FMU log: "
                                  f"{'; '.join(log.messages)}", log.messages) from exc
            out[s] = slave.get_group(g_out)
    finally:
        slave.close()
    result, c = {}, 0
    for name in TRANSFER_OUTPUTS:
        m = slave.refs(name)[1]
        result[name] = out[1:, c:c + m]
        c += m
    return result
