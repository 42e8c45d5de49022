"""The references every co-simulated result is compared with: the system's navigator run
through cffi on the same sensor data (:func:`direct_navigation`; for the integrated
navigator the batch API on :func:`integrated_recording`), the differences between the
two (:func:`differences_from_direct`), the navigation errors against the vehicle's truth
(:func:`navigation_errors`), and :func:`compare_runners` (``gfins cosim``): the Python
master, the SSP file and the container FMU, each checked against the reference.
"""
from __future__ import annotations

import pathlib
import time
from dataclasses import fields, replace
from typing import Callable, Iterable, Mapping

import numpy as np

from gfins_fmi._lib import as_scalar
from gfins_fmi.estimation.navigator import IntegratedNavigator
from gfins_fmi.estimation.solution import IntegratedSolution
from gfins_fmi.fmi.container import run_container, write_container
from gfins_fmi.fmi.ins_gnss import monitor_innovations
from gfins_fmi.fmi.master import CoSimulation
from gfins_fmi.fmi.paths import fmu_variables
from gfins_fmi.fmi.ssp import run_ssp, write_ssp
from gfins_fmi.fmi.system import (NAVIGATORS, System, integrated_example, vehicle_integrated_navigation,
                                  vehicle_navigation)
from gfins_fmi.gyrofree.geometry import STRATEGIES, layout
from gfins_fmi.gyrofree.navigator import GyroFreeNavigator
from gfins_fmi.io.records import ImuRecord
from gfins_fmi.nav.earth import attitude_error_rad, radii
from gfins_fmi.nav.strapdown import VERTICAL_MODES, NavState, SinsConfig, Strapdown
from gfins_fmi.sim.vehicle import BaroMeasurements, GnssMeasurements, OdometerMeasurements

__all__ = ["direct_navigation", "integrated_recording", "navigation_errors",
           "differences_from_direct", "compare_runners"]


def _start_values(model: str, given: Mapping) -> Callable:
    """A lookup of a component's start values: the system's, else the FMU's own (its
    modelDescription), so the cffi reference runs with exactly what the FMU runs."""
    variables = fmu_variables(model, 3)

    def value(name):
        if name in given:
            return given[name]
        v = variables[name]
        cast = float if v.type == "Float64" else int
        items = [cast(x) for x in str(v.start).split()]
        return items if v.dimensions else items[0]
    return value


def direct_navigation(system: System, sensors: Mapping[str, np.ndarray], start_time_s: float = 0.0,
                      imu_errors=None, initial=None):
    """Run the system's navigator through cffi (no FMU) on sensor records.

    Parameters
    ----------
    sensors : mapping
        ``{"A": (n, n_sensors)}`` array samples at t_k = start + (skip + k) h for a
        gyro-free navigator, or ``{"dtheta": (n, 3), "dv": (n, 3)}`` increments over
        (t_(k-1), t_k], k = skip + 1 ... for the SINS.

        For the integrated navigator (``ins_gnss``): what :func:`integrated_recording`
        returns; the batch API then runs on it (see :func:`_integrated_reference`).
    initial : gfins_fmi.estimation.InitialState, optional
        ``ins_gnss`` only: the batch API's initial state (default: the system's, with the
        covariance the FMU makes of its stds: both convert with gf_earth).
    imu_errors : gfins_fmi.ImuErrors, optional
        The error model the SINS FMU compensates (``imu_comp = 1``; its
        ``fmu_parameters()`` must be the navigator's): the increments are compensated
        as mean rates over the step with the FMU's arithmetic before navigating.

    Returns
    -------
    NavSolution
        Row k: the state at t_(skip + k) (gyro-free: the sample; SINS: after the k-th
        increment, row 0 the initial state). ``ins_gnss``: the IntegratedSolution of
        ``IntegratedNavigator.run``, row k the state after the k-th increment.
    """
    model, nav = system.components["navigator"]
    if model == "ins_gnss":
        return _integrated_reference(system, sensors, initial)
    value = _start_values(model, nav)
    h = system.step_s
    t0 = start_time_s + value("skip_steps") * h
    init = NavState(np.asarray(value("q0"), float), np.asarray(value("v0"), float),
                    value("lat0"), value("lon0"), value("h0"), t0)
    vertical = {v: k for k, v in VERTICAL_MODES.items()}[value("vertical_mode")]
    cfg = dict(vertical=vertical, hold_height_m=value("hold_height"), baro_tau_s=value("baro_tau"))
    if model.startswith("gfnav_"):
        strategy = {v: k for k, v in STRATEGIES.items()}[value("strategy")]
        navi = GyroFreeNavigator(layout(model[len("gfnav_"):], value("l")), init, strategy=strategy,
                                 omega_init_rad_s=value("omega_init"),
                                 accel_noise_m_s2=value("accel_noise"), sins=SinsConfig(**cfg))
        sol, _ = navi.run(sensors["A"], h)
        return sol
    if value("lowpass_sections"):
        raise ValueError("direct_navigation: the SINS FMU's low-pass is not reproduced here; "
                         "filter the record with gfins_fmi.nav.signal_conditioning.BiquadFilter first")
    dth, dv = sensors["dtheta"], sensors["dv"]
    if value("imu_comp"):
        if imu_errors is None or not all(np.array_equal(v, value(k))
                                         for k, v in imu_errors.fmu_parameters().items()):
            raise ValueError("the navigator compensates IMU errors (imu_comp = 1): pass the "
                             "ImuErrors whose fmu_parameters() it was given as imu_errors")
        k = 1.0 / h                                    # the FMU's arithmetic, to the bit
        w, f = imu_errors.compensate(dth * k, dv * k)
        dth, dv = w / k, f / k
    sd = Strapdown(init, SinsConfig(input="increments", coning=bool(value("coning")),
                                    max_rate_rad_s=value("max_rate"),
                                    max_specific_force_m_s2=value("max_specific_force"), **cfg))
    return sd.run(dth, dv, h)


def _series(result, kind: str, comp: str, var: str, size: int | None = None) -> np.ndarray:
    """A variable recorded by a run, (rows,) for a scalar (``size`` None) or (rows, size):
    ``kind`` "master" (:meth:`CoSimulation.run`: arrays under "comp.var"), "ssp"
    (:func:`run_ssp`: FMI 2.0 scalars "comp.var[i]") or "container" (:func:`run_container`:
    "comp_var_i")."""
    if kind not in ("master", "ssp", "container"):
        raise ValueError(f"kind must be 'master', 'ssp' or 'container'; got {kind!r}")
    if kind == "master":
        a = np.asarray(result[f"{comp}.{var}"])
        return a[:, 0] if size is None else a[:, :size]

    def key(i=None):
        k = f"{comp}.{var}" if i is None else f"{comp}.{var}[{i}]"
        return k.replace(".", "_").replace("[", "_").replace("]", "") if kind == "container" else k
    if size is None:
        return np.asarray(result[key()])
    return np.stack([np.asarray(result[key(i)]) for i in range(1, size + 1)], 1)


def integrated_recording(system: System, result, kind: str = "master") -> dict:
    """What the integrated navigator of a run (:func:`vehicle_integrated_navigation`)
    consumed and produced, read from the recorded rows.

    Every runner records a navigator one row after the vehicle outputs it consumed (the
    navigator's row j took the vehicle's row j - 1): the Python master (Jacobi, or
    Gauss-Seidel with the navigator first) records the initial row and then a row after
    each step; the SSP simulator and the container hand a step what was read after the
    previous one. The navigator's IMU samples are its rows where ``n_imu`` counts 1, 2,
    ... N; the row before the first is its start (the first doStep of an increments
    navigator only starts the run; skipped steps come before it). Epochs delivered with
    the start step are never handed to the filter (the FMU counts them as rejected).

    Parameters
    ----------
    kind : {"master", "ssp", "container"}
        The runner that made ``result`` (see :func:`differences_from_direct`).

    Returns
    -------
    dict
        ``t_s`` (N + 1,): the start time and the sample times (the navigator's own
        ``time_s``); ``dtheta``, ``dv`` (N, 3): the increments it took; ``gnss``,
        ``baro``, ``odometer``: the epochs it was handed (``GnssMeasurements`` ...;
        None for a sensor not connected) and ``gnss_sample`` ... (m,): the sample, 1 .. N,
        each came with; ``solution``: the navigator's rows as an ``IntegratedSolution``
        (innovations from its monitoring outputs, residuals NaN).
    """
    model, _ = system.components["navigator"]
    if model != "ins_gnss":
        raise ValueError(f"integrated_recording reads an ins_gnss navigator; this system's is {model!r}")

    def nav(var, size=None):
        return _series(result, kind, "navigator", var, size)

    def veh(var, size=None):
        return _series(result, kind, "vehicle", var, size)
    n_imu = nav("n_imu").astype(np.int64)
    rows = np.flatnonzero(n_imu > 0)
    N = len(rows)
    if N == 0 or rows[0] < 1 or not np.array_equal(n_imu[rows], np.arange(1, N + 1)) \
            or not np.array_equal(rows, np.arange(rows[0], rows[0] + N)):
        raise ValueError("the recording does not show one IMU sample per navigator step after "
                         "its start (n_imu 1, 2, ...): was it made by a CoSimulation (Jacobi or "
                         "navigator first), run_ssp or run_container of this system?")
    start = rows[0] - 1
    used = rows - 1                                  # the vehicle rows the samples took
    T = nav("time_s")
    out = {"t_s": np.r_[T[start], T[rows]], "dtheta": veh("dtheta", 3)[used],
           "dv": veh("dv", 3)[used]}
    links = {c.dest_var for c in system.connections}
    kinds = {"gnss": ("gnss", GnssMeasurements), "baro": ("baro", BaroMeasurements),
             "odometer": ("odo", OdometerMeasurements)}
    for key, (prefix, cls) in kinds.items():
        out[key] = out[f"{key}_sample"] = None
        if f"{prefix}_valid" not in links:
            continue
        k = np.flatnonzero(veh(f"{prefix}_valid")[used] > 0)
        out[f"{key}_sample"] = k + 1
        r = used[k]
        if key == "gnss":
            v = {f: veh(f"gnss_{f}", 3)[r] for f in ("vel_enu_m_s", "pos_std_m", "vel_std_m_s")}
            out[key] = cls(veh("gnss_time_s")[r], veh("gnss_lat_rad")[r], veh("gnss_lon_rad")[r],
                           veh("gnss_h_m")[r], v["pos_std_m"], v["vel_enu_m_s"], v["vel_std_m_s"],
                           np.zeros(len(r), np.int8))
        elif key == "baro":
            out[key] = cls(veh("baro_time_s")[r], veh("baro_h_m")[r], veh("baro_std_m")[r])
        else:
            out[key] = cls(veh("odo_time_s")[r], veh("odo_speed_m_s")[r], veh("odo_std_m_s")[r])
    counts = nav("update_count", 7).astype(np.int64)
    inn = monitor_innovations(counts[rows], counts[start], nav("update_time", 7)[rows],
                               nav("update_status", 7)[rows].astype(np.int64), nav("nis", 7)[rows])
    out["solution"] = IntegratedSolution(
        T[rows], nav("q", 4)[rows], nav("v", 3)[rows], nav("lat")[rows], nav("lon")[rows],
        nav("h")[rows], nav("std", 9)[rows], nav("sensors", 16)[rows],
        nav("standstill")[rows].astype(bool), inn, system.sources.get("config"))
    return out


def _integrated_reference(system: System, rec: Mapping, initial=None):
    """The batch API (``IntegratedNavigator.run``) on what the co-simulated integrated
    navigator consumed (:func:`integrated_recording`), each epoch handed in with the IMU
    sample it arrived with.

    ``IntegratedNavigator.run`` takes an epoch with the first sample whose time reaches
    its time of validity; so does the FMU when the epoch arrives in time (zero latency:
    the vehicle delivers it at the end of the step it falls in, the navigator gets it with
    that step's increment). An epoch that arrives later (latency) reaches the FMU with a
    later sample, valid before that sample's interval: the batch API is then fed in pieces
    (it continues where it stopped), a piece starting at each such sample, so that the
    epoch comes with it, and the core makes the same delayed update (its history,
    ``FilterConfig.max_latency_s``). A time of validity within the FMU's clock tolerance
    after the sample (1e-9 max(1, |t|) s, beyond the core's 1e-9 s) is taken at the
    sample, as the FMU does. ``initial`` (default: the system's as the FMU takes it,
    same start as the FMU) starts the filter at the recorded start time.
    """
    cfg = system.sources["config"]
    init = system.sources["initial"] if initial is None else initial
    t = np.asarray(rec["t_s"], float)
    T = t[1:]
    N = len(T)
    init = replace(init, nav=replace(init.nav, t_s=float(t[0])))
    starts, epochs = {0}, {}
    for key in ("gnss", "baro", "odometer"):
        m = rec.get(key)
        if m is None:
            continue
        k = np.asarray(rec[f"{key}_sample"]) - 1                # 0-based sample
        tk = T[k]
        tm = np.array(m.t_s, float)
        clock = (tm > tk + 1e-9) & (tm - tk <= 1e-9 * np.maximum(1.0, np.abs(tk)))
        tm[clock] = tk[clock]
        natural = np.searchsorted(T + 1e-9, tm, side="left")  # gf_ins_run's sample
        starts.update(k[natural < k].tolist())
        epochs[key] = (replace(m, t_s=tm), k)
    bounds = sorted(starts) + [N]
    navigator = IntegratedNavigator(cfg, init)
    parts = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        imu = ImuRecord(T[a:b], rec["dtheta"][a:b], rec["dv"][a:b], kind="increments",
                        source="co-simulation")
        sel = {}
        for key, (m, k) in epochs.items():
            take = (k >= a) & (k < b)
            sel[key] = type(m)(**{f.name: getattr(m, f.name)[take] for f in fields(m)}) \
                if np.any(take) else None
        # a piece may hold only epochs delivered late (stale, as the FMU logs them): on
        # purpose, so the check for records a run cannot use is off
        parts.append(navigator.run(imu, sel.get("gnss"), sel.get("baro"), sel.get("odometer"),
                                   gnss_velocity=system.sources.get("gnss_velocity", True),
                                   checks="off"))
    cat = {f: np.concatenate([getattr(p, f) for p in parts])
           for f in ("t_s", "q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m", "std", "sensors",
                     "standstill", "innovations")}
    return IntegratedSolution(**cat, config=cfg)


def navigation_errors(result: Mapping) -> dict:
    """Navigation error against the vehicle's truth for a :meth:`CoSimulation.run`
    result (Jacobi, or Gauss-Seidel with the navigator first): row k + 1 of the
    navigator describes the time of row k of the vehicle.

    Returns
    -------
    dict with t_s (n,), horizontal_m (n,) horizontal position error (m, north/east with
    the WGS-84 radii), velocity_m_s (n,) norm of the horizontal velocity error and
    attitude_rad (n, 3) the attitude error as a rotation vector (ENU, rad) of
    q_nav (x) q_true* (its norm is the error angle).
    """
    t = result["vehicle.time_s"][:-1, 0]
    lat_t, lon_t = result["vehicle.lat"][:-1, 0], result["vehicle.lon"][:-1, 0]
    lat_n, lon_n = result["navigator.lat"][1:, 0], result["navigator.lon"][1:, 0]
    h = result["vehicle.h"][:-1, 0]
    RM, RN, _, _ = radii(lat_t)
    north = (lat_n - lat_t) * (RM + h)
    east = (lon_n - lon_t) * (RN + h) * np.cos(lat_t)
    dv = result["navigator.v"][1:, :2] - result["vehicle.v"][:-1, :2]
    return dict(t_s=t, horizontal_m=np.hypot(north, east),
                velocity_m_s=np.linalg.norm(dv, axis=1),
                attitude_rad=attitude_error_rad(result["navigator.q"][1:], result["vehicle.q"][:-1]))


def differences_from_direct(system: System, result, kind: str = "master", imu_errors=None) -> dict:
    """Max |difference| between a co-simulated navigator and :func:`direct_navigation`
    on the sensor data recorded in ``result`` (0.0 when bit-identical).

    ``kind``: "master" (a :meth:`CoSimulation.run` result), "ssp" (:func:`run_ssp`) or
    "container" (:func:`run_container`, FMI 2.0). The rows are aligned as each runner
    records them (see their docstrings); ``imu_errors`` as for :func:`direct_navigation`.
    Returns {"lat_rad": ..., "v_m_s": ...}; for the integrated navigator (``ins_gnss``)
    also "lon_rad", "h_m", "q", "std" and "sensors", against the batch API
    (``IntegratedNavigator.run``) on the recorded increments and epochs.
    """
    model, nav = system.components["navigator"]
    if kind not in ("master", "ssp", "container"):
        raise ValueError(f"kind must be 'master', 'ssp' or 'container'; got {kind!r}")
    if model == "ins_gnss":
        rec = integrated_recording(system, result, kind)
        ref, sol = direct_navigation(system, rec), rec["solution"]
        return {name: float(np.max(np.abs(getattr(sol, f) - getattr(ref, f))))
                for name, f in (("lat_rad", "lat_rad"), ("lon_rad", "lon_rad"), ("h_m", "h_m"),
                                ("v_m_s", "v_n_m_s"), ("q", "q_bn"), ("std", "std"),
                                ("sensors", "sensors"))}
    gyro_free = model.startswith("gfnav_")
    n_in = NAVIGATORS[model][1][0][2] if gyro_free else 3

    def rows(comp, var, size=None):
        return _series(result, kind, comp, var, size)
    # the navigator's row j took the vehicle's row j - 1 (every runner); its first sample
    # comes after the initial row (master, container), the skipped steps and, for the
    # SINS, the step that only starts it
    first = (kind != "ssp") + int(nav.get("skip_steps", 0)) + (0 if gyro_free else 1)
    data = ({"A": rows("vehicle", "A", n_in)[first - 1:-1]} if gyro_free else
            {k: rows("vehicle", k, 3)[first - 1:-1] for k in ("dtheta", "dv")})
    lat, v = rows("navigator", "lat")[first:], rows("navigator", "v", 3)[first:]
    sol = direct_navigation(system, data, imu_errors=imu_errors)
    return {"lat_rad": float(np.max(np.abs(sol.lat_rad - lat))),
            "v_m_s": float(np.max(np.abs(sol.v_n_m_s - v)))}


def compare_runners(navigator: str, profile, stop_s: float, out_dir: str | pathlib.Path,
                    step_s: float = 0.01, fmi_version: int = 3,
                    runners: Iterable[str] = ("master", "ssp", "container"),
                    progress: bool = False, options: Mapping | None = None) -> dict:
    """Run vehicle + ``navigator`` along ``profile`` through each runner and compare each
    navigation solution with the cffi navigator on the sensor data that runner recorded
    (``"ins_gnss"``: :func:`vehicle_integrated_navigation` with ``options``, default
    :func:`integrated_example`, against the batch API ``IntegratedNavigator.run``).

    "master": :class:`CoSimulation` (FMI ``fmi_version``); "ssp": an SSP file in
    ``out_dir`` run by fmpy's SSP simulator; "container": an FMI 2.0 container FMU in
    ``out_dir`` run by fmpy (both with ``skip_steps = 1``, see :func:`run_ssp`).

    Returns
    -------
    dict runner -> {"wall_s", "diff" ({"lat_rad", "v_m_s"}), "path" (written file or
    None)}; the "master" entry also has "errors" (:func:`navigation_errors`).
    """
    step_s = as_scalar("step_s", step_s, "s", above=0.0)
    stop_s = as_scalar("stop_s", stop_s, "s", at_least=step_s)
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    out = {}
    for runner in runners:
        skip = 0 if runner == "master" else 1
        if navigator == "ins_gnss":
            system = vehicle_integrated_navigation(
                profile, step_s=step_s, stop_s=stop_s, skip_steps=skip,
                **(integrated_example() if options is None else dict(options)))
        else:
            system = vehicle_navigation(navigator, profile, step_s=step_s, stop_s=stop_s,
                                        skip_steps=skip)
        t0 = time.perf_counter()
        path = None
        if runner == "master":
            with CoSimulation(system, fmi_version=fmi_version) as m:
                m.initialize()
                result = m.run(progress=progress)
        elif runner == "ssp":
            path = write_ssp(system, out_dir / "vehicle_navigation.ssp")
            result = run_ssp(path, stop_s, step_s)
        elif runner == "container":
            path = write_container(system, out_dir / "vehicle_navigation.fmu", fmi_version=2)
            result = run_container(path, stop_s, step_s)
        else:
            raise ValueError(f"runner must be 'master', 'ssp' or 'container'; got {runner!r}")
        entry = dict(wall_s=time.perf_counter() - t0, path=path,
                     diff=differences_from_direct(system, result, runner))
        if runner == "master":
            entry["errors"] = navigation_errors(result)
        out[runner] = entry
    return out
