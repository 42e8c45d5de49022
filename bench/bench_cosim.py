"""Cost of the FMUs under a master: one doStep from a minimal C master, and a 600 s,
100 Hz vehicle + navigator co-simulation through fmpy.

    python bench/bench_cosim.py [--seconds 600] [--profile] [--steps-only] [--runs 5]

1. bench/fmu_master.c (compiled here with cc) dlopens an FMU's FMI 2.0 binary and times
   {fmi2SetReal(inputs); fmi2DoStep; fmi2GetReal(outputs)} per sample, with the inputs
   recorded from the C vehicle model (seed 001's run): the cost a system tool pays.
   Every navigator FMU the build makes (gfins_fmi.fmi.paths.MODELS: sins, ins_gnss and the
   gyro-free gfnav_*), plus the accel9 solver and the vehicle; CPU time of the master
   process (best and median of --runs). --steps-only stops after this part.
2. The vehicle FMU + gyro-free navigator FMU co-simulated for --seconds at 100 Hz by
   gfins_fmi.fmi.master.CoSimulation (FMI 2.0 and 3.0), fmpy's SSP simulator and fmpy's
   container FMU; with --profile, cProfile of the Python master says where the time goes.
"""
from __future__ import annotations

import argparse
import cProfile
import os
import pathlib
import platform
import pstats
import shutil
import subprocess
import tempfile
import time

import numpy as np

import gfins_fmi as gf
from gfins_fmi.fmi.master import CoSimulation
from gfins_fmi.fmi.system import System, vehicle_navigation
from gfins_fmi.fmi.container import run_container, write_container
from gfins_fmi.fmi.ssp import run_ssp, write_ssp
from gfins_fmi.sim.vehicle import VehicleProfile, simulate_vehicle

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _build_master(tmp: pathlib.Path) -> pathlib.Path:
    exe = tmp / "fmu_master"
    cc = shutil.which("cc") or shutil.which("gcc")
    subprocess.run([cc, "-O2", "-std=c11", "-Wall", "-Werror", "-I", str(ROOT / "fmu" / "include"),
                    str(ROOT / "bench" / "fmu_master.c"), "-o", str(exe), "-ldl"], check=True)
    return exe


def _time_fmu(exe, model, inputs: dict, outputs: list, n, h, tmp, params_note=""):
    from fmpy import extract, read_model_description
    path = gf.fmu_path(model, 2)
    md = read_model_description(str(path))
    unz = pathlib.Path(extract(str(path)))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    in_names, data = [], []
    for name, arr in inputs.items():
        arr = np.atleast_2d(np.asarray(arr, float).T).T
        in_names += [f"{name}[{i}]" for i in range(1, arr.shape[1] + 1)]
        data.append(arr)
    out_names = [o for name in outputs for o in ([name] if name in vr else
                 [k for k in vr if k.startswith(name + "[")])]
    binfile = tmp / f"{model}.bin"
    if data:
        np.ascontiguousarray(np.hstack(data)[:n]).tofile(binfile)
    lib = unz / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    args = [str(exe), str(lib), md.guid, (unz / "resources").as_uri(), str(n), str(h),
            ",".join(str(vr[k]) for k in in_names) or "-", ",".join(str(vr[k]) for k in out_names) or "-"]
    if data:
        args.append(str(binfile))
    res = subprocess.run(args, capture_output=True, text=True, check=True)
    shutil.rmtree(unz, ignore_errors=True)
    print(f"  {model:12s} {params_note:24s} {res.stdout.strip()}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=600.0)
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--steps-only", action="store_true", help="only the C-master step timings")
    ap.add_argument("--runs", type=int, default=5, help="runs of the C master per FMU (best, median)")
    args = ap.parse_args()
    cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo")
                if line.startswith("model name")), platform.processor())
    print(f"machine: {cpu}, {os.cpu_count()} logical CPUs")
    h = 0.01
    n = int(round(args.seconds / h))
    prof = VehicleProfile.seed001(align_s=60.0)
    rec = simulate_vehicle(prof, args.seconds, h)
    A9 = rec.array_outputs(gf.layout("qin9", 0.1))
    with tempfile.TemporaryDirectory() as tmpd:
        tmp = pathlib.Path(tmpd)
        exe = _build_master(tmp)
        os.environ["FMU_MASTER_RUNS"] = str(args.runs)
        print(f"1. one doStep from a C master (dlopen, FMI 2.0), {n} steps of {h} s, CPU time:")
        from gfins_fmi.fmi.paths import MODELS
        print(f"  FMUs built: {', '.join(sorted(MODELS))}")
        outs = ["q", "v", "lat", "lon", "h"]
        _time_fmu(exe, "gfnav_qin9", {"A": A9}, outs, n, h, tmp, "default strategy")
        _time_fmu(exe, "gfnav_cube6", {"A": rec.array_outputs(gf.layout("cube6", 0.1))}, outs, n, h,
                  tmp, "default strategy")
        _time_fmu(exe, "gfnav_12", {"A": rec.array_outputs(gf.layout("12", 0.1))}, outs, n, h,
                  tmp, "default strategy")
        inc = np.vstack([np.zeros((1, 3)), rec.dtheta_rad]), np.vstack([np.zeros((1, 3)), rec.dv_m_s])
        _time_fmu(exe, "sins", {"dtheta": inc[0], "dv": inc[1]}, outs, n, h, tmp, "increments, coning")
        _time_fmu(exe, "ins_gnss", {"dtheta": inc[0], "dv": inc[1]}, outs, n, h, tmp,
                  "EKF, P every 0.1 s")
        _time_fmu(exe, "vehicle", {}, ["A", "dtheta", "dv", "q", "v", "lat", "lon", "h"], n, h, tmp,
                  "seed 001 run, outputs")
        if args.steps_only:
            return
        print(f"2. vehicle + gfnav_qin9 co-simulation, {args.seconds:g} s at 100 Hz ({n} steps):")
        system = vehicle_navigation("gfnav_qin9", prof, stop_s=args.seconds)
        for version in (2, 3):
            with CoSimulation(system, fmi_version=version) as m:
                m.initialize()
                t0 = time.perf_counter()
                if args.profile and version == 2:
                    pr = cProfile.Profile()
                    pr.enable()
                    m.run()
                    pr.disable()
                else:
                    m.run()
                dt = time.perf_counter() - t0
            print(f"  Python master (fmpy FMU{version}Slave)  {dt:7.2f} s  {dt / n * 1e6:6.1f} us/step")
        ssp_sys = vehicle_navigation("gfnav_qin9", prof, stop_s=args.seconds, skip_steps=1)
        ssp = write_ssp(ssp_sys, tmp / "vn.ssp")
        t0 = time.perf_counter()
        run_ssp(ssp, args.seconds, h)
        dt = time.perf_counter() - t0
        print(f"  fmpy SSP simulator (FMI 2.0)      {dt:7.2f} s  {dt / n * 1e6:6.1f} us/step")
        cont = write_container(ssp_sys, tmp / "vn.fmu", fmi_version=2)
        t0 = time.perf_counter()
        run_container(cont, args.seconds, h)
        dt = time.perf_counter() - t0
        print(f"  fmpy container FMU (FMI 2.0)      {dt:7.2f} s  {dt / n * 1e6:6.1f} us/step")
        from gfins_fmi.fmi import osp
        if osp.available() is None:     # OSP libcosim: wall and CPU (its steps run on threads)
            for label, outputs in (("recording", system.outputs), ("no outputs", {})):
                run_sys = System(system.components, system.connections, outputs,
                                       system.step_s, system.stop_s)
                c0, t0 = time.process_time(), time.perf_counter()
                osp.run_libcosim(run_sys)
                dt, cpu = time.perf_counter() - t0, time.process_time() - c0
                print(f"  OSP libcosim, {label:11s}       {dt:7.2f} s  {dt / n * 1e6:6.1f} us/step "
                      f"(CPU {cpu:.2f} s)")
        else:
            print(f"  OSP libcosim: {osp.available()}")
        if args.profile:
            print("where the Python master's time goes (cProfile, FMI 2.0, top 12 by own time):")
            pstats.Stats(pr).sort_stats("tottime").print_stats(12)


if __name__ == "__main__":
    main()
