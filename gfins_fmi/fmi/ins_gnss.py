"""The integrated navigator's FMU (``gfins_ins_gnss``) from Python: the start values that
make it the batch filter (:func:`ins_gnss_fmu_parameters`), its innovation log rebuilt from
the monitoring outputs (:func:`monitor_innovations`), and the driver that feeds it a
record through fmpy with the grouping of the batch API (:class:`InsGnssDriver`,
:func:`run_ins_gnss_fmu`)."""
from __future__ import annotations

import pathlib
import warnings
from typing import Callable, Mapping

import numpy as np

from gfins_fmi._lib import as_rows
from gfins_fmi.estimation.config import FilterConfig, InitialState
from gfins_fmi.estimation.measurements import INNOVATION_DTYPE, gather_measurements
from gfins_fmi.estimation.settings import fmu_settings
from gfins_fmi.estimation.solution import IntegratedSolution
from gfins_fmi.fmi.paths import FmuRunError, fmu_path
from gfins_fmi.fmi.runner import FmuLog, FmuSlave

__all__ = ["INITIAL_STD_PARAMETERS", "OLD_PARAMETER_NAMES", "renamed_parameters", "ins_gnss_fmu_parameters", "monitor_innovations", "InsGnssDriver",
           "run_ins_gnss_fmu"]

#: InitialState's std blocks (gf_ins_initial_std's members) -> the FMU's std0_* parameters
INITIAL_STD_PARAMETERS = {
    "velocity_std_m_s": "std0_vel", "position_std_m": "std0_pos", "attitude_std_rad": "std0_att",
    "gyro_bias_std_rad_s": "std0_gyro_bias", "accel_bias_std_m_s2": "std0_accel_bias",
    "gyro_scale_std": "std0_gyro_scale", "accel_scale_std": "std0_accel_scale",
    "baro_bias_std_m": "std0_baro_bias", "odometer_scale_std": "std0_odo_scale",
    "odometer_mount_std_rad": "std0_odo_mount"}


#: the FMU's parameter names before they became the settings table's (one release of
#: grace: :func:`renamed_parameters` maps them and warns)
OLD_PARAMETER_NAMES = {
    "input_mode": "input", "propagation_interval": "propagation_interval_s",
    "max_imu_gap": "max_imu_gap_s", "max_rate": "max_rate_rad_s",
    "max_specific_force": "max_specific_force_m_s2", "scale_states": "scale_factors",
    "baro_state": "baro_bias", "odo_state": "odometer_scale", "odo_mount_state": "odometer_mount",
    "gyro_arw": "gyro_arw_rad_sqrt_s", "accel_vrw": "accel_vrw_m_s_sqrt_s",
    "gyro_bias_std": "gyro_bias_std_rad_s", "gyro_bias_tau": "gyro_bias_tau_s",
    "accel_bias_std": "accel_bias_std_m_s2", "accel_bias_tau": "accel_bias_tau_s",
    "gyro_scale_tau": "gyro_scale_tau_s", "accel_scale_tau": "accel_scale_tau_s",
    "baro_bias_std": "baro_bias_std_m", "baro_bias_tau": "baro_bias_tau_s",
    "odo_scale_std": "odometer_scale_std", "odo_scale_tau": "odometer_scale_tau_s",
    "odo_mount_std": "odometer_mount_std_rad", "odo_mount_tau": "odometer_mount_tau_s",
    "gnss_lever_arm": "gnss_lever_arm_m", "odo_lever_arm": "odometer_lever_arm_m",
    "odo_mount": "odometer_mount_rad", "gate_prob": "gate_probability",
    "max_latency": "max_latency_s", "nhc_std": "nhc_std_m_s", "nhc_interval": "nhc_interval_s",
    "zupt_std": "zupt_std_m_s", "zaru_std": "zaru_std_rad_s", "zupt_interval": "zupt_interval_s",
    "still_window": "standstill_window_s", "still_accel_std": "standstill_accel_std_m_s2",
    "still_gyro": "standstill_gyro_rad_s"}


def renamed_parameters(parameters) -> dict:
    """``parameters`` with the FMU's old parameter names replaced by the settings table's,
    with a DeprecationWarning naming each (the old names go in the next release)."""
    out = {}
    for name, value in (parameters or {}).items():
        new = OLD_PARAMETER_NAMES.get(name)
        if new is not None:
            warnings.warn(f"gfins_ins_gnss parameter {name!r} is now {new!r} (the name of the "
                          "setting in C and FilterConfig); the old name goes in the next release",
                          DeprecationWarning, stacklevel=3)
            name = new
        out[name] = value
    return out


def ins_gnss_fmu_parameters(config, initial) -> dict:
    """Start values (FMI 3.0 names, SI) that make the integrated-navigator FMU the filter
    ``IntegratedNavigator(config, initial)``.

    The configuration is copied field by field from the C struct the batch API hands the
    core (``FilterConfig`` in datasheet units -> SI process noise included); the initial
    state and one standard deviation per error block (position in metres east, north,
    up; the defaults of :class:`gfins_fmi.estimation.InitialState`). Both objects are
    validated with the batch API's own checks and messages.

    Parameters
    ----------
    config : gfins_fmi.estimation.FilterConfig
    initial : gfins_fmi.estimation.InitialState
    """
    if not isinstance(config, FilterConfig):
        raise TypeError("config must be a gfins_fmi.estimation.FilterConfig")
    if not isinstance(initial, InitialState):
        raise TypeError("initial must be a gfins_fmi.estimation.InitialState")
    initial.covariance(config)            # the batch API's checks of the initial stds
    c = config._c()
    params = {}
    for st in fmu_settings():               # every FMU parameter of the settings table
        owner, _, member = st.member.rpartition(".")
        value = getattr(getattr(c, owner) if owner else c, member)
        params[st.short] = [float(x) for x in value] if st.kind == "vector" else value
    nav = initial.nav
    sensors = np.zeros(16) if initial.sensors is None else np.asarray(initial.sensors, float)
    params.update({INITIAL_STD_PARAMETERS[k]: v for k, v in initial.std_blocks(config).items()
                   if k in INITIAL_STD_PARAMETERS})   # not the transfer-alignment blocks
    params.update(
        q0=np.asarray(nav.q_bn, float).tolist(), v0=np.asarray(nav.v_n_m_s, float).tolist(),
        lat0=float(nav.lat_rad), lon0=float(nav.lon_rad), h0=float(nav.h_m),
        sensors0=sensors.tolist(),
        # the batch API starts from the given attitude (no alignment phase); the alignment
        # parameters at their spec defaults
        align_time=0.0, align_heading=0, align_min_speed=1.0, align_travel_std=float(np.radians(10.0)))
    return params


_INS_FLOAT_OUT = ("q", "v", "lat", "lon", "h", "time_s", "std", "sensors", "nis", "update_time")
_INS_INT_OUT = ("standstill", "update_status", "update_count", "aligning")
_INS_GNSS_IN = ("gnss_time_s", "gnss_lat_rad", "gnss_lon_rad", "gnss_h_m", "gnss_vel_enu_m_s",
                "gnss_pos_std_m", "gnss_vel_std_m_s")
_INS_KINDS = 7     # per-kind monitoring outputs: GF_INS_MEAS_GNSS_POS .. GF_INS_MEAS_ZARU


def monitor_innovations(counts, counts_before, update_time, update_status, nis) -> np.ndarray:
    """The innovation log of consecutive steps of the integrated-navigator FMU rebuilt from
    its per-kind monitoring outputs (rows: steps; columns: kinds GF_INS_MEAS_GNSS_POS ..
    ZARU): a kind's ``update_count`` grows by one per update, whose time, outcome and NIS
    ``update_time``, ``update_status`` and ``nis`` hold; the updates of a step ordered by
    time, then kind, as the core makes them. ``counts_before``: the counts before the
    first row. Fields t_s, type, status, m, nis; r and s_std NaN (not FMU outputs)."""
    counts = np.asarray(counts)
    if len(counts) == 0:
        return np.zeros(0, INNOVATION_DTYPE)
    # a count that changed is an update, unless the kind says "none yet" (status -1):
    # the monitoring restarts at the end of an alignment phase, and its counts drop to 0
    changed = counts != np.vstack([np.asarray(counts_before)[None, :], counts[:-1]])
    grew = changed & (np.asarray(update_status) != -1)
    r, k = np.nonzero(grew)
    t = np.asarray(update_time)[r, k]
    order = np.lexsort((k, t, r))
    r, k, t = r[order], k[order], t[order]
    inn = np.zeros(len(r), INNOVATION_DTYPE)
    ty = k + 1
    inn["t_s"], inn["type"] = t, ty
    inn["status"], inn["nis"] = np.asarray(update_status)[r, k], np.asarray(nis)[r, k]
    inn["m"] = np.select([ty <= 2, ty == 5, ty <= 4], [3, 2, 1], 3)
    inn["r"] = inn["s_std"] = np.nan
    return inn


class InsGnssDriver:
    """The integrated-navigator FMU fed a record by fmpy: one ``doStep`` per IMU sample at
    the sample's own time (increments: first a step at the start time without a sample),
    each measurement in the step of the first sample whose time reaches its time of
    validity within 1e-9 s — the grouping of ``gf_ins_run`` — so the FMU makes the core
    calls the batch API makes. Used by :func:`run_ins_gnss_fmu`; the tests roll it back
    through FMU states."""

    def __init__(self, imu, gnss, baro, odometer, *, config, initial, gnss_velocity=True,
                 fmi_version=2, path=None, parameters=None, logging_on=False, echo=None):
        params = ins_gnss_fmu_parameters(config, initial)
        params.update(renamed_parameters(parameters))
        t = np.ascontiguousarray(np.asarray(imu.t_s, dtype=float))
        n = t.shape[0] if t.ndim == 1 else 0
        if t.ndim != 1 or n == 0:
            raise ValueError(f"imu.t_s must be a non-empty (n,) array; got shape {t.shape}")
        g = as_rows("imu.gyro", imu.gyro, 3, "rad or rad/s")
        a = as_rows("imu.accel", imu.accel, 3, "m/s or m/s^2")
        if g.shape[0] != n or a.shape[0] != n:
            raise ValueError(f"imu.gyro and imu.accel must have {n} rows like imu.t_s")
        kind = getattr(imu, "kind", config.input)
        if kind != config.input:
            raise ValueError(f"the IMU record holds {kind!r} but the filter is configured for "
                             f"input={config.input!r}")
        gather_measurements(gnss, baro, odometer, gnss_velocity)   # the batch API's checks
        t0 = float(initial.nav.t_s)
        self.increments = config.input == "increments"
        if self.increments:
            if not t[0] > t0:
                raise ValueError(f"imu.t_s[0] = {float(t[0])!r} s must be after initial.nav.t_s = "
                                 f"{t0!r} s: an increment covers the interval since the "
                                 "previous sample")
            times = np.r_[t0, t]
        else:
            if t[0] != t0:
                raise ValueError(f"with rates the FMU takes the first sample at its start time: "
                                 f"initial.nav.t_s = {t0!r} s must equal imu.t_s[0] = {float(t[0])!r} s")
            times = t.copy()
        self.shift = 1 if self.increments else 0         # FMU step k = record row k - shift
        h = np.diff(times)
        self.times = times
        self.h = np.r_[h, h[-1] if len(h) else 1e-3]
        self.imu = np.c_[g, a]
        self.n_steps = len(times)
        t_reach = t + 1e-9              # gf_ins_run: sample k takes t_m <= t_k + 1e-9 s

        def schedule(tm, what):
            k = np.searchsorted(t_reach, np.asarray(tm, dtype=float), side="left")
            at = np.full(self.n_steps, -1)
            keep = np.flatnonzero(k < n)   # after the last sample: not delivered (as the batch)
            ks = k[keep]
            if np.any(np.diff(ks) == 0):
                j = int(ks[np.flatnonzero(np.diff(ks) == 0)[0]])
                raise ValueError(f"two {what} measurements fall into the interval of IMU sample "
                                 f"{j} (t = {float(t[j])!r} s): the FMU takes one per kind and step")
            at[ks + self.shift] = keep
            return at

        nan3 = np.full(3, np.nan)
        self.gnss_at = self.baro_at = self.odo_at = np.full(self.n_steps, -1)
        vel_valid = 0
        if gnss is not None:
            self.gnss_at = schedule(gnss.t_s, "GNSS")
            vel = getattr(gnss, "vel_enu_m_s", None) if gnss_velocity else None
            vel_valid = int(vel is not None)
            m = len(gnss.t_s)
            v = np.asarray(vel, float) if vel is not None else np.tile(nan3, (m, 1))
            vs = np.asarray(gnss.vel_std_m_s, float) if vel is not None else np.tile(nan3, (m, 1))
            self.gnss = np.c_[gnss.t_s, gnss.lat_rad, gnss.lon_rad, gnss.h_m, v,
                              np.asarray(gnss.pos_std_m, float), vs]
        if baro is not None:
            self.baro_at = schedule(baro.t_s, "barometer")
            self.baro = np.c_[baro.t_s, baro.h_m, baro.std_m]
        if odometer is not None:
            self.odo_at = schedule(odometer.t_s, "odometer")
            self.odo = np.c_[odometer.t_s, odometer.speed_m_s, odometer.std_m_s]
        params["gnss_vel_valid"] = vel_valid
        self.params = params
        self.version = fmi_version
        self.config = config
        self.log = FmuLog(echo)
        path = pathlib.Path(path) if path else fmu_path("ins_gnss", fmi_version)
        from fmpy.fmi1 import FMICallException   # lazy: fmpy (~30 ms) only where an FMU runs
        try:
            self.slave = FmuSlave(path, fmi_version, self.log, logging_on)
        except FMICallException as exc:
            raise FmuRunError(f"FMI {fmi_version}.0 ins_gnss FMU could not be instantiated: "
                              f"{exc}", self.log.messages) from exc
        s = self.slave
        self.g_imu = s.group(["dtheta", "dv"] if self.increments else ["gyro_rate", "specific_force"])
        self.g_flags = s.group(["gnss_valid", "baro_valid", "odo_valid"])
        self.g_gnss = s.group(_INS_GNSS_IN)
        self.g_baro = s.group(["baro_time_s", "baro_h_m", "baro_std_m"])
        self.g_odo = s.group(["odo_time_s", "odo_speed_m_s", "odo_std_m_s"])
        self.g_out_f = s.group(_INS_FLOAT_OUT)
        self.g_out_i = s.group(_INS_INT_OUT)
        self.cols_f = self._columns(_INS_FLOAT_OUT)
        self.cols_i = self._columns(_INS_INT_OUT)
        self.out_f = np.full((self.n_steps, self.g_out_f[1]), np.nan)
        self.out_i = np.zeros((self.n_steps, self.g_out_i[1]), np.int64)
        self._flags = None
        self.failed_step = None

    def _columns(self, names) -> dict:
        cols, c = {}, 0
        for name in names:
            k = self.slave.refs(name)[1]
            cols[name] = slice(c, c + k)
            c += k
        return cols

    def initialize(self) -> None:
        self.slave.initialize(float(self.times[0]), float(self.times[-1] + self.h[-1]), self.params)

    def forget_inputs(self) -> None:
        """After an FMU state was restored (it holds the inputs): set every input again."""
        self._flags = None

    def run(self, k0: int, k1: int, bar=None) -> None:
        """FMU steps k0 .. k1 - 1; outputs into ``out_f``/``out_i`` rows k0 .. k1 - 1."""
        s = self.slave
        for k in range(k0, k1):
            r = k - self.shift
            if r >= 0:
                s.set_group(self.g_imu, self.imu[r])
            jg, jb, jo = int(self.gnss_at[k]), int(self.baro_at[k]), int(self.odo_at[k])
            flags = (int(jg >= 0), int(jb >= 0), int(jo >= 0))
            if flags != self._flags:
                s.set_group(self.g_flags, flags)
                self._flags = flags
            if jg >= 0:
                s.set_group(self.g_gnss, self.gnss[jg])
            if jb >= 0:
                s.set_group(self.g_baro, self.baro[jb])
            if jo >= 0:
                s.set_group(self.g_odo, self.odo[jo])
            try:
                s.slave.doStep(currentCommunicationPoint=float(self.times[k]),
                               communicationStepSize=float(self.h[k]))
            except Exception:
                self.failed_step = k
                raise
            self.out_f[k] = s.get_group(self.g_out_f)
            self.out_i[k] = s.get_group(self.g_out_i)
            if bar is not None and k % 1000 == 999:
                bar.update(1000)

    def solution(self, k_end: int | None = None):
        """The IntegratedSolution of the record rows whose FMU steps are done (up to FMU
        step ``k_end``, default all)."""
        k_end = self.n_steps if k_end is None else k_end
        F, I = self.out_f[self.shift:k_end], self.out_i[self.shift:k_end]
        cf, ci = self.cols_f, self.cols_i
        counts = self.out_i[:, ci["update_count"]]
        before = counts[self.shift - 1] if self.shift else np.zeros(_INS_KINDS, np.int64)
        inn = monitor_innovations(counts[self.shift:k_end], before, F[:, cf["update_time"]],
                                   I[:, ci["update_status"]], F[:, cf["nis"]])
        return IntegratedSolution(
            F[:, cf["time_s"]][:, 0].copy(), F[:, cf["q"]].copy(), F[:, cf["v"]].copy(),
            F[:, cf["lat"]][:, 0].copy(), F[:, cf["lon"]][:, 0].copy(), F[:, cf["h"]][:, 0].copy(),
            F[:, cf["std"]].copy(), F[:, cf["sensors"]].copy(),
            I[:, ci["standstill"]][:, 0].astype(bool), inn, self.config)

    def close(self) -> None:
        self.slave.close()


def run_ins_gnss_fmu(imu, gnss=None, baro=None, odometer=None, *, config, initial,
                     gnss_velocity: bool = True, fmi_version: int = 2,
                     path: str | pathlib.Path | None = None, parameters: Mapping | None = None,
                     logging_on: bool = False, echo: Callable[[str], None] | None = None,
                     progress: bool = False):
    """Run a record through the integrated-navigator FMU with fmpy as the master; the
    result lines up with ``IntegratedNavigator(config, initial).run(imu, gnss, baro,
    odometer)`` (row k: the state after IMU sample k).

    One ``doStep`` per IMU sample at the sample's time (with increments, a first step at
    ``initial.nav.t_s`` only starts the run; with rates ``imu.t_s[0]`` must be
    ``initial.nav.t_s``); each measurement is delivered in the step of the first sample
    whose time reaches its time of validity (within 1e-9 s), where the FMU splits the
    IMU interval at it. Measurements valid after the last sample are not delivered.

    Parameters
    ----------
    imu, gnss, baro, odometer, gnss_velocity
        As :meth:`gfins_fmi.estimation.IntegratedNavigator.run` (at most one measurement
        of a kind per IMU interval).
    config : FilterConfig
    initial : InitialState
        Turned into start values by :func:`ins_gnss_fmu_parameters`.
    parameters : mapping, optional
        More start values (FMI 3.0 names), overriding those.

    Returns
    -------
    gfins_fmi.estimation.IntegratedSolution
        ``innovations`` is rebuilt from the FMU's per-kind monitoring outputs: ``t_s``,
        ``type``, ``status``, ``m``, ``nis`` of every update; ``r`` and ``s_std`` are NaN
        (the FMU reports the NIS, not the residuals).

    Raises
    ------
    FmuRunError
        An FMU call failed; carries the FMU's log and, in ``partial``, the solution of the
        samples before it.
    """
    from fmpy.fmi1 import FMICallException   # lazy: fmpy (~30 ms) only where an FMU runs
    drv = InsGnssDriver(imu, gnss, baro, odometer, config=config, initial=initial,
                         gnss_velocity=gnss_velocity, fmi_version=fmi_version, path=path,
                         parameters=parameters, logging_on=logging_on, echo=echo)
    bar = None
    if progress:
        from tqdm import tqdm   # lazy: tqdm (~25 ms) only with a progress bar
        bar = tqdm(total=drv.n_steps, unit="step", unit_scale=True, desc="ins_gnss FMU")
    try:
        try:
            drv.initialize()
        except FMICallException as exc:
            raise FmuRunError(f"FMI {fmi_version}.0 ins_gnss FMU refused its parameters: {exc} "
                              f"FMU log: {'; '.join(drv.log.messages) or 'no message logged'}",
                              drv.log.messages) from exc
        try:
            drv.run(0, drv.n_steps, bar)
        except FMICallException as exc:
            k = drv.failed_step
            row = k - drv.shift
            raise FmuRunError(f"FMI {fmi_version}.0 ins_gnss FMU failed at record row {row}: {exc} "
                              f"FMU log: {'; '.join(drv.log.messages) or 'no message logged'}",
                              drv.log.messages, drv.solution(k)) from exc
        if bar:
            bar.update(drv.n_steps - bar.n)
        return drv.solution()
    finally:
        if bar:
            bar.close()
        drv.close()
