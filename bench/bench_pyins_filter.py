"""Integrated navigation (INS/GNSS EKF) against pyins' ``run_feedback_filter``: speed and
accuracy on the same simulated record (issue 11: ">= 20x pyins' run_feedback_filter on
the same data at equal or better accuracy").

    python bench/bench_pyins_filter.py [--minutes 30] [--repeat 3] [--seed 0] [--seeds 1]

The record (gfins_fmi.sim.scenarios)
    town_drive(T) simulated by simulate_drive at 100 Hz: increments over (t_(k-1), t_k],
    tactical IMU (TACTICAL: ARW 0.05 deg/sqrt(h), VRW 50 ug/sqrt(Hz), Gauss-Markov biases
    1 deg/h and 100 ug with tau 3600 s, started in steady state); GNSS from
    gfins_fmi.sim.vehicle.GnssReceiver at 1 Hz, position and velocity with white errors of the
    same std on every axis (1 m and 0.05 m/s: pyins' Position and NedVelocity take one
    scalar std for the three axes), no Gauss-Markov error, no latency, lever arm zero.
    Two 60 s GNSS outages (at 40 % and 70 % of the record) are cut from the GNSS record
    both filters get. The filters start from the truth perturbed by a fixed error
    (position E, N, U +1.5, -1.0, +2.0 m; velocity +0.10, -0.10, +0.05 m/s; roll +0.1 deg,
    pitch -0.1 deg, heading +1.0 deg), 0.5 to 1 sigma of the initial uncertainty below.

gfins_fmi (timed: ``integrate(imu, gnss, config=..., initial=...)``, whole record)
    FilterConfig(imu=TACTICAL) with its defaults (EKF, increments, coning/sculling,
    NIS gate 0.9999) and propagation_interval_s = 0.1 (the default; "decimated") or 0
    (covariance propagated at every IMU sample); GNSS position and velocity;
    InitialState(position_std_m=2, velocity_std_m_s=0.2, attitude_std_rad=(0.2, 0.2, 2)
    deg; bias stds default to the IMU model's bias instability).

pyins (PyPI ``python-ins``, imported as ``pyins``; benchmark only, not a dependency;
timed: ``compute_increments_from_imu`` + ``run_feedback_filter``, after a JIT warm-up on
the first 10 s)
    * frames: pyins navigates in NED with a body front-right-down frame; ours in ENU with
      body right-front-up: x_frd = y_rfu, y_frd = x_rfu, z_frd = -z_rfu for the
      increments; (VN, VE, VD) = (v_N, v_E, -v_U); (roll, pitch, heading) in deg are our
      (roll, pitch, heading) (gfins_fmi.nav.strapdown.quat_to_euler: the same angles, checked to
      1e-10 deg by bench/bench_sins.py); lat, lon in deg.
    * time: pyins' IMU table is indexed by the end of each interval like ours;
      compute_increments_from_imu(..., "increment") needs one reading before the first,
      so the first increment is repeated at the start time t_0 (its coning/sculling term
      with itself is zero). initial_pva.name = t_0. GNSS at its times of validity
      (pyins predicts the strapdown state to the measurement time inside an IMU interval,
      as ours does).
    * IMU model (inertial_sensor.EstimationModel, SI): noise = our white noise intensity
      (FilterConfig.noise_si(): gyro ARW rad/sqrt(s), accelerometer VRW m/s/sqrt(s));
      bias_sd = the Gauss-Markov std sigma (our initial bias std too); bias_walk =
      sigma sqrt(2 / tau), the driving noise of our Gauss-Markov bias. pyins models a
      bias as a random constant plus random walk: the same driving noise, without the
      decay -b / tau (tau = 1 h), so where GNSS does not observe a bias its variance
      grows as sigma^2 (1 + 2 t / tau) instead of staying at sigma^2. This is the only
      modelling difference; no scale-factor states in either.
    * measurements: pyins.measurements.Position(lat, lon, alt; sd = 1 m) and
      NedVelocity(VN, VE, VD; sd = 0.05 m/s), the same epochs and values as ours.
    * initial uncertainty: position_sd = 2 m, velocity_sd = 0.2 m/s, level_sd = 0.2 deg,
      azimuth_sd = 2 deg (pyins maps roll/pitch/heading std to its phi-angle states).
    * time_step = 0.1 s (its default, = our propagation_interval_s); with_altitude=True
      (3-D, like ours). No gate in pyins.
Both filters see the same increments, the same GNSS epochs and the same initial state.

Accuracy: errors against the truth with gfins_fmi.estimation.evaluation.navigation_errors
(the truth interpolated to each solution's times; for pyins its output rows converted to
ENU, q_b^n), over t >= --converge-s (default 300 s) of --seeds records (seed, seed + 1,
...; each filter runs once on the others): "outage" rows run from the start of an outage
to the first GNSS epoch after it, "aided" rows are the others. Horizontal and vertical
position error, 3-D velocity error, heading error (Euler heading difference), tilt
(|rotation-vector error E, N|), RMS and max over the rows; and the outage score (RMS over
the outages of the maximum horizontal error in each, as in evaluation.outage_protocol).

Timing (first record only): best of --repeat of the whole filter run (record preparation
excluded; gfins_fmi is run once before, pyins on 10 s for numba's JIT), wall
time (time.perf_counter) and CPU time of this process (time.process_time); BLAS threads
are pinned to one (the machine is shared). The load average is printed with each record
and after the pyins timing.
"""
from __future__ import annotations

import argparse
import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import platform  # noqa: E402
import subprocess  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402

from gfins_fmi.estimation import UPDATE_STATUS, FilterConfig, InitialState, integrate  # noqa: E402
from gfins_fmi.estimation.evaluation import navigation_errors  # noqa: E402
from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive, town_drive  # noqa: E402
from gfins_fmi.nav.strapdown import NavState, euler_to_quat, quat_to_euler  # noqa: E402
from gfins_fmi.nav.earth import euler_to_quat as euler_to_quat_rows, radii  # noqa: E402
from gfins_fmi.sim.vehicle import GnssReceiver  # noqa: E402

DEG = np.pi / 180.0
DT_S = 0.01
GNSS_POS_STD_M = 1.0
GNSS_VEL_STD_M_S = 0.05
OUTAGE_S = 60.0
# initial uncertainty (1 sigma) and the fixed initial error both filters start with
P0_POS_M, P0_VEL_M_S, P0_LEVEL_DEG, P0_HEADING_DEG = 2.0, 0.2, 0.2, 2.0
ERR0_POS_ENU_M = np.array([1.5, -1.0, 2.0])
ERR0_VEL_ENU_M_S = np.array([0.10, -0.10, 0.05])
ERR0_HPR_DEG = np.array([1.0, -0.1, 0.1])      # heading, pitch, roll


@dataclass
class Record:
    drive: object          # SimulatedDrive
    gnss: object           # GnssRecord with the outages cut
    outages: np.ndarray    # (k, 2) [t0, t1)
    nav0: NavState         # the (perturbed) initial state


def build_record(minutes: float, seed: int) -> Record:
    T = 60.0 * minutes
    rx = GnssReceiver(rate_hz=1.0, pos_std_m=(GNSS_POS_STD_M,) * 3,
                      vel_std_m_s=(GNSS_VEL_STD_M_S,) * 3)
    d = simulate_drive(town_drive(T), T, DT_S, imu=TACTICAL, gnss=rx, seed=seed)
    t0 = float(d.truth.t_s[0])
    outages = np.array([[t0 + f * T, t0 + f * T + OUTAGE_S] for f in (0.4, 0.7)])
    gnss = d.gnss.with_outages([tuple(w) for w in outages])
    x = d.initial
    RM, RN, _, _ = radii(x.lat_rad)
    hpr = quat_to_euler(x.q_bn) + ERR0_HPR_DEG * DEG
    nav0 = NavState(euler_to_quat(hpr), x.v_n_m_s + ERR0_VEL_ENU_M_S,
                    x.lat_rad + ERR0_POS_ENU_M[1] / (RM + x.h_m),
                    x.lon_rad + ERR0_POS_ENU_M[0] / ((RN + x.h_m) * np.cos(x.lat_rad)),
                    x.h_m + ERR0_POS_ENU_M[2], x.t_s)
    return Record(d, gnss, outages, nav0)


# ---------------------------------------------------------------- gfins_fmi
def ours_runner(rec: Record, propagation_interval_s: float):
    cfg = FilterConfig(imu=TACTICAL, propagation_interval_s=propagation_interval_s)
    init = InitialState(rec.nav0, position_std_m=P0_POS_M, velocity_std_m_s=P0_VEL_M_S,
                        attitude_std_rad=np.radians([P0_LEVEL_DEG, P0_LEVEL_DEG, P0_HEADING_DEG]))

    def run():
        return integrate(rec.drive.imu, rec.gnss, config=cfg, initial=init)
    return run


# ---------------------------------------------------------------- pyins
@dataclass
class PyinsSolution:
    """pyins' trajectory in gfins_fmi's conventions (for navigation_errors)."""
    t_s: np.ndarray
    lat_rad: np.ndarray
    lon_rad: np.ndarray
    h_m: np.ndarray
    v_n_m_s: np.ndarray    # ENU
    q_bn: np.ndarray       # body RFU -> ENU


def _frd(x):
    return np.c_[x[:, 1], x[:, 0], -x[:, 2]]


def pyins_runner(rec: Record):
    """The pyins inputs (prepared once, not timed) and the timed run."""
    import pandas as pd
    from pyins import filters, inertial_sensor, measurements
    from pyins.strapdown import compute_increments_from_imu

    d, x0 = rec.drive, rec.nav0
    t_imu = np.asarray(d.imu.t_s)
    g, a = _frd(np.asarray(d.imu.gyro)), _frd(np.asarray(d.imu.accel))
    imu = pd.DataFrame(np.c_[np.r_[g[:1], g], np.r_[a[:1], a]],
                       index=pd.Index(np.r_[x0.t_s, t_imu], name="time"),
                       columns=["gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"])
    noise = FilterConfig(imu=TACTICAL).noise_si()

    def models():
        gb, gt = noise["gyro_bias_std_rad_s"], noise["gyro_bias_tau_s"]
        ab, at = noise["accel_bias_std_m_s2"], noise["accel_bias_tau_s"]
        return (inertial_sensor.EstimationModel(bias_sd=gb, noise=noise["gyro_arw_rad_sqrt_s"],
                                                bias_walk=gb * np.sqrt(2.0 / gt)),
                inertial_sensor.EstimationModel(bias_sd=ab, noise=noise["accel_vrw_m_s_sqrt_s"],
                                                bias_walk=ab * np.sqrt(2.0 / at)))

    gn = rec.gnss
    t_g = pd.Index(np.asarray(gn.t_s), name="time")
    pos = pd.DataFrame({"lat": np.degrees(gn.lat_rad), "lon": np.degrees(gn.lon_rad), "alt": gn.h_m},
                       index=t_g)
    v = np.asarray(gn.vel_enu_m_s)
    vel = pd.DataFrame({"VN": v[:, 1], "VE": v[:, 0], "VD": -v[:, 2]}, index=t_g)
    meas = [measurements.Position(pos, GNSS_POS_STD_M), measurements.NedVelocity(vel, GNSS_VEL_STD_M_S)]
    hpr = quat_to_euler(x0.q_bn) / DEG
    pva = pd.Series({"lat": np.degrees(x0.lat_rad), "lon": np.degrees(x0.lon_rad), "alt": x0.h_m,
                     "VN": x0.v_n_m_s[1], "VE": x0.v_n_m_s[0], "VD": -x0.v_n_m_s[2],
                     "roll": hpr[2], "pitch": hpr[1], "heading": hpr[0]}, name=x0.t_s)

    def run(n=None):
        gm, am = models()
        inc = compute_increments_from_imu(imu if n is None else imu.iloc[:n + 1], "increment")
        return filters.run_feedback_filter(pva, P0_POS_M, P0_VEL_M_S, P0_LEVEL_DEG, P0_HEADING_DEG,
                                           inc, gyro_model=gm, accel_model=am, measurements=meas,
                                           time_step=0.1, with_altitude=True)
    return run


def pyins_solution(res) -> PyinsSolution:
    tr = res.trajectory
    q = euler_to_quat_rows(np.radians(tr["heading"].values), np.radians(tr["pitch"].values),
                           np.radians(tr["roll"].values))
    return PyinsSolution(np.asarray(tr.index, float), np.radians(tr["lat"].values),
                         np.radians(tr["lon"].values), tr["alt"].values.copy(),
                         np.c_[tr["VE"].values, tr["VN"].values, -tr["VD"].values], q)


# ---------------------------------------------------------------- measurement
def timed(fn, repeat):
    """Best wall and best CPU time over ``repeat`` runs, and the last result."""
    walls, cpus, out = [], [], None
    for _ in range(repeat):
        out = None
        c0, w0 = time.process_time(), time.perf_counter()
        out = fn()
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
    return min(walls), min(cpus), out


def error_samples(sol, rec: Record, converge_s: float) -> dict:
    """Per row class ("aided", "outage"), the error magnitudes of the rows (see the module),
    and the maximum horizontal error in each outage ("outage_max_m")."""
    e = navigation_errors(sol, rec.drive.truth)
    t = e.t_s
    t_g = np.asarray(rec.gnss.t_s)
    in_out = np.zeros(len(t), bool)
    out_max = []
    for a, b in rec.outages:
        # an outage lasts until the first GNSS epoch after it
        end = t_g[np.searchsorted(t_g, b, side="right")] if t_g[-1] > b else np.inf
        sel = (t >= a) & (t < end)
        in_out |= sel
        out_max.append(float(np.max(e.horizontal_m[sel])))
    after = t >= t[0] + converge_s
    res = {"outage_max_m": np.array(out_max)}
    for name, sel in (("aided", after & ~in_out), ("outage", in_out)):
        res[name] = {"hor_m": e.horizontal_m[sel], "ver_m": np.abs(e.pos_enu_m[sel, 2]),
                     "vel_m_s": np.linalg.norm(e.vel_enu_m_s[sel], axis=1),
                     "head_deg": np.abs(e.heading_rad[sel]) / DEG,
                     "tilt_deg": np.hypot(e.att_rad[sel, 0], e.att_rad[sel, 1]) / DEG}
    return res


def summarise(samples: list) -> dict:
    """RMS and max of each quantity over the rows of all records; outage score = RMS over
    the outages of the maximum horizontal error in each."""
    out = {}
    for part in ("aided", "outage"):
        out[part] = {}
        for k in samples[0][part]:
            v = np.concatenate([s[part][k] for s in samples])
            out[part][k] = (float(np.sqrt(np.mean(v ** 2))), float(np.max(v)))
    om = np.concatenate([s["outage_max_m"] for s in samples])
    out["outage_max_m"] = om
    out["outage_score_m"] = float(np.sqrt(np.mean(om ** 2)))
    return out


def machine() -> str:
    model, cores = platform.processor() or "unknown", str(os.cpu_count())
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
        info = {k.strip(): v.strip() for k, v in (line.split(":", 1) for line in out.splitlines()
                                                  if ":" in line)}
        model, cores = info.get("Model name", model), info.get("CPU(s)", cores)
    except (OSError, subprocess.CalledProcessError):
        pass
    return f"{model}, {cores} logical CPUs, Python {platform.python_version()}, numpy {np.__version__}"


def load() -> str:
    return "load average " + " ".join(f"{x:.2f}" for x in os.getloadavg())


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=30.0, help="record length (min)")
    ap.add_argument("--repeat", type=int, default=3, help="timed runs per filter (best is kept)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the timed record")
    ap.add_argument("--seeds", type=int, default=1,
                    help="records for the accuracy (seed, seed + 1, ...; only the first is timed)")
    ap.add_argument("--converge-s", type=float, default=300.0,
                    help="accuracy is taken from this time after the start (s)")
    ap.add_argument("--skip-pyins", action="store_true")
    a = ap.parse_args(argv)
    if a.minutes * 60.0 * 0.3 <= OUTAGE_S:
        ap.error(f"--minutes must exceed {OUTAGE_S / 0.3 / 60.0:.2f}: the two {OUTAGE_S:g} s outages "
                 "(at 40 % and 70 % of the record) must fit apart and before the end")
    if a.minutes * 60.0 * 0.4 < a.converge_s:
        ap.error("the first outage (at 40 % of the record) must come after --converge-s")
    if a.repeat < 1 or a.seeds < 1:
        ap.error("--repeat and --seeds must be >= 1")
    try:
        import pyins
    except ImportError:
        pyins = None
        print("pyins not installed (pip install python-ins into this venv): comparison skipped")
    if a.skip_pyins:
        pyins = None

    print(f"machine: {machine()}")
    ours = (("gfins_fmi EKF, propagation 0.1 s", 0.1), ("gfins_fmi EKF, every sample", 0.0))
    p_label = f"pyins {getattr(pyins, '__version__', '?')} run_feedback_filter"
    rows, samples, biases = [], {}, {}
    for k, seed in enumerate(range(a.seed, a.seed + a.seeds)):
        t0 = time.perf_counter()
        rec = build_record(a.minutes, seed)
        n = len(rec.drive.imu.t_s) if k == 0 else n
        print(f"record seed {seed}: {a.minutes:g} min town drive, {len(rec.drive.imu.t_s)} IMU "
              f"increments at 100 Hz, {len(rec.gnss.t_s)} GNSS epochs (pos {GNSS_POS_STD_M} m, "
              f"vel {GNSS_VEL_STD_M_S} m/s), outages "
              f"{[tuple(float(x) for x in np.round(w, 1)) for w in rec.outages]} s; prepared in "
              f"{time.perf_counter() - t0:.1f} s; {load()}")
        if k == 0:
            biases["truth"] = (rec.drive.gyro_bias_rad_s[-1], rec.drive.accel_bias_m_s2[-1])
        for label, dtp in ours:
            run = ours_runner(rec, dtp)
            if k == 0:
                run()    # warm caches (first touch of the output pages)
                w, c, sol = timed(run, a.repeat)
                rows.append((label, w, c))
                st = sol.rejected()["status"]
                why = ", ".join(f"{np.count_nonzero(st == s)} {v}" for s, v in UPDATE_STATUS.items()
                                if s and np.any(st == s))
                print(f"  {label}: wall {w:.3f} s, CPU {c:.3f} s; {len(sol.innovations) - len(st)} "
                      f"updates applied, not applied: {why or 'none'}")
                biases[label] = (sol.sensors[-1, :3], sol.sensors[-1, 3:6])
            else:
                sol = run()
            samples.setdefault(label, []).append(error_samples(sol, rec, a.converge_s))
        if pyins is not None:
            prun = pyins_runner(rec)
            if k == 0:
                prun(1000)     # numba JIT warm-up (10 s of data), not timed
                w, c, res = timed(prun, a.repeat)
                rows.append((p_label, w, c))
                print(f"  {p_label}: wall {w:.3f} s, CPU {c:.3f} s; {load()}")
                # pyins' estimates are FRD: back to RFU
                biases[p_label] = (_frd(res.gyro.values[-1:])[0], _frd(res.accel.values[-1:])[0])
            else:
                res = prun()
            samples.setdefault(p_label, []).append(error_samples(pyins_solution(res), rec, a.converge_s))

    print(f"\nsensor-error estimates at the end of seed {a.seed} (body right, front, up; "
          "gyro deg/h, accelerometer ug):")
    for label, (gb, ab) in biases.items():
        print(f"  {label:<40} gyro {np.array2string(np.asarray(gb) / DEG * 3600, precision=3)}  "
              f"accel {np.array2string(np.asarray(ab) / 9.80665e-6, precision=1)}")

    ref = rows[-1] if pyins is not None else None
    print(f"\nspeed (seed {a.seed}: {n} IMU samples, best of {a.repeat}; ratio = pyins' time / "
          "this one's):")
    print(f"| {'filter':<40} | wall s   | CPU s    | samples/s (CPU) | ratio (CPU) | ratio (wall) |")
    print(f"|{'-' * 42}|----------|----------|-----------------|-------------|--------------|")
    for label, w, c in rows:
        rc = f"{ref[2] / c:10.0f}x" if ref else f"{'-':>11}"
        rw = f"{ref[1] / w:11.0f}x" if ref else f"{'-':>12}"
        print(f"| {label:<40} | {w:8.3f} | {c:8.3f} | {n / c:15,.0f} | {rc} | {rw} |")

    acc = {label: summarise(v) for label, v in samples.items()}
    print(f"\naccuracy against the truth over {a.seeds} record(s), RMS / max, t >= {a.converge_s:g} s "
          "(outage: from the start of each 60 s outage to the first GNSS epoch after it; aided: "
          "the other rows):")
    print(f"| {'filter':<40} | rows   | horizontal m  | vertical m    | velocity m/s    "
          "| heading deg   | tilt deg        |")
    print(f"|{'-' * 42}|--------|---------------|---------------|-----------------"
          "|---------------|-----------------|")
    for label, r0 in acc.items():
        for part in ("aided", "outage"):
            r = r0[part]
            print(f"| {label:<40} | {part:<6} | {r['hor_m'][0]:5.3f} / {r['hor_m'][1]:5.3f} "
                  f"| {r['ver_m'][0]:5.3f} / {r['ver_m'][1]:5.3f} "
                  f"| {r['vel_m_s'][0]:6.4f} / {r['vel_m_s'][1]:6.4f} "
                  f"| {r['head_deg'][0]:5.3f} / {r['head_deg'][1]:5.3f} "
                  f"| {r['tilt_deg'][0]:6.4f} / {r['tilt_deg'][1]:6.4f} |")
    print("\nmaximum horizontal error in each outage (m) and their RMS (the outage score):")
    for label, r0 in acc.items():
        print(f"  {label:<40} {np.array2string(r0['outage_max_m'], precision=3)}  "
              f"score {r0['outage_score_m']:.3f} m")


if __name__ == "__main__":
    main()
