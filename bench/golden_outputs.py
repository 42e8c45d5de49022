"""Golden outputs: sha256 of what the commands and the main API calls produce, to prove a
code move changed no result (issue 19: "a move keeps behaviour: record output hashes
before, compare after").

    python bench/golden_outputs.py --write before.json     # record
    python bench/golden_outputs.py --compare before.json   # after the move: every hash equal

Every case runs a user-visible path on deterministic inputs (fixed seeds, the repository's
rtk_walk recording) and hashes each output file byte for byte, the command's exit code
and its standard output and error (lines that carry a wall-clock time are dropped), and,
for API calls, the bytes of every returned array. Figures (PNG) are not hashed: their
bytes carry the matplotlib version, not our results. Takes ~2 minutes on one core.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
RTK = ROOT / "tests" / "data" / "rtk_walk"
DEG = np.pi / 180
_TIMING = re.compile(r"\b\d+(\.\d+)?\s*(ms|s|min)\b.*(elapsed|took|wall|per s|/s)|it/s|s/it"
                     r"|\d\d:\d\d<|\bin \d+(\.\d+)? ?s\b|^report -> .*\(\d+(\.\d+)? s\)$")


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _arrays(*arrays) -> str:
    h = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(np.asarray(a))
        h.update(str((a.dtype.str, a.shape)).encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _clean(text: str, work: pathlib.Path) -> str:
    text = text.replace(str(work), "<work>")
    return "\n".join(x for x in text.splitlines() if not _TIMING.search(x))


class Golden:
    def __init__(self, work: pathlib.Path):
        self.work = work
        self.hashes: dict[str, str] = {}
        exe = pathlib.Path(sys.executable).with_name("gfins")
        self.gfins = [str(exe)] if exe.exists() else [sys.executable, "-m", "gfins_fmi.cli"]

    def cli(self, name: str, args: list, outputs: list):
        """Run `gfins ARGS` in a folder of its own; hash exit code, output text and files."""
        d = self.work / name
        d.mkdir(parents=True, exist_ok=True)
        env = dict(os.environ, MPLBACKEND="Agg", OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
        p = subprocess.run(self.gfins + [str(a) for a in args], cwd=d, capture_output=True,
                           text=True, env=env)
        self.hashes[f"{name}/exit"] = str(p.returncode)
        self.hashes[f"{name}/stdout"] = _sha(_clean(p.stdout, self.work).encode())
        self.hashes[f"{name}/stderr"] = _sha(_clean(p.stderr, self.work).encode())
        for o in outputs:
            f = d / o
            self.hashes[f"{name}/{o}"] = _sha(f.read_bytes()) if f.exists() else "missing"
        print(f"{name}: exit {p.returncode}", file=sys.stderr)

    def api(self, name: str, *arrays):
        self.hashes[name] = _arrays(*arrays)
        print(f"{name}", file=sys.stderr)


# ---- inputs --------------------------------------------------------------------------
def _strapdown_record(n=3000, dt=0.01):
    """t, gyro increments (rad), accel increments (m/s): a vehicle-like wobble at rest."""
    t = np.arange(1, n + 1) * dt
    w = np.c_[0.02 * np.sin(0.7 * t), 0.01 * np.cos(1.1 * t), 0.05 * np.sin(0.2 * t)]
    f = np.c_[0.3 * np.sin(0.5 * t), 0.2 + 0.1 * np.cos(0.3 * t), 9.80 + 0.05 * np.sin(t)]
    return np.c_[t, w * dt, f * dt]


def _array_record(gf, layout: str, n=2000, dt=0.01, l_m=0.1):
    t = np.arange(n) * dt
    omega = np.c_[0.4 + 0.2 * np.sin(0.5 * t), -0.3 + 0.1 * t / t[-1], 0.6 * np.cos(0.3 * t)]
    omega_dot = np.c_[0.1 * np.cos(0.5 * t), 0.1 / t[-1] + 0 * t, -0.18 * np.sin(0.3 * t)]
    f = np.tile([0.1, -0.2, 9.8], (n, 1))
    geom = gf.accel9_geometry(l_m) if layout == "qin9" else gf.layout(layout, l_m)
    A = gf.forward_model(geom, f, omega, omega_dot)
    rng = np.random.default_rng(5)
    A = A + rng.normal(0, 1e-5, A.shape)
    return np.c_[t, A], omega[0]


def run_all(g: Golden):
    import gfins_fmi as gf
    w = g.work
    np.savetxt(w / "sins_inc.csv", _strapdown_record(), delimiter=",")
    rates = _strapdown_record()
    rates[:, 1:] /= 0.01
    np.savetxt(w / "sins_rates.csv", rates, delimiter=",")
    # ---- record commands
    nav0 = ["--lat0", "30", "--lon0", "114", "--h0", "50", "--heading0", "20"]
    g.cli("navigate_inc", ["navigate", w / "sins_inc.csv", "out.csv"] + nav0, ["out.csv"])
    g.cli("navigate_rates", ["navigate", w / "sins_rates.csv", "out.csv", "--input-kind", "rates",
                             "--vertical", "hold"] + nav0, ["out.csv"])
    g.cli("navigate_sub2", ["navigate", w / "sins_inc.csv", "out.npz", "--subsamples", "2"] + nav0,
          ["out.npz"])
    for lay, strat in [("qin9", "integrate"), ("qin9", "sqrt"), ("qin9", "fused"),
                       ("cube6", "integrate"), ("12", "eigen")]:
        rec, w0 = _array_record(gf, lay)
        f = w / f"array_{lay}.csv"
        np.savetxt(f, rec, delimiter=",")
        extra = ["--accel-noise", "1e-5"] if strat == "fused" else []
        g.cli(f"gfnav_{lay}_{strat}", ["gfnav", f, "out.csv", "--layout", lay, "--lever-arm", "0.1",
                                        "--strategy", strat, f"--omega-init={w0[0]},{w0[1]},{w0[2]}"]
              + extra + nav0, ["out.csv"])
        if lay == "qin9" and strat == "integrate":
            g.cli("solve9", ["solve9", f, "out.csv", "--lever-arm", "0.1",
                             f"--omega-init={w0[0]},{w0[1]},{w0[2]}"], ["out.csv"])
    # ---- integrated navigation on the real recording
    imu, gnss = RTK / "imu_1730_sf.csv", RTK / "gnss_1730_sf.pos"
    base = ["integrate", imu, gnss, "out.csv", "--imu-format", "rtk_walk", "--grade", "consumer",
            "--static", "9", "--zupt", "--lever-arm=0,0,0.05"]
    outs = ["out.csv", "out.innovations.csv"]
    g.cli("integrate_ekf", base, outs)
    g.cli("integrate_ekf_smooth", base + ["--smooth"], outs + ["out.smoothed.csv"])
    g.cli("integrate_ukf", base + ["--filter", "ukf"], outs)
    g.cli("integrate_sub2_prop0", base + ["--subsamples", "2", "--propagation-interval", "0"], outs)
    g.cli("integrate_outages", base + ["--outages", "10,30,30", "--smooth"], outs + ["out.smoothed.csv"])
    # ---- simulated drive with every sensor, written as CSV records
    _drive_cli(g)
    # ---- calibration and alignment
    cal = ["calibrate", "rec.csv", "--lat", "34", "--height", "80", "--simulate", "turntable19",
           "--json", "p.json", "--report", "r.md", "--passes", "1"]
    g.cli("calibrate_turntable19", cal, ["rec.csv", "rec.csv.truth.json", "p.json", "r.md"])
    g.cli("calibrate_delay", cal + ["--delay", "--sim-seed", "3"], ["rec.csv", "p.json", "r.md"])
    rec = w / "calibrate_turntable19" / "rec.csv"
    g.cli("align_static", ["align", "static", rec, "--position", "34,0,80", "--window", "0,50"], [])
    g.cli("align_static_fine", ["align", "static", rec, "--position", "34,0,80", "--window", "0,30",
                                "--fine"], [])
    g.cli("align_disturbed", ["align", "static", rec, "--position", "34,0,80", "--disturbed",
                              "--window", "0,50"], [])
    _align_motion(g)
    # ---- co-simulation, reproductions, analysis
    for nav in ["gfnav_qin9", "gfnav_cube6", "gfnav_12", "sins", "ins_gnss"]:
        for v in (["2", "3"] if nav in ("sins", "ins_gnss") else ["2"]):
            g.cli(f"cosim_{nav}_fmi{v}", ["cosim", "--navigator", nav, "--seconds", "3", "--align", "1",
                                          "--fmi", v, "--out", "o", "--quiet"], [])
            for f in sorted((w / f"cosim_{nav}_fmi{v}" / "o").glob("*.csv")):
                g.hashes[f"cosim_{nav}_fmi{v}/{f.name}"] = _sha(f.read_bytes())
    g.cli("reproduce_qin", ["reproduce", "qin", "--runs", "4", "--workers", "2", "--out", "o"], [])
    for f in sorted((w / "reproduce_qin" / "o").glob("*.md")):
        g.hashes[f"reproduce_qin/{f.name}"] = _sha(f.read_bytes())
    g.cli("analyze", ["analyze", "--config", "sins", "--config", "qin9-fused", "--runs", "6",
                      "--workers", "2", "--out", "o", "--quiet"], [])
    for f in sorted((w / "analyze" / "o").glob("*.md")):
        g.hashes[f"analyze/{f.name}"] = _sha(f.read_bytes())
    _api(g)


def _drive(seconds=120.0):
    from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive, town_drive
    from gfins_fmi.sim.vehicle import Barometer, GnssReceiver, Odometer
    prof = town_drive(seconds, lat0_rad=0.6, lon0_rad=2.0, h0_m=30.0, heading0_rad=0.4)
    return simulate_drive(prof, seconds, 0.01, imu=TACTICAL, gnss=GnssReceiver(lever_arm_m=(0.3, 1.1, 1.5)),
                          baro=Barometer(), odometer=Odometer(), seed=11, imu_mount_rad=(0.01, -0.02))


def _drive_cli(g: Golden):
    d = _drive()
    w = g.work
    d.imu.to_csv(w / "drive_imu.csv")
    d.gnss.to_csv(w / "drive_gnss.csv")
    d.baro.to_csv(w / "drive_baro.csv")
    d.odometer.to_csv(w / "drive_odo.csv")
    from gfins_fmi.io import TruthRecord
    tr = d.truth
    TruthRecord(t_s=tr.t_s, lat_rad=tr.lat_rad, lon_rad=tr.lon_rad, h_m=tr.h_m, v_enu_m_s=tr.v_n_m_s,
                euler_rad=tr.euler_rad).to_csv(w / "drive_truth.csv")
    for f in ("drive_imu.csv", "drive_gnss.csv", "drive_baro.csv", "drive_odo.csv", "drive_truth.csv"):
        g.hashes[f"inputs/{f}"] = _sha((w / f).read_bytes())
    e = [float(x) for x in np.degrees(gf_quat_to_euler(tr.q_bn[0]))]
    p0 = [float(np.degrees(tr.lat_rad[0])), float(np.degrees(tr.lon_rad[0])), float(tr.h_m[0])]
    ini = f"--initial={p0[0]!r},{p0[1]!r},{p0[2]!r},{e[0]!r},{e[1]!r},{e[2]!r}"
    args = ["integrate", w / "drive_imu.csv", w / "drive_gnss.csv", "out.csv", "--imu-format", "csv",
            "--gnss-format", "csv", "--grade", "tactical", ini, "--lever-arm=0.3,1.1,1.5",
            "--baro", w / "drive_baro.csv", "--odometer", w / "drive_odo.csv", "--nhc", "--odometer-mount"]
    outs = ["out.csv", "out.innovations.csv"]
    g.cli("integrate_drive_all", args + ["--smooth"], outs + ["out.smoothed.csv"])
    g.cli("integrate_drive_ukf", args + ["--filter", "ukf", "--subsamples", "2"], outs)
    g.cli("integrate_drive_truth", args + ["--truth", w / "drive_truth.csv"], outs)


def gf_quat_to_euler(q):
    import gfins_fmi as gf
    return gf.quat_to_euler(q)


def _align_motion(g: Golden):
    from gfins_fmi.io import BaroRecord, ImuRecord, OdometerRecord
    from gfins_fmi.sim.vehicle import Segment, VehicleProfile, simulate_vehicle
    dt = 0.02
    segs = [Segment(20.0), Segment(30.0, dheading_rad=np.pi / 2), Segment(20.0, dspeed_m_s=1.0)]
    prof = VehicleProfile(lat0_rad=30 * DEG, lon0_rad=114 * DEG, h0_m=-50.0, heading0_rad=40 * DEG,
                          speed0_m_s=4.5, segments=segs)
    tr = simulate_vehicle(prof, 70.0, dt)
    rng = np.random.default_rng(7)
    n = len(tr.t_s) - 1
    imu = ImuRecord(t_s=tr.t_s[1:], gyro=tr.dtheta_rad + rng.normal(0, 1e-6, (n, 3)),
                    accel=tr.dv_m_s + rng.normal(0, 1e-5, (n, 3)), kind="increments")
    ks = np.arange(5, n + 1, 5)
    vh = np.hypot(tr.v_n_m_s[ks, 0], tr.v_n_m_s[ks, 1])
    tach = OdometerRecord(t_s=tr.t_s[ks], speed_m_s=vh + rng.normal(0, 0.05, len(ks)),
                          std_m_s=np.full(len(ks), 0.05))
    kd = np.arange(50, n + 1, 50)
    depth = BaroRecord(t_s=tr.t_s[kd], h_m=tr.h_m[kd] + rng.normal(0, 0.1, len(kd)),
                       std_m=np.full(len(kd), 0.1))
    w = g.work
    imu.to_csv(w / "auv_imu.csv")
    tach.to_csv(w / "auv_speed.csv")
    depth.to_csv(w / "auv_depth.csv")
    e = [float(x) for x in np.degrees(gf_quat_to_euler(tr.q_bn[0])) + [2.0, 0.2, -0.2]]
    g.cli("align_motion", ["align", "motion", w / "auv_imu.csv", w / "auv_speed.csv",
                           f"--initial=30,114,-50,{e[0]!r},{e[1]!r},{e[2]!r}", "--depth", w / "auv_depth.csv",
                           "--passes", "2", "--output", "passes.csv"], ["passes.csv"])


def _api(g: Golden):
    """The batch API and the FMUs on one simulated drive: EKF/UKF with every option, the
    smoother, the FMU runs (FMI 2 and 3), the strapdown and gyro-free navigators and their
    FMUs, the laboratory calibration, the error models."""
    import gfins_fmi as gf
    from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
    from gfins_fmi.sim.scenarios import TACTICAL
    from gfins_fmi.fmi.ins_gnss import run_ins_gnss_fmu
    from gfins_fmi.fmi.models import run_sins_fmu, run_gfnav_fmu
    d = _drive(60.0)
    init = InitialState(d.initial, position_std_m=(0.3, 0.2, 0.5), velocity_std_m_s=0.05,
                        attitude_std_rad=(1e-3, 1e-3, 5e-3))
    cases = {
        "ekf": dict(),
        "ukf": dict(filter="ukf"),
        "ekf25": dict(scale_factors=True, baro_bias=True, odometer_scale=True, nhc=True,
                      odometer_mount=True, propagation_interval_s=0.0, odometer_mount_rad=(0.01, -0.02)),
        "ukf25": dict(filter="ukf", scale_factors=True, baro_bias=True, odometer_scale=True, nhc=True,
                      odometer_mount=True, odometer_mount_tau_s=900.0),
        "ekf_sub3": dict(subsamples=3, zupt=True),
    }
    for name, kw in cases.items():
        cfg = FilterConfig(imu=TACTICAL, gnss_lever_arm_m=(0.3, 1.1, 1.5), **kw)
        sol = IntegratedNavigator(cfg, init).run(d.imu, d.gnss, d.baro, d.odometer, smoother=True)
        fields = [getattr(sol, f) for f in ("t_s", "q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m",
                                             "std", "sensors", "standstill")]
        g.api(f"api/ins_{name}", *fields, *[sol.innovations[k] for k in sol.innovations.dtype.names])
        sm = sol.smooth()
        g.api(f"api/ins_{name}_smooth", sm.t_s, sm.q_bn, sm.v_n_m_s, sm.lat_rad, sm.lon_rad, sm.h_m,
              sm.std, sm.sensors)
        if name in ("ekf", "ukf25"):
            for v in (2, 3):
                out = run_ins_gnss_fmu(d.imu, d.gnss, d.baro, d.odometer, config=cfg, initial=init,
                                       fmi_version=v)
                g.api(f"api/fmu_ins_{name}_fmi{v}", out.t_s, out.q_bn, out.v_n_m_s, out.lat_rad,
                      out.std, out.sensors)
    # strapdown: batch and FMU
    rec = _strapdown_record(2000)
    nav = gf.NavState(gf.euler_to_quat(np.array([0.3, 0.01, -0.02])), np.array([1.0, 2.0, 0.0]),
                      0.5, 2.0, 50.0, 0.0)
    for sub in (1, 2, 4):
        s = gf.Strapdown(nav, gf.SinsConfig(subsamples=sub)).run(rec[:, 1:4], rec[:, 4:7], 0.01)
        g.api(f"api/sins_sub{sub}", s.q_bn, s.v_n_m_s, s.lat_rad, s.lon_rad, s.h_m)
    for v in (2, 3):
        s = run_sins_fmu(rec[:, 1:4], rec[:, 4:7], 0.01, nav, fmi_version=v)
        g.api(f"api/fmu_sins_fmi{v}", s.q_bn, s.v_n_m_s, s.lat_rad, s.h_m)
    # gyro-free: navigator and FMUs
    for lay in ("qin9", "cube6", "12"):
        r, w0 = _array_record(gf, lay, 1500)
        geom = gf.accel9_geometry(0.1) if lay == "qin9" else gf.layout(lay, 0.1)
        s, rs = gf.GyroFreeNavigator(geom, nav, omega_init_rad_s=w0).run(r[:, 1:], 0.01)
        g.api(f"api/gfnav_{lay}", s.q_bn, s.v_n_m_s, s.lat_rad, s.h_m, rs.omega_rad_s)
        s, om, f, fl = run_gfnav_fmu(lay, r[:, 1:], 0.01, nav, l_m=0.1, omega_init_rad_s=w0)
        g.api(f"api/fmu_gfnav_{lay}", s.q_bn, s.v_n_m_s, s.lat_rad, s.h_m, om, f, fl)
    r, w0 = _array_record(gf, "qin9", 1500)
    sol = gf.solve_accel9(r[:, 1:], 0.01, 0.1, omega_init_rad_s=w0)
    g.api("api/solve9", sol.f_m_s2, sol.omega_rad_s, sol.omega_dot_rad_s2, sol.flags)
    o = gf.run_accel9_fmu(r[:, 1:], 0.01, 0.1, omega_init_rad_s=w0)
    g.api("api/fmu_accel9", o.f_m_s2, o.omega_rad_s, o.omega_dot_rad_s2, o.flags)
    # laboratory calibration
    from gfins_fmi.calibration.laboratory import calibrate, simulate, test_plan
    errs = gf.ImuErrors(gyro_scale_ppm=(100, -50, 30), accel_bias_ug=(200, -100, 50))
    data = simulate(errs, test_plan(), np.random.default_rng(3))
    res = calibrate(data)
    g.api("api/calibration_lab", np.array([res.estimate[k] for k in sorted(res.estimate)]),
          np.array([res.std[k] for k in sorted(res.std)]), res.residual_rms_accel_m_s2,
          res.residual_rms_gyro_rad_s)
    # error models
    from gfins_fmi.analysis.strapdown_errors import sins_error_model
    m = sins_error_model(0.6, gf.euler_to_quat(np.array([0.3, 0.01, -0.02])))
    g.api("api/error_model_sins", *[np.asarray(x) for x in (m.A, m.B, m.C, m.D)])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--write", help="write the hashes to this JSON file")
    ap.add_argument("--compare", help="compare with the hashes in this JSON file")
    ap.add_argument("--keep", help="keep the outputs in this folder")
    a = ap.parse_args(argv)
    work = pathlib.Path(a.keep or tempfile.mkdtemp(prefix="golden_"))
    work.mkdir(parents=True, exist_ok=True)
    g = Golden(work.resolve())
    try:
        run_all(g)
    finally:
        if not a.keep:
            shutil.rmtree(work, ignore_errors=True)
    if a.write:
        pathlib.Path(a.write).write_text(json.dumps(g.hashes, indent=1, sort_keys=True) + "\n")
    print(f"{len(g.hashes)} hashes")
    if a.compare:
        ref = json.loads(pathlib.Path(a.compare).read_text())
        diff = sorted(k for k in set(ref) | set(g.hashes) if ref.get(k) != g.hashes.get(k))
        for k in diff:
            print(f"DIFFERS: {k}: {ref.get(k)} -> {g.hashes.get(k)}")
        print(f"{len(diff)} of {len(ref)} differ")
        return 1 if diff else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
