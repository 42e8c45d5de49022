"""``gfins demo``: the main job, end to end.

1. A closed-form rigid-body motion (body rates that cross zero, angular acceleration,
   specific force) and the outputs of the 9-accelerometer array it would produce.
2. The record solved through cffi (one C call) — noise-free, to show exact recovery.
3. The same record (with sensor noise) solved by the FMI 2.0 and FMI 3.0 FMUs under
   fmpy as the master; agreement with the cffi solution.
4. The analysis: predicted noise of the solution against the measured one.
5. A figure (PNG) of rates, errors and flags.
6. Strapdown navigation of a closed-form trajectory: cffi batch and the SINS FMU, and
   the gyro-free chain (accelerometer array -> 9-accelerometer solver -> the same
   mechanization fed with rates); a second figure.
7. Co-simulation: the vehicle FMU (seed 001's run, shortened) feeding the gyro-free
   navigator FMU, through the Python master and fmpy's SSP simulator, each checked
   against the navigator called through cffi on the same sensor data.
"""
from __future__ import annotations

import pathlib
import time
from dataclasses import dataclass

import numpy as np

from gfins_fmi._lib import as_scalar
from gfins_fmi.analysis.noise_gains import accel9_noise_gains
from gfins_fmi.estimation.config import FilterConfig, InitialState
from gfins_fmi.estimation.evaluation import navigation_errors, plot_errors
from gfins_fmi.estimation.navigator import IntegratedNavigator
from gfins_fmi.fmi.models import run_accel9_fmu, run_sins_fmu
from gfins_fmi.fmi.paths import fmu_path, validate
from gfins_fmi.fmi.reference import compare_runners
from gfins_fmi.gyrofree.array import MIN_LEVER_ARM_M, accel9_geometry, forward_model, solve_accel9
from gfins_fmi.nav.strapdown import NavState, SinsConfig, Strapdown
from gfins_fmi.sim import trajectory as tj
from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive, town_drive
from gfins_fmi.sim.vehicle import GnssReceiver, VehicleProfile


@dataclass
class Motion:
    """Closed-form body motion sampled at t (s): f (m/s^2), omega (rad/s), omega_dot
    (rad/s^2), all in body axes."""

    t_s: np.ndarray
    f_m_s2: np.ndarray
    omega_rad_s: np.ndarray
    omega_dot_rad_s2: np.ndarray


def tumbling_motion(duration_s: float, dt_s: float) -> Motion:
    """A tumbling body: each rate component is a sinusoid (x and z cross zero), the
    specific force is gravity's 9.81 m/s^2 on the body z axis plus a sway."""
    t = np.arange(int(round(duration_s / dt_s))) * dt_s
    w = np.c_[1.2 * np.sin(0.4 * t), 0.6 + 0.8 * np.cos(0.3 * t), 2.0 * np.sin(0.2 * t + 0.3)]
    wd = np.c_[0.48 * np.cos(0.4 * t), -0.24 * np.sin(0.3 * t), 0.4 * np.cos(0.2 * t + 0.3)]
    f = np.c_[0.5 * np.sin(0.9 * t), 0.3 * np.cos(0.5 * t), 9.81 + 0.2 * np.sin(1.1 * t)]
    return Motion(t, f, w, wd)


def _rel_diff(a: np.ndarray, b: np.ndarray) -> float:
    scale = np.maximum(np.abs(b), 1e-300)
    return float(np.max(np.abs(a - b) / scale))


def run(out_dir: str | pathlib.Path = "gfins_demo", duration_s: float = 60.0,
        dt_s: float = 0.01, l_m: float = 0.1, noise_m_s2: float = 1e-4,
        seed: int = 1, echo=print) -> dict:
    """Run the demonstration; returns the figures it printed (for tests and scripts).

    Raises
    ------
    ValueError
        A parameter out of range (checked before anything runs): ``duration_s`` and
        ``dt_s`` > 0 giving at least 2 samples, ``l_m`` >= 1e-6 m, ``noise_m_s2`` >= 0.
    """
    duration_s = as_scalar("duration_s", duration_s, "s", above=0.0)
    dt_s = as_scalar("dt_s", dt_s, "s", above=0.0)
    l_m = as_scalar("l_m", l_m, "m", at_least=MIN_LEVER_ARM_M)
    noise_m_s2 = as_scalar("noise_m_s2", noise_m_s2, "m/s^2", at_least=0.0)
    if int(round(duration_s / dt_s)) < 2:
        raise ValueError(f"duration_s = {duration_s:g} s at dt_s = {dt_s:g} s gives fewer than 2 "
                         "samples")
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    results: dict = {}
    m = tumbling_motion(duration_s, dt_s)
    n = m.t_s.size
    geometry = accel9_geometry(l_m)
    A = forward_model(geometry, m.f_m_s2, m.omega_rad_s, m.omega_dot_rad_s2)
    w0 = m.omega_rad_s[0]
    echo(f"gfins demo — 9-accelerometer gyro-free solver (Qin et al.), l = {l_m} m, "
         f"{n} samples at {dt_s} s ({duration_s:g} s)")

    # 1. noise-free through cffi: exact recovery
    t0 = time.perf_counter()
    exact = solve_accel9(A, dt_s, l_m, w0)
    t_c = time.perf_counter() - t0
    err = {
        "f_m_s2": float(np.max(np.abs(exact.f_m_s2 - m.f_m_s2))),
        "omega_dot_rad_s2": float(np.max(np.abs(exact.omega_dot_rad_s2 - m.omega_dot_rad_s2))),
        "omega_rad_s (|w|>1e-3)": float(np.max(np.abs(exact.omega_rad_s - m.omega_rad_s)[
            np.abs(m.omega_rad_s) > 1e-3])),
    }
    results["noise_free_max_error"] = err
    echo(f"\n[C core via cffi] noise-free record solved in {t_c * 1e3:.2f} ms; max |error|:")
    for k, v in err.items():
        echo(f"    {k:26s} {v:.3e}")

    # 2. noisy record through cffi and through both FMUs
    rng = np.random.default_rng(seed)
    A_noisy = A + rng.normal(0.0, noise_m_s2, A.shape)
    ref = solve_accel9(A_noisy, dt_s, l_m, w0)
    echo(f"\n[FMUs via fmpy] noisy record (white noise {noise_m_s2:g} m/s^2 per accelerometer)")
    for version in (2, 3):
        path = fmu_path("accel9", version)
        problems = validate(path)
        t0 = time.perf_counter()
        sol = run_accel9_fmu(A_noisy, dt_s, l_m, w0, fmi_version=version)
        t_f = time.perf_counter() - t0
        diff = max(_rel_diff(getattr(sol, k), getattr(ref, k))
                   for k in ("f_m_s2", "omega_rad_s", "omega_dot_rad_s2", "omega_sq_rad2_s2"))
        same_flags = bool(np.array_equal(sol.flags, ref.flags))
        results[f"fmi{version}"] = dict(problems=problems, max_rel_diff=diff,
                                        flags_equal=same_flags, seconds=t_f)
        echo(f"    FMI {version}.0 {path.name}: fmpy validate: {len(problems)} problems; "
             f"{n} doSteps in {t_f:.2f} s; max relative difference to cffi {diff:.1e}; "
             f"flags {'identical' if same_flags else 'DIFFERENT'}")

    # 3. analysis: predicted vs measured noise of the solution
    gains = accel9_noise_gains(l_m)
    meas = {
        "f": (ref.f_m_s2 - m.f_m_s2).std(axis=0),
        "omega_sq": (ref.omega_sq_rad2_s2 - m.omega_rad_s ** 2).std(axis=0),
        "omega_dot": (ref.omega_dot_rad_s2 - m.omega_dot_rad_s2).std(axis=0),
    }
    pred = {"f": noise_m_s2 * gains.f, "omega_sq": noise_m_s2 * gains.omega_sq,
            "omega_dot": noise_m_s2 * gains.omega_dot}
    results["noise_std"] = {k: dict(predicted=pred[k].tolist(), measured=meas[k].tolist())
                            for k in pred}
    echo("\n[analysis] solution noise std, predicted from the solution matrix vs measured "
         f"({n} samples; expect agreement within ~{300 / np.sqrt(n):.0f}%):")
    units = {"f": "m/s^2", "omega_sq": "rad^2/s^2", "omega_dot": "rad/s^2"}
    for k in pred:
        echo(f"    {k:10s} predicted {pred[k][0]:.3e}  measured "
             + " ".join(f"{v:.3e}" for v in meas[k]) + f"  {units[k]}")
    counts = ref.flag_counts()
    echo(f"    flagged samples (omega_k^2 < 0 under noise, rate propagated): "
         f"x {counts['neg_omega_sq_x']}, y {counts['neg_omega_sq_y']}, z {counts['neg_omega_sq_z']}")
    err_w = ref.omega_rad_s - m.omega_rad_s
    results["omega_rms_error_rad_s"] = np.sqrt((err_w ** 2).mean(axis=0)).tolist()
    echo("    rate RMS error (rad/s): " + " ".join(f"{v:.2e}" for v in results["omega_rms_error_rad_s"])
         + "  — largest near zero crossings, where |w| = sqrt(w^2) amplifies noise")

    # 4. figure
    png = out_dir / "gfins_demo.png"
    _plot(png, m, ref, gains, noise_m_s2)
    results["figure"] = str(png)

    # 5. strapdown navigation and the gyro-free chain
    results["sins"] = _strapdown(out_dir, min(duration_s, 120.0), dt_s, l_m, echo)
    results["cosim"] = _cosim(out_dir, echo)
    results["integrated"] = _integrated(out_dir, echo)
    echo(f"\nfigures: {png}, {results['sins']['figure']}, {results['integrated']['figure']}")
    return results


def _cosim(out_dir: pathlib.Path, echo) -> dict:
    prof = VehicleProfile.seed001(align_s=5.0, accel_s=10.0, turn_times_s=(20.0,), turn_s=15.0)
    stop = 60.0
    res = compare_runners("gfnav_qin9", prof, stop, out_dir, fmi_version=2,
                                runners=("master", "ssp"))
    e = res["master"]["errors"]
    echo(f"\n[co-simulation] vehicle FMU (rest, 15 m/s, a 180 deg turn) -> gyro-free navigator "
         f"FMU (qin9), {stop:g} s at 100 Hz: Python master {res['master']['wall_s']:.2f} s, fmpy "
         f"SSP {res['ssp']['wall_s']:.2f} s; max horizontal error {e['horizontal_m'].max():.3g} m; "
         f"vs cffi on the same data: master |dlat| {res['master']['diff']['lat_rad']:.1g} rad, "
         f"SSP |dlat| {res['ssp']['diff']['lat_rad']:.1g} rad")
    return dict(max_horizontal_error_m=float(e["horizontal_m"].max()),
                master_diff=max(res["master"]["diff"].values()),
                ssp_diff=max(res["ssp"]["diff"].values()))


def _integrated(out_dir: pathlib.Path, echo) -> dict:
    """INS/GNSS: a simulated 5-minute drive (tactical IMU, 1 Hz GNSS with a 60 s outage),
    EKF, UKF and RTS smoother, errors against the truth."""
    T = 300.0
    outage = (150.0, 210.0)
    d = simulate_drive(town_drive(T), T, 0.01, imu=TACTICAL, seed=2,
                       gnss=GnssReceiver(rate_hz=1.0, offset_s=0.37, outages_s=(outage,)))
    init = InitialState(d.initial, position_std_m=(1.0, 1.0, 2.0), velocity_std_m_s=0.1,
                        attitude_std_rad=(0.005, 0.005, 0.02))
    out = {}
    for filt in ("ekf", "ukf"):
        t0 = time.perf_counter()
        sol = IntegratedNavigator(FilterConfig(imu=TACTICAL, filter=filt), init).run(d.imu, d.gnss,
                                                                                    smoother=True)
        wall = time.perf_counter() - t0
        sm = sol.smooth()
        ef, es = navigation_errors(sol, d.truth), navigation_errors(sm, d.truth)
        inside = (sol.t_s >= outage[0]) & (sol.t_s < outage[1])
        out[filt] = dict(outage_max_m=float(ef.horizontal_m[inside].max()),
                         smoothed_outage_max_m=float(es.horizontal_m[inside].max()),
                         rms_m=float(ef.rms()["horizontal_m"]), seconds=wall)
        if filt == "ekf":
            png = plot_errors(ef, out_dir / "gfins_demo_ins_gnss.png", std=sol.std,
                              title="INS/GNSS EKF, tactical IMU, 1 Hz GNSS, 60 s outage",
                              windows=np.array([outage]))
    echo(f"\n[INS/GNSS] {T:g} s drive, tactical IMU at 100 Hz, 1 Hz GNSS, a 60 s outage: "
         + "; ".join(f"{k.upper()} {v['seconds']:.2f} s, horizontal RMS {v['rms_m']:.2f} m, max in the "
                     f"outage {v['outage_max_m']:.2f} m (smoothed {v['smoothed_outage_max_m']:.2f} m)"
                     for k, v in out.items()))
    out["figure"] = str(png)
    return out


def _strapdown(out_dir: pathlib.Path, duration_s: float, dt_s: float, l_m: float, echo) -> dict:
    tr = tj.sample(tj.Circle(), duration_s, dt_s)
    x0 = NavState.from_trajectory(tr, 0)
    R = 6371000.0

    def horiz(sol, k0):
        return np.hypot((sol.lat_rad - tr.lat_rad[k0:]) * R,
                        (sol.lon_rad - tr.lon_rad[k0:]) * R * np.cos(tr.lat_rad[k0:]))

    t0 = time.perf_counter()
    nav = Strapdown(x0).run(tr.dtheta_rad, tr.dv_m_s, dt_s=dt_s)
    t_c = time.perf_counter() - t0
    fmu = run_sins_fmu(tr.dtheta_rad, tr.dv_m_s, dt_s, x0, fmi_version=3)
    diff = max(_rel_diff(getattr(fmu, k), getattr(nav, k))
               for k in ("q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m"))
    # gyro-free: the array's outputs -> (omega, f) -> the mechanization in rate mode
    A = tr.array_outputs(accel9_geometry(l_m))
    gfree = solve_accel9(A, dt_s, l_m, tr.gyro_rad_s[0])
    gnav = Strapdown(x0, SinsConfig(input="rates")).run(gfree.omega_rad_s, gfree.f_m_s2, dt_s=dt_s)
    e_nav, e_gf = horiz(nav, 1), horiz(gnav, 0)
    echo(f"\n[strapdown] circle of 100 m at 10 m/s, {duration_s:g} s at {dt_s} s, from exact "
         f"increments: C core {t_c * 1e3:.1f} ms, max horizontal error {e_nav.max():.2e} m; "
         f"SINS FMU (FMI 3.0) vs cffi: max relative difference {diff:.1e}")
    echo(f"[gyro-free chain] noise-free 9-accelerometer array -> solver -> mechanization "
         f"(rates): max horizontal error {e_gf.max():.2e} m")

    import matplotlib   # lazy: matplotlib (~0.3 s) only for figures
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.5), constrained_layout=True)
    E = lambda lon: (lon - tr.lon_rad[0]) * R * np.cos(tr.lat_rad[0])  # noqa: E731
    N = lambda lat: (lat - tr.lat_rad[0]) * R                          # noqa: E731
    ax[0].plot(E(tr.lon_rad), N(tr.lat_rad), lw=3, alpha=0.4, label="truth")
    ax[0].plot(E(nav.lon_rad), N(nav.lat_rad), "--", label="strapdown (increments)")
    ax[0].plot(E(gnav.lon_rad), N(gnav.lat_rad), ":", label="gyro-free chain")
    ax[0].set(xlabel="east (m)", ylabel="north (m)", aspect="equal", title="ground track")
    ax[0].legend(fontsize=8)
    ax[1].semilogy(nav.t_s, e_nav + 1e-12, label="strapdown (increments)")
    ax[1].semilogy(gnav.t_s, e_gf + 1e-12, label="gyro-free chain (rates)")
    ax[1].set(xlabel="time (s)", ylabel="horizontal error (m)", title="navigation error")
    ax[1].legend(fontsize=8)
    png = out_dir / "gfins_demo_sins.png"
    fig.savefig(png, dpi=100)
    plt.close(fig)
    return dict(max_horizontal_error_m=float(e_nav.max()), fmu_max_rel_diff=diff,
                gyro_free_max_horizontal_error_m=float(e_gf.max()), figure=str(png))


def _plot(png: pathlib.Path, m: Motion, sol, gains, noise_m_s2: float) -> None:
    import matplotlib   # lazy: matplotlib (~0.3 s) only for figures
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(3, 1, figsize=(10, 9), sharex=True, constrained_layout=True)
    colors = ("tab:blue", "tab:orange", "tab:green")
    for k, axis in enumerate("xyz"):
        ax[0].plot(m.t_s, m.omega_rad_s[:, k], color=colors[k], lw=2, alpha=0.4,
                   label=f"true $\\omega_{axis}$")
        ax[0].plot(m.t_s, sol.omega_rad_s[:, k], color=colors[k], lw=0.8, ls="--",
                   label=f"solved $\\omega_{axis}$")
        ax[1].semilogy(m.t_s, np.abs(sol.omega_rad_s[:, k] - m.omega_rad_s[:, k]) + 1e-12,
                       color=colors[k], lw=0.6, label=f"$|\\delta\\omega_{axis}|$")
        ax[2].plot(m.t_s, ((sol.flags >> k) & 1) * (k + 1), ".", color=colors[k], ms=2,
                   label=f"$\\omega_{axis}^2<0$")
    # first-order prediction of the rate noise, sigma_w2 / (2|w|), per axis
    sd = gains.omega_std(noise_m_s2, m.omega_rad_s)   # broadcasts over (n, 3)
    for k in range(3):
        ax[1].semilogy(m.t_s, sd[:, k], color="k", lw=1.0, ls=(0, (4, 2)), zorder=3)
    ax[0].set_ylabel("rate (rad/s)")
    ax[0].legend(ncol=3, fontsize=8)
    ax[0].set_title("9-accelerometer gyro-free solution (seed 000): |omega| from omega^2, "
                    "sign from integrated omega_dot")
    ax[1].set_ylabel("|rate error| (rad/s)")
    ax[1].set_ylim(1e-8, 1)
    ax[1].legend(ncol=3, fontsize=8, title="coloured: error; black dashed: predicted 1-sigma "
                 "$\\sigma_{\\omega^2}/(2|\\omega|)$", title_fontsize=8)
    ax[2].set_ylabel("flag (axis)")
    ax[2].set_yticks([1, 2, 3], ["x", "y", "z"])
    ax[2].set_ylim(0.5, 3.5)
    ax[2].set_xlabel("time (s)")
    ax[2].legend(ncol=3, fontsize=8, loc="upper right")
    fig.savefig(png, dpi=110)
    plt.close(fig)
