"""Transfer alignment by Monte Carlo (issue 24): a consumer MEMS slave IMU (gyro biases
200 deg/h, accelerometer biases 3 mg, random constants drawn per run; ARW 0.3
deg/sqrt(h), 100 ug/sqrt(Hz)) beside a navigation-grade master INS (free inertial with
a held height, its initial attitude error 1", 1", 1' drawn per run; 10 Hz outputs) on a
car on a straight road (10 m/s) whose instrument platform rolls +-30 deg
(gfins_fmi.sim.transfer.roll_manoeuvre); the slave is mounted at tens of arcminutes
(heading 20', pitch -15', roll 25'), 0.1 m from the master (lever arm x) and its stream
stamped 15 ms late. The slave filter (EKF, gfins_fmi.estimation.transfer.transfer_align)
estimates its attitude, biases, mounting, lever arm and time offset from 100 s of
velocity+attitude (or velocity-only) matching; the master's errors enter as measurement
noise (MASTER_ERRORS below). With --master white the master's outputs are its truth plus
the white noise the filter assumes (a check of the filter's own consistency).

Printed per matching: the mounting, lever-arm, time-offset and bias errors at the end
(RMS over the runs) against the filter's median 1-sigma, the share of (angle, run) pairs
of the mounting inside 3 sigma, the mean NEES of the mounting (3 states) and of the
transfer-alignment states (mounting, lever arm x and z, time offset: 6) with their 99%
bands; with --plot the figures of docs/alignment.md.

    python bench/study_transfer.py [--runs 100] [--seconds 100] [--workers 2]
                                   [--matching both|velocity|velocity+attitude] [--plot DIR]
    python bench/study_transfer.py --manoeuvres [--runs 20] [--workers 2]
    python bench/study_transfer.py --no-offset-state [--runs 20]   # the offset left out

--manoeuvres: observability per manoeuvre (docs/alignment.md, "Transfer alignment"): the
same installation and filter on a straight road, with the +-30 deg roll, with S-turns
(+-90 deg of heading every 20 s) and with both, each matching; printed per state the RMS
error and the median 1-sigma at the end against its prior 1-sigma (a state whose sigma
stays near its prior is not observable in that manoeuvre).
"""
from __future__ import annotations

import argparse
import pathlib
import sys
import time

import numpy as np

from gfins_fmi.analysis import montecarlo
from gfins_fmi.estimation import FilterConfig
from gfins_fmi.estimation.evaluation import chi2_band
from gfins_fmi.estimation.transfer import MasterErrors, TransferTruth, transfer_align
from gfins_fmi.nav.imu_errors import DEG_H
from gfins_fmi.sim.rotation import RotationSchedule, rest
from gfins_fmi.sim.transfer import MEMS_SLAVE, SlaveInstallation, roll_manoeuvre, simulate_transfer, straight_road
from gfins_fmi.sim.vehicle import Segment, VehicleProfile

DEG = np.pi / 180
ARCMIN = DEG / 60
MG = 9.80665e-3

INSTALLATION = SlaveInstallation(mount_rad=(20 * ARCMIN, -15 * ARCMIN, 25 * ARCMIN),
                                 lever_arm_m=(0.1, 0.0, 0.0), time_offset_s=0.015)
#: the master's errors as the slave filter takes them (white per epoch): the part that
#: changes over 100 s of the simulated navigation-grade INS (velocity RMS 0.005-0.02 m/s
#: horizontally, 0.002-0.003 m/s with its barometer vertically; attitude wandering by
#: 0.4-2.4"), and its constant attitude error (1", 1", 1' drawn per run), which the
#: slave's attitude inherits
MASTER_ERRORS = MasterErrors(velocity_std_m_s=(0.015, 0.015, 0.005), attitude_std_rad=2e-5,
                             attitude_bias_std_rad=(5e-6, 5e-6, 3e-4))
#: the slave filter's start: the master's attitude turned by the nominal mounting, 1.2 deg
#: on the mounting (its attitude error the mounting's, correlated, plus 1 mrad), the
#: biases' turn-on spread, 0.1 m on the lever arm, 30 ms on the offset
INITIAL = dict(attitude_std_rad=1e-3, velocity_std_m_s=0.1, position_std_m=1.0,
               gyro_bias_std_rad_s=200 * DEG_H, accel_bias_std_m_s2=3 * MG, mount_std_rad=0.02,
               lever_std_m=0.1, time_offset_std_s=0.03)


def config(offset_state: bool = True, **kw) -> FilterConfig:
    """The slave filter: the slave's white noise, random-constant biases, every transfer
    state but the flexure (with ``offset_state`` False not the time offset either: its
    nominal 0 then stays, the effect of an offset left out)."""
    return FilterConfig(imu=MEMS_SLAVE, master_mount=True, master_lever=True,
                        master_time_offset=offset_state, **kw)


def s_turns(speed_m_s: float = 10.0) -> VehicleProfile:
    """The straight road's car weaving: 5 s straight, then +90 deg of heading over 10 s,
    10 s straight, -90 deg over 10 s, 10 s straight, repeated (heading rate up to 18
    deg/s, lateral acceleration up to 3 m/s^2 at 10 m/s)."""
    cycle = [Segment(10.0, dheading_rad=np.pi / 2), Segment(10.0), Segment(10.0, dheading_rad=-np.pi / 2),
             Segment(10.0)]
    road = straight_road(speed_m_s)
    return VehicleProfile(speed0_m_s=speed_m_s, heading0_rad=road.heading0_rad, segments=[Segment(5.0)] + cycle * 5)


#: manoeuvre name -> (host profile or None: the straight road, platform schedule or None: no roll)
MANOEUVRES = {"straight road": (None, "level"), "roll +-30 deg": (None, None),
              "S-turns": ("turns", "level"), "roll + S-turns": ("turns", None)}


def _host_motion(manoeuvre: str):
    prof, sched = MANOEUVRES[manoeuvre]
    profile = s_turns() if prof == "turns" else None
    schedule = RotationSchedule([rest(10.0)], repeat=True) if sched == "level" else None
    return profile, schedule


def make_task(seconds: float, matching: str, filter_: str = "ekf", installation=INSTALLATION,
              master_model: str = "ins", manoeuvre: str = "roll +-30 deg", offset_state: bool = True):
    """The Monte-Carlo task: run k simulates its errors (the host's motion is shared) and
    aligns; it returns the errors and 1-sigma at the end and over time (every second)."""
    profile, schedule = _host_motion(manoeuvre)
    motion = dict(profile=profile, schedule=schedule)
    host = simulate_transfer(seconds, installation=installation, seed=0, **motion).info["host"]
    cfg = config(offset_state, filter=filter_)
    errors = MASTER_ERRORS
    white = (errors.velocity_std_m_s, errors.attitude_std_rad, errors.position_std_m)
    if master_model == "white":    # the master's errors exactly as the filter models them
        errors = MasterErrors(errors.velocity_std_m_s, errors.attitude_std_rad, errors.position_std_m)

    def task(k: int, rng: np.random.Generator) -> dict:
        seed = int(rng.integers(2 ** 31))
        sc = simulate_transfer(seconds, installation=installation, seed=seed, host=host,
                               master_model=master_model, master_white=white, **motion)
        res = transfer_align(sc.slave_imu, sc.master, config=cfg, master_rate_rad_s=sc.master_rate_rad_s,
                             matching=matching, master_errors=errors, **INITIAL)
        truth = TransferTruth(installation.mount_rad, installation.lever_arm_m, installation.time_offset_s,
                              sc.slave_gyro_bias_rad_s, sc.slave_accel_bias_m_s2, sc.truth)
        e = res.errors(truth)
        every = np.searchsorted(res.t_s, res.t_s[0] + np.arange(1.0, seconds + 1e-9, 1.0)) - 1
        out = {"t_s": res.t_s[every] - res.t_s[0]}
        for key, name in (("mount", "mount_rad"), ("lever", "lever_arm_m"), ("offset", "time_offset_s"),
                          ("gyro", "gyro_bias_rad_s"), ("accel", "accel_bias_m_s2"), ("att", "attitude")):
            out[key + "_err"] = e[name]["error"][every] if name != "attitude" else e[name]["error"][-1:]
            out[key + "_std"] = e[name]["sigma"][every] if name != "attitude" else e[name]["sigma"][-1:]
        return out
    return task


def summarize(r: dict, runs: int, matching: str, verbose: bool = True) -> dict:
    """The acceptance figures of one matching from the stacked task results."""
    me, ms = r["mount_err"][:, -1], r["mount_std"][:, -1]            # (runs, 3) at the end
    z = me / ms
    inside = float(np.mean(np.abs(z) <= 3.0))
    nees_mount = float(np.mean(np.sum(z ** 2, axis=1)))
    # the transfer states: mounting (3), lever arm x and z (y: not observable with a roll
    # about y, its sigma stays at the prior), time offset
    zl = (r["lever_err"][:, -1] / r["lever_std"][:, -1])[:, [0, 2]]
    zo = (r["offset_err"][:, -1] / r["offset_std"][:, -1]).reshape(runs, 1)
    zt = np.hstack([z, zl, zo])
    nees6 = float(np.mean(np.sum(zt ** 2, axis=1)))
    band3, band6 = chi2_band(3, runs, 0.99), chi2_band(6, runs, 0.99)
    rms = lambda a: np.sqrt(np.mean(np.asarray(a) ** 2, axis=0))
    med = lambda a: np.median(np.asarray(a), axis=0)
    out = {"matching": matching, "runs": runs,
           "mount_rms_arcmin": rms(me) / ARCMIN, "mount_sigma_arcmin": med(ms) / ARCMIN,
           "mount_inside_3sigma": inside, "nees_mount": nees_mount, "nees_mount_band": band3,
           "nees_transfer": nees6, "nees_transfer_band": band6,
           "offset_rms_ms": float(rms(r["offset_err"][:, -1, 0]) * 1e3),
           "offset_sigma_ms": float(med(r["offset_std"][:, -1, 0]) * 1e3),
           "lever_rms_m": rms(r["lever_err"][:, -1]), "lever_sigma_m": med(r["lever_std"][:, -1]),
           "gyro_rms_deg_h": rms(r["gyro_err"][:, -1]) / DEG_H, "gyro_sigma_deg_h": med(r["gyro_std"][:, -1]) / DEG_H,
           "accel_rms_mg": rms(r["accel_err"][:, -1]) / MG, "accel_sigma_mg": med(r["accel_std"][:, -1]) / MG,
           "att_rms_arcmin": rms(r["att_err"][:, -1]) / ARCMIN, "att_sigma_arcmin": med(r["att_std"][:, -1]) / ARCMIN,
           "bias_inside_3sigma": float(np.mean(np.abs(np.hstack([r["gyro_err"][:, -1] / r["gyro_std"][:, -1],
                                                                  r["accel_err"][:, -1] / r["accel_std"][:, -1]]))
                                               <= 3.0))}
    if verbose:
        f3 = lambda a, p=3: ", ".join(f"{x:.{p}g}" for x in np.atleast_1d(a))
        print(f"--- {matching} matching, {runs} runs, {r['t_s'][0, -1]:.0f} s ---")
        print(f"mounting heading/pitch/roll: RMS error {f3(out['mount_rms_arcmin'])} arcmin; median 1-sigma "
              f"{f3(out['mount_sigma_arcmin'])} arcmin; inside 3 sigma: {100 * inside:.1f}% of {3 * runs} (angle, run) pairs")
        print(f"NEES of the mounting: {nees_mount:.3f} (99% band of the mean of {runs} chi2(3): "
              f"[{band3[0]:.3f}, {band3[1]:.3f}]); of mounting + lever x, z + offset: {nees6:.3f} "
              f"([{band6[0]:.3f}, {band6[1]:.3f}])")
        print(f"time offset: RMS error {out['offset_rms_ms']:.4f} ms, median 1-sigma {out['offset_sigma_ms']:.4f} ms")
        print(f"lever arm x/y/z: RMS error {f3(out['lever_rms_m'])} m; median 1-sigma {f3(out['lever_sigma_m'])} m")
        print(f"gyro bias: RMS error {f3(out['gyro_rms_deg_h'])} deg/h, median 1-sigma {f3(out['gyro_sigma_deg_h'])}; "
              f"accel bias: RMS error {f3(out['accel_rms_mg'])} mg, median 1-sigma {f3(out['accel_sigma_mg'])}; "
              f"biases inside 3 sigma: {100 * out['bias_inside_3sigma']:.1f}%")
        print(f"attitude E/N/U: RMS error {f3(out['att_rms_arcmin'])} arcmin, median 1-sigma {f3(out['att_sigma_arcmin'])}")
    return out


def run(runs: int = 100, seconds: float = 100.0, matching: str = "velocity+attitude", seed: int = 0,
        workers=None, scheduler=None, filter_: str = "ekf", progress: bool = False, verbose: bool = True,
        master_model: str = "ins", manoeuvre: str = "roll +-30 deg", offset_state: bool = True):
    """The study for one matching: {figures} (summarize) and the stacked runs."""
    task = make_task(seconds, matching, filter_, master_model=master_model, manoeuvre=manoeuvre,
                     offset_state=offset_state)
    with montecarlo.executor(scheduler, workers) as ex:
        r = montecarlo.run(task, runs, seed=seed, executor=ex, progress=progress, desc=matching)
    return summarize(r, runs, matching, verbose), r


def plot(results: dict, path: pathlib.Path) -> None:
    """docs/alignment.md's figure: the mounting's RMS error and median 1-sigma over time,
    velocity-only against velocity+attitude matching, and the time offset's."""
    import matplotlib   # lazy: only for the figure
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    for j, (matching, r) in enumerate(results.items()):
        t = r["t_s"][0]
        for i, nm in enumerate(("heading", "pitch", "roll")):
            rms = np.sqrt(np.mean(r["mount_err"][:, :, i] ** 2, axis=0)) / ARCMIN
            sig = np.median(r["mount_std"][:, :, i], axis=0) / ARCMIN
            line, = ax[0, j].semilogy(t, rms, label=f"{nm} RMS error")
            ax[0, j].semilogy(t, sig, ls="--", color=line.get_color(), label=f"{nm} median 1-sigma")
        ax[0, j].set_title(f"mounting, {matching} matching ({len(r['t_s'])} runs)")
        ax[0, j].set_ylabel("arcmin")
        rms = np.sqrt(np.mean(r["offset_err"][:, :, 0] ** 2, axis=0)) * 1e3
        sig = np.median(r["offset_std"][:, :, 0], axis=0) * 1e3
        ax[1, j].semilogy(t, rms, label="RMS error")
        ax[1, j].semilogy(t, sig, ls="--", label="median 1-sigma")
        ax[1, j].set_title(f"time offset (15 ms), {matching} matching")
        ax[1, j].set_ylabel("ms")
        ax[1, j].set_xlabel("time (s)")
        for a in ax[:, j]:
            a.grid(alpha=0.3, which="both")
            a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


#: the priors of INITIAL per state of the manoeuvre table (what "not observable" stays at)
_PRIOR = {"mount": 0.02 / ARCMIN, "offset": 30.0, "lever": 0.1, "gyro": 200.0, "accel": 3.0}


def observability(runs: int, seconds: float, seed: int, workers, scheduler) -> None:
    """The manoeuvre table: per manoeuvre and matching, RMS error / median 1-sigma at the
    end of the mounting (arcmin), time offset (ms), lever arm (m), gyro (deg/h) and
    accelerometer (mg) biases."""
    f = lambda a, p=2: "/".join(f"{x:.{p}g}" for x in np.atleast_1d(a))
    print(f"priors (1-sigma): mounting {_PRIOR['mount']:.0f}', offset {_PRIOR['offset']:.0f} ms, lever arm "
          f"{_PRIOR['lever']} m, gyro bias {_PRIOR['gyro']:.0f} deg/h, accel bias {_PRIOR['accel']:.0f} mg")
    print("| manoeuvre | matching | mounting h/p/r (') | offset (ms) | lever x/y/z (m) | gyro bias x/y/z "
          "(deg/h) | accel bias x/y/z (mg) |")
    print("|---|---|---|---|---|---|---|")
    for manoeuvre in MANOEUVRES:
        for matching in ("velocity", "velocity+attitude"):
            t0 = time.time()
            o, _ = run(runs, seconds, matching, seed, workers, scheduler, verbose=False, manoeuvre=manoeuvre)
            cell = lambda e, sg, p=2: f"{f(e, p)} / {f(sg, p)}"
            print(f"| {manoeuvre} | {matching} | {cell(o['mount_rms_arcmin'], o['mount_sigma_arcmin'])} | "
                  f"{cell(o['offset_rms_ms'], o['offset_sigma_ms'])} | {cell(o['lever_rms_m'], o['lever_sigma_m'])} | "
                  f"{cell(o['gyro_rms_deg_h'], o['gyro_sigma_deg_h'])} | {cell(o['accel_rms_mg'], o['accel_sigma_mg'])} |",
                  flush=True)
            print(f"  ({time.time() - t0:.1f} s wall; mounting inside 3 sigma {100 * o['mount_inside_3sigma']:.0f}%, "
                  f"NEES {o['nees_mount']:.2f})", file=sys.stderr)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--runs", type=int, default=100)
    p.add_argument("--seconds", type=float, default=100.0)
    p.add_argument("--matching", choices=("both", "velocity", "velocity+attitude"), default="both")
    p.add_argument("--filter", choices=("ekf", "ukf"), default="ekf")
    p.add_argument("--master", choices=("ins", "white"), default="ins",
                   help="the master: a navigation-grade INS (default) or truth + white noise")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--workers", type=int, default=None, help="threads (default: one per CPU)")
    p.add_argument("--scheduler", default=None, help="a dask.distributed scheduler's address")
    p.add_argument("--plot", type=pathlib.Path, default=None, help="folder for the figure")
    p.add_argument("--progress", action="store_true")
    p.add_argument("--no-offset-state", action="store_true",
                   help="the time offset not estimated (its effect: the nominal 0 against the true 15 ms)")
    p.add_argument("--manoeuvres", action="store_true",
                   help="the observability table per manoeuvre (use --runs 20)")
    a = p.parse_args(argv)
    if a.manoeuvres:
        observability(a.runs, a.seconds, a.seed, a.workers, a.scheduler)
        return 0
    kinds = ("velocity", "velocity+attitude") if a.matching == "both" else (a.matching,)
    stacked = {}
    for m in kinds:
        t0 = time.time()
        _, stacked[m] = run(a.runs, a.seconds, m, a.seed, a.workers, a.scheduler, a.filter, a.progress,
                            master_model=a.master, offset_state=not a.no_offset_state)
        print(f"({time.time() - t0:.1f} s wall)", file=sys.stderr)
    if a.plot and len(stacked) == 2:
        a.plot.mkdir(parents=True, exist_ok=True)
        plot(stacked, a.plot / "transfer_alignment_mc.png")
        print(f"figure -> {a.plot / 'transfer_alignment_mc.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
