"""The measurements and logs the filter exchanges with the C core, as numpy structured
arrays laid out exactly as its structs (``gf_ins_meas``, ``gf_ins_pass``,
``gf_ins_innovation``), and the gathering of the aiding records into one time-sorted
measurement array (the checks every runner of the filter shares: batch, FMU driver)."""
from __future__ import annotations

import numpy as np

from gfins_fmi._lib import ffi, lib
from gfins_fmi.estimation.config import MEAS_TYPES, N_SENSORS

__all__ = ["MEAS_DTYPE", "PASS_DTYPE", "INNOVATION_DTYPE", "gather_measurements", "MAX_STD"]

#: the largest measurement standard deviation taken (m, m/s): its square, and the
#: innovation covariance built from it, stay far from overflowing a double
MAX_STD = 1e100


def _struct_dtype(cname: str, spec) -> np.dtype:
    """A numpy dtype laid out exactly as the C struct (offsets from cffi)."""
    names, formats, offsets = [], [], []
    for name, *fmt in spec:
        names.append(name)
        formats.append(tuple(fmt) if len(fmt) > 1 else fmt[0])
        offsets.append(ffi.offsetof(cname, name))
    return np.dtype({"names": names, "formats": formats, "offsets": offsets,
                     "itemsize": ffi.sizeof(cname)})


#: one measurement (gf_ins_meas)
MEAS_DTYPE = _struct_dtype("gf_ins_meas", [("type", "<i4"), ("t_s", "<f8"), ("z", "<f8", (3,)),
                                            ("std", "<f8", (3,)), ("aux", "<f8", (3,))])
#: the state after a forward or backward pass (gf_ins_pass)
PASS_DTYPE = _struct_dtype("gf_ins_pass", [("direction", "<i4"), ("t_s", "<f8"), ("q_bn", "<f8", (4,)),
                                            ("v_n_m_s", "<f8", (3,)), ("std9", "<f8", (9,)),
                                            ("sensors", "<f8", (N_SENSORS,)), ("n_updates", "<u8"),
                                            ("n_rejected", "<u8")])
#: one entry of the innovation log (gf_ins_innovation)
INNOVATION_DTYPE = _struct_dtype("gf_ins_innovation", [("t_s", "<f8"), ("type", "<i4"), ("status", "<i4"),
                                                   ("m", "<i4"), ("nis", "<f8"), ("r", "<f8", (3,)),
                                                   ("s_std", "<f8", (3,))])


def gather_measurements(gnss, baro, odometer, gnss_velocity: bool, speed=None,
                        master=None) -> np.ndarray:
    """All measurements as one array of gf_ins_meas, sorted by time (stable: position
    before velocity at the same instant; the master's after the sensors' at one instant);
    refused with a message when one holds NaN or Inf or a standard deviation <= 0.
    ``master``: rows of the transfer-alignment kinds already in ``MEAS_DTYPE`` (from
    :func:`gfins_fmi.estimation.transfer.master_measurements`)."""
    parts = []

    def block(t, type_, z, std):
        a = np.zeros(len(t), MEAS_DTYPE)
        a["type"], a["t_s"] = type_, t
        a["z"][:, :z.shape[1]] = z
        a["std"][:, :std.shape[1]] = std
        parts.append(a)

    if gnss is not None:
        t = np.asarray(gnss.t_s, float)
        block(t, lib.GF_INS_MEAS_GNSS_POS, np.c_[gnss.lat_rad, gnss.lon_rad, gnss.h_m],
              np.asarray(gnss.pos_std_m, float))
        if gnss_velocity and getattr(gnss, "vel_enu_m_s", None) is not None:
            if getattr(gnss, "vel_std_m_s", None) is None:
                raise ValueError("the GNSS record has velocities but no vel_std_m_s: give their "
                                 "standard deviations or pass gnss_velocity=False")
            block(t, lib.GF_INS_MEAS_GNSS_VEL, np.asarray(gnss.vel_enu_m_s, float),
                  np.asarray(gnss.vel_std_m_s, float))
    if baro is not None:
        block(np.asarray(baro.t_s, float), lib.GF_INS_MEAS_BARO, np.asarray(baro.h_m, float)[:, None],
              np.asarray(baro.std_m, float)[:, None])
    if odometer is not None:
        block(np.asarray(odometer.t_s, float), lib.GF_INS_MEAS_ODO,
              np.asarray(odometer.speed_m_s, float)[:, None], np.asarray(odometer.std_m_s, float)[:, None])
    if speed is not None:
        block(np.asarray(speed.t_s, float), lib.GF_INS_MEAS_SPEED,
              np.asarray(speed.speed_m_s, float)[:, None], np.asarray(speed.std_m_s, float)[:, None])
    if master is not None:
        if not isinstance(master, np.ndarray) or master.dtype != MEAS_DTYPE:
            raise TypeError("master must be an array of MEAS_DTYPE (see "
                            "gfins_fmi.estimation.transfer.master_measurements)")
        parts.append(master)
    if not parts:
        return np.zeros(0, MEAS_DTYPE)
    meas = np.concatenate(parts)
    bad = ~(np.isfinite(meas["t_s"]) & np.all(np.isfinite(meas["z"]), axis=1) &
            np.all(np.isfinite(meas["std"]), axis=1) & np.all(np.isfinite(meas["aux"]), axis=1))
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(f"measurement {MEAS_TYPES[int(meas['type'][k])]} at t = {float(meas['t_s'][k])!r} s "
                         "holds NaN or Inf (value or standard deviation): remove it or mark the "
                         "epoch invalid")
    for type_, m in ((lib.GF_INS_MEAS_GNSS_POS, 3), (lib.GF_INS_MEAS_GNSS_VEL, 3),
                     (lib.GF_INS_MEAS_BARO, 1), (lib.GF_INS_MEAS_ODO, 1), (lib.GF_INS_MEAS_SPEED, 1),
                     (lib.GF_INS_MEAS_MASTER_VEL, 3), (lib.GF_INS_MEAS_MASTER_ATT, 3),
                     (lib.GF_INS_MEAS_MASTER_POS, 3)):
        sel = meas["type"] == type_
        if np.any(sel) and not np.all(meas["std"][sel, :m] > 0):
            k = int(np.flatnonzero(sel & ~np.all(meas["std"][:, :m] > 0, axis=1))[0])
            raise ValueError(f"{MEAS_TYPES[int(type_)]} at t = {float(meas['t_s'][k])!r} s has a "
                             f"standard deviation <= 0 ({meas['std'][k, :m].tolist()}): every std "
                             "must be > 0")
        big = sel & ~np.all(meas["std"][:, :m] <= MAX_STD, axis=1)
        if np.any(big):
            # before: the variance overflowed in C and the run stopped with "IMU sample k
            # holds NaN or Inf" (issue 21)
            k = int(np.flatnonzero(big)[0])
            raise ValueError(f"{MEAS_TYPES[int(type_)]} at t = {float(meas['t_s'][k])!r} s has a "
                             f"standard deviation of {meas['std'][k, :m].tolist()} (in the record's "
                             f"units: m, m/s): above {MAX_STD:g} its variance overflows, and a "
                             "measurement that uncertain carries no information: leave the epoch "
                             "out or mark it invalid")
    order = np.argsort(meas["t_s"], kind="stable")
    out = np.zeros(len(meas), MEAS_DTYPE)      # concatenate drops the C padding: copy by field
    for name in MEAS_DTYPE.names:
        out[name] = meas[name][order]
    return out
