"""The per-model runners of the shipped FMUs with fmpy as the master: the
9-accelerometer solver, the strapdown navigator and the gyro-free navigators; each
result lines up with the batch API's on the same record."""
from __future__ import annotations

import pathlib
from typing import Callable

import numpy as np

from gfins_fmi._lib import as_array, as_rows, as_scalar, as_vector3
from gfins_fmi.fmi.paths import MODELS, FmuRunError
from gfins_fmi.fmi.runner import run_fmu
from gfins_fmi.gyrofree.array import Accel9Solution
from gfins_fmi.gyrofree.geometry import STRATEGIES
from gfins_fmi.nav.rotating import RotatingNavSolution
from gfins_fmi.nav.strapdown import EARTH_MODELS, INPUT_KINDS, VERTICAL_MODES, NavSolution, SinsConfig

__all__ = ["run_accel9_fmu", "run_sins_fmu", "run_gfnav_fmu"]


def run_accel9_fmu(A_m_s2, dt_s: float, l_m: float, omega_init_rad_s=(0.0, 0.0, 0.0), *,
                   fmi_version: int = 2, start_time_s: float = 0.0,
                   path: str | pathlib.Path | None = None, logging_on: bool = False,
                   echo: Callable[[str], None] | None = None) -> Accel9Solution:
    """Run a record through the 9-accelerometer FMU with fmpy as the master.

    One ``doStep`` per sample (communication step ``dt_s``); the outputs read after the
    step of sample k are row k of the result, so it lines up with
    :func:`gfins_fmi.solve_accel9` on the same record. ``l_m`` is checked by the FMU
    itself (that check is part of what runs here).

    Raises
    ------
    FmuRunError
        An FMU call failed; carries the FMU's log and, in ``partial``, an
        :class:`Accel9Solution` of the rows completed.
    """
    A = as_rows("A_m_s2", A_m_s2, 9, "m/s^2")
    w0 = as_vector3("omega_init_rad_s", omega_init_rad_s, "rad/s")
    names = ["f", "omega", "omega_dot", "omega_sq", "flags"]

    def solution(d):
        return Accel9Solution(d["f"], d["omega"], d["omega_dot"], d["omega_sq"],
                              d["flags"][:, 0].astype(np.uint8))
    try:
        d = run_fmu("accel9", {"A": A}, names, dt_s, parameters={"l": float(l_m), "omega_init": w0},
                    fmi_version=fmi_version, start_time_s=start_time_s, path=path,
                    logging_on=logging_on, echo=echo)
    except FmuRunError as exc:
        exc.partial = solution(exc.partial)
        raise
    return solution(d)


def run_sins_fmu(gyro, accel, dt_s: float, initial, *, config=None, h_ext_m=None,
                 fmi_version: int = 2, start_time_s: float | None = None,
                 progress: bool = False, imu_errors=None, lowpass_sos=None, gimbal_rad=None,
                 **kwargs):
    """Run a record through the strapdown FMU; the result lines up with
    :meth:`gfins_fmi.Strapdown.run` on the same record (for increments, the FMU takes
    the increment over (t_(k-1), t_k] at t_k, so the record is shifted by one step
    internally and its first step only starts the run).

    ``imu_errors`` (:class:`gfins_fmi.ImuErrors`) switches on the FMU's compensation of
    its inputs; ``lowpass_sos`` (n_sections <= 8, 6) its low-pass after it (the same as
    ``ImuErrors.compensate`` followed by ``signal_conditioning.BiquadFilter`` on the six channels).

    ``gimbal_rad`` (n, 2; the middle and inner angles at each record row's time) makes it
    the navigator of a rotating INS (rotating = 1): the record is the IMU frame's and the
    result is a :class:`gfins_fmi.nav.rotating.RotatingNavSolution` with the vehicle attitude
    from the gimbal angles (as :func:`gfins_fmi.nav.rotating.navigate`).

    Returns a :class:`gfins_fmi.NavSolution` (with ``gimbal_rad``: a RotatingNavSolution).
    """
    cfg = config or SinsConfig()
    if cfg.earth != "wgs84":
        raise ValueError("the SINS FMU navigates on WGS-84 only (earth='wgs84')")
    if cfg.checked_subsamples() != 1:
        raise ValueError(f"subsamples = {cfg.subsamples}: the SINS FMU takes one sample per "
                         "communication step and makes one navigation update of it (the master's "
                         "step is the update interval); navigate subsampled records with "
                         "Strapdown.run")
    x0 = initial.checked()    # the same checks and messages as Strapdown
    cfg._c(x0.h_m)
    g = as_rows("gyro", gyro, 3, "rad or rad/s")
    a = as_rows("accel", accel, 3, "m/s or m/s^2")
    n = g.shape[0]
    if a.shape[0] != n:
        raise ValueError(f"gyro has {n} samples but accel has {a.shape[0]}")
    t0 = x0.t_s if start_time_s is None else as_scalar("start_time_s", start_time_s, "s")
    params = {"input_mode": int(INPUT_KINDS[cfg.input]), "coning": int(cfg.coning),
              "vertical_mode": int(VERTICAL_MODES[cfg.vertical]),
              "hold_height": cfg.held_height_m(x0.h_m), "baro_tau": cfg.baro_tau_s,
              "max_rate": cfg.max_rate_rad_s, "max_specific_force": cfg.max_specific_force_m_s2,
              "q0": x0.q_bn, "v0": x0.v_n_m_s, "lat0": x0.lat_rad, "lon0": x0.lon_rad,
              "h0": x0.h_m}
    if imu_errors is not None:
        params.update(imu_comp=1, **imu_errors.fmu_parameters())
    if lowpass_sos is not None:
        sos = np.asarray(lowpass_sos, float)
        if sos.ndim != 2 or sos.shape[1] != 6 or not 1 <= sos.shape[0] <= 8:
            raise ValueError(f"lowpass_sos must have shape (1..8, 6); got {sos.shape}")
        params.update(lowpass_sections=sos.shape[0],
                      lowpass_sos=np.r_[sos.ravel(), np.zeros(48 - sos.size)])
    he = np.full(n, np.nan) if h_ext_m is None else as_array("h_ext_m", h_ext_m, (n,), "m",
                                                             finite=False)
    gim = None if gimbal_rad is None else as_array("gimbal_rad", gimbal_rad, (n, 2), "rad")
    if gim is not None:
        params["rotating"] = 1
    if cfg.input == "increments":
        # sample j of the record covers (t_j, t_(j+1)]: set it at t_(j+1)
        z = np.zeros((1, 3))
        ins = {"dtheta": np.r_[z, g], "dv": np.r_[z, a], "gyro_rate": np.zeros((n + 1, 3)),
               "specific_force": np.zeros((n + 1, 3)), "h_ext": np.r_[np.nan, he]}
        if gim is not None:
            ins["gimbal"] = np.r_[gim[:1], gim]
    else:
        ins = {"gyro_rate": g, "specific_force": a, "dtheta": np.zeros((n, 3)),
               "dv": np.zeros((n, 3)), "h_ext": he}
        if gim is not None:
            ins["gimbal"] = gim
    shift = 1 if cfg.input == "increments" else 0   # FMU step k takes record row k - shift

    def solution(d):
        sl = slice(shift, None)
        sol = NavSolution(d["time_s"][sl, 0], d["q"][sl], d["v"][sl], d["lat"][sl, 0],
                          d["lon"][sl, 0], d["h"][sl, 0])
        if gim is None:
            return sol
        return RotatingNavSolution(sol, d["q_vehicle"][sl])
    outs = ["q", "v", "lat", "lon", "h", "time_s"] + (["q_vehicle"] if gim is not None else [])
    try:
        d = run_fmu("sins", ins, outs, dt_s, parameters=params,
                    fmi_version=fmi_version, start_time_s=t0, progress=progress, **kwargs)
    except FmuRunError as exc:
        k = len(exc.partial.get("q", [])) if exc.partial else 0
        exc.partial = solution(exc.partial) if exc.partial else None
        if k >= shift:
            exc.args = (f"record row {k - shift}: " + exc.args[0],)
        raise
    return solution(d)


def run_gfnav_fmu(layout_name: str, A_m_s2, dt_s: float, initial, *, l_m: float = 0.1,
                  strategy: str = "integrate", omega_init_rad_s=(0.0, 0.0, 0.0),
                  accel_noise_m_s2: float = 1e-4, sins=None, fmi_version: int = 2, **kwargs):
    """Run an array record through the gyro-free navigator FMU of a layout ("cube6",
    "qin9", "12"); the result lines up with :meth:`gfins_fmi.GyroFreeNavigator.run` on
    the same record (row k: the state at sample k).

    Returns (NavSolution, omega_rad_s (n, 3), f_m_s2 (n, 3), flags (n,)).
    """
    model = f"gfnav_{layout_name}"
    if model not in MODELS:
        raise ValueError(f"no navigator FMU for layout {layout_name!r}; choose cube6, qin9 or 12")
    n_in = {"cube6": 6, "qin9": 9, "12": 12}[layout_name]
    A = as_rows("A_m_s2", A_m_s2, n_in, "m/s^2")
    sc = sins or SinsConfig()
    if sc.subsamples != 1:
        raise ValueError(f"sins.subsamples = {sc.subsamples!r}: the gyro-free navigator FMU "
                         "makes one update per array sample; use subsamples=1")
    flat = sc.earth == "flat"
    x0 = initial.checked(flat)    # the same checks and messages as GyroFreeNavigator
    sc._c(x0.h_m)
    if strategy not in STRATEGIES:
        raise ValueError(f"strategy must be one of {sorted(STRATEGIES)}; got {strategy!r}")
    # l and accel_noise are checked by the FMU itself (that check is part of what runs)
    params = {"l": float(l_m), "strategy": int(STRATEGIES[strategy]),
              "accel_noise": float(accel_noise_m_s2),
              "omega_init": as_vector3("omega_init_rad_s", omega_init_rad_s, "rad/s"),
              "earth": int(EARTH_MODELS[sc.earth]), "flat_gravity": sc.flat_gravity_m_s2,
              "vertical_mode": int(VERTICAL_MODES[sc.vertical]), "hold_height": sc.held_height_m(x0.h_m),
              "baro_tau": sc.baro_tau_s, "q0": x0.q_bn, "v0": x0.v_n_m_s, "lat0": x0.lat_rad,
              "lon0": x0.lon_rad, "h0": x0.h_m,
              "pos0": x0.pos_m if flat else np.zeros(3)}
    d = run_fmu(model, {"A": A}, ["q", "v", "lat", "lon", "h", "pos", "omega", "f", "flags",
                                  "time_s"], dt_s, parameters=params, fmi_version=fmi_version,
                start_time_s=x0.t_s, **kwargs)
    sol = NavSolution._from_pos(d["time_s"][:, 0], d["q"], d["v"],
                                d["pos"] if flat else np.c_[d["lat"], d["lon"], d["h"]], flat)
    return sol, d["omega"], d["f"], d["flags"][:, 0].astype(np.uint8)
