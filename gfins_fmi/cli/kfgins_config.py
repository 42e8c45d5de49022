"""``gfins integrate --kfgins-config their.yaml``: a KF-GINS configuration file read as it
is (i2Nav-WHU/KF-GINS, ``dataset/kf-gins.yaml`` and ``loadConfig`` in ``src/kf_gins.cpp``)
and KF-GINS's three output files written in its format, so a KF-GINS user's files and
plotting scripts work unchanged.

Keys read (KF-GINS's frames and units, converted here to ours: body right-front-up,
navigation east-north-up, :mod:`gfins_fmi.io.conventions`): ``imupath``, ``gnsspath``,
``outputpath`` (relative paths from the current folder, as KF-GINS), ``imudatalen``,
``imudatarate``, ``starttime``, ``endtime`` (-1: the record's end), ``initpos`` (deg, deg,
m), ``initvel`` (north, east, down m/s), ``initatt`` (roll, pitch, yaw deg), ``initgyrbias``
(deg/h), ``initaccbias`` (mGal), ``initgyrscale``/``initaccscale`` (ppm; IMU forward,
right, down), ``initposstd``/``initvelstd`` (north, east, down), ``initattstd`` (roll,
pitch, yaw deg), ``initbgstd``/``initbastd``/``initsgstd``/``initsastd`` (default: the
noise block's), ``imunoise`` (``arw`` deg/sqrt(h), ``vrw`` m/s/sqrt(h), ``gbstd`` deg/h,
``abstd`` mGal, ``gsstd``/``asstd`` ppm, ``corrtime`` h), ``antlever`` (forward, right,
down m). KF-GINS estimates the scale factors: so does the run (21 states).

Where the filter differs from KF-GINS the reading says so: ``imunoise``'s six noise values
are per axis in KF-GINS and one per sensor triad here (the settings table, the C filter,
the FMU): the largest axis is used, with a warning naming the key, the three values and
the one used when they differ; the initial biases, scale factors and their 1-sigma stay
per axis. ``initattstd``'s roll and pitch become one tilt 1-sigma about east and north
(the larger) and ``imudatarate`` is not needed (the time column gives the interval): both
stated in :attr:`KfginsRun.notes`. A key that is not KF-GINS's (a fork's odometer noise or
lever arm, a misspelt key) is named in a warning, never ignored silently.

Outputs in ``outputpath`` (KF-GINS's names and columns, its ``%-15.9lf`` numbers as
``%.9f`` with one space between): ``KF_GINS_Navresult.nav`` (week 0, time, lat, lon deg,
h m, velocity north, east, down m/s, roll, pitch, yaw deg), ``KF_GINS_IMU_ERR.txt`` (time,
gyro bias deg/h, accelerometer bias mGal, gyro and accelerometer scale ppm, forward, right,
down axes), ``KF_GINS_STD.txt`` (time, 1-sigma of position m and velocity m/s north, east, down,
attitude north, east, down deg, gyro bias deg/h, accelerometer bias mGal, gyro and
accelerometer scale ppm, forward, right, down: KF-GINS's ``writeSTD``), and
``KF_GINS.config.json``, what the run used.
"""
from __future__ import annotations

import dataclasses
import math
import pathlib
import warnings

import numpy as np
import yaml

from gfins_fmi.estimation.config import UG, InitialState
from gfins_fmi.io.conventions import frd_to_rfu, ned_to_enu, rpy_frd_ned_to_euler_rfu_enu
from gfins_fmi.nav.earth import deg
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.nav.strapdown import NavState, euler_to_quat

__all__ = ["kfgins_config_text", "kfgins_noise_block", "KfginsRun", "KFGINS_KEYS", "KFGINS_NOISE_KEYS", "read_kfgins_config", "initial_state", "kfgins_outputs", "write_kfgins_outputs",
           "kfgins_tables", "open_kfgins_writers", "KFGINS_DECIMALS", "KFGINS_TEXT", "KFGINS_COLUMNS"]

#: KF-GINS's text numbers: ``%-15.9lf`` (src/fileio/filesaver.cc)
KFGINS_DECIMALS = 9
MGAL = 1e-5         #: m/s^2
DEG_H = deg / 3600.0

#: the output files in ``outputpath``
NAV_FILE, IMU_ERR_FILE, STD_FILE, CONFIG_FILE = ("KF_GINS_Navresult.nav", "KF_GINS_IMU_ERR.txt", "KF_GINS_STD.txt",
                                                  "KF_GINS.config.json")


@dataclasses.dataclass
class KfginsRun:
    """What a KF-GINS configuration file asks for, in our frames and units."""
    imu: pathlib.Path
    gnss: pathlib.Path
    output: pathlib.Path
    imu_columns: int
    start_s: float
    end_s: float | None
    noise: ImuNoise
    scale_std: tuple          # gyro, accelerometer Gauss-Markov std (dimensionless)
    correlation_s: float
    lever_arm_m: tuple        # right, front, up
    nav0: tuple               # lat rad, lon rad, h m, v ENU, euler (heading, pitch, roll) rad
    position_std_m: tuple     # E, N, U
    velocity_std_m_s: tuple
    attitude_std_rad: tuple   # tilt E, tilt N, heading
    sensors0: np.ndarray      # SENSOR_NAMES order, the first 12
    sensor_std: dict          # InitialState's bias/scale stds (RFU)
    notes: list = dataclasses.field(default_factory=list)   # keys that map differently, stated


def _vec(doc, key, path, n=3, default=None):
    v = doc.get(key, default)
    if v is None:
        raise ValueError(f"{path}: '{key}' is missing (KF-GINS's configuration needs it)")
    try:
        out = [float(x) for x in (v if isinstance(v, (list, tuple)) else [v])]
    except (TypeError, ValueError):
        raise ValueError(f"{path}: '{key}' must be {n} numbers; got {v!r}") from None
    if len(out) != n or not all(math.isfinite(x) for x in out):
        raise ValueError(f"{path}: '{key}' must be {n} finite numbers; got {v!r}")
    return out


def _swap(v):
    """Magnitudes per axis, forward-right-down -> right-front-up (x and y swap)."""
    return (abs(v[1]), abs(v[0]), abs(v[2]))


#: every key of KF-GINS's configuration (dataset/kf-gins.yaml, loadConfig in src/kf_gins.cpp)
KFGINS_KEYS = ("imupath", "gnsspath", "outputpath", "imudatalen", "imudatarate", "starttime", "endtime", "initpos",
               "initvel", "initatt", "initgyrbias", "initaccbias", "initgyrscale", "initaccscale", "initposstd",
               "initvelstd", "initattstd", "initbgstd", "initbastd", "initsgstd", "initsastd", "imunoise", "antlever")
#: the keys of its ``imunoise`` block, with their units
KFGINS_NOISE_KEYS = {"arw": "deg/sqrt(h)", "vrw": "m/s/sqrt(h)", "gbstd": "deg/h", "abstd": "mGal", "gsstd": "ppm",
                     "asstd": "ppm", "corrtime": "h"}


def _unused_keys(doc: dict, noise: dict, path) -> None:
    """A warning naming the keys this reading does not use (a KF-GINS fork's odometer
    settings, a misspelt key): nothing is ignored silently."""
    unused = [k for k in doc if k not in KFGINS_KEYS]
    unused += [f"imunoise.{k}" for k in noise if k not in KFGINS_NOISE_KEYS]
    if not unused:
        return
    odo = [k for k in unused if "odo" in k.lower()]
    hint = (f"; for an odometer ({', '.join(odo)}): give its record with --odometer ODO.csv "
            "(OdometerRecord: t_s, speed_m_s, std_m_s) and --odometer-mount / --nhc" if odo else "")
    warnings.warn(f"{path}: not KF-GINS keys, not used by this run: {', '.join(unused)} (KF-GINS's keys: "
                  f"{', '.join(KFGINS_KEYS)}; imunoise: {', '.join(KFGINS_NOISE_KEYS)}){hint}",
                  UserWarning, stacklevel=3)


def _one_per_triad(key: str, v: list, path) -> float:
    """The one value per sensor triad the filter takes (FilterConfig's noise): the
    largest of KF-GINS's three axes, with a warning when they differ."""
    top = max(v)
    if min(v) != top:
        unit = KFGINS_NOISE_KEYS[key]
        warnings.warn(f"{path}: imunoise.{key} differs between the axes ({', '.join(f'{x:g}' for x in v)} {unit}, "
                      f"forward, right, down); the filter takes one value per sensor triad: it uses the "
                      f"largest, {top:g} {unit}, on every axis", UserWarning, stacklevel=3)
    return top


def read_kfgins_config(path) -> KfginsRun:
    """Read a KF-GINS YAML configuration file (the keys of the module's docstring).

    Warns (UserWarning) naming a key that is not KF-GINS's (not used by the run) and an
    ``imunoise`` value whose three axes differ (the filter has one per triad: the
    largest is used); :attr:`KfginsRun.notes` states the keys that map differently.

    Raises
    ------
    ValueError
        The file is missing, not YAML, or a key is missing or malformed (named).
    """
    path = pathlib.Path(path)
    try:
        doc = yaml.safe_load(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ValueError(f"--kfgins-config {path}: no such file") from None
    except yaml.YAMLError as exc:
        raise ValueError(f"--kfgins-config {path}: not YAML ({exc})") from None
    if not isinstance(doc, dict):
        raise ValueError(f"--kfgins-config {path}: not a KF-GINS configuration (a mapping of keys)")
    for key in ("imupath", "gnsspath", "outputpath"):
        if not doc.get(key):
            raise ValueError(f"{path}: '{key}' is missing")
    noise = doc.get("imunoise") or {}
    if not isinstance(noise, dict):
        raise ValueError(f"{path}: 'imunoise' must be a block of arw, vrw, gbstd, abstd, gsstd, asstd, corrtime")
    _unused_keys(doc, noise, path)
    arw, vrw, gb, ab, gs, as_ = (_vec(noise, k, f"{path}: imunoise") for k in
                                 ("arw", "vrw", "gbstd", "abstd", "gsstd", "asstd"))
    corr_h = float(noise.get("corrtime", float("nan")))
    if not corr_h > 0:
        raise ValueError(f"{path}: imunoise.corrtime must be > 0 h; got {noise.get('corrtime')!r}")
    tau = corr_h * 3600.0
    # ImuNoise is one number per triad: the largest axis, warned of when they differ
    top = {k: _one_per_triad(k, v, path) for k, v in
           (("arw", arw), ("vrw", vrw), ("gbstd", gb), ("abstd", ab), ("gsstd", gs), ("asstd", as_))}
    imu = ImuNoise(gyro_arw_deg_sqrt_h=top["arw"], accel_vrw_ug_sqrt_hz=top["vrw"] * math.sqrt(2.0) / 60.0 / UG,
                   gyro_bias_instability_deg_h=top["gbstd"], accel_bias_instability_ug=top["abstd"] * MGAL / UG,
                   gyro_correlation_time_s=tau, accel_correlation_time_s=tau)
    pos, vel, att = _vec(doc, "initpos", path), _vec(doc, "initvel", path), _vec(doc, "initatt", path)
    euler = rpy_frd_ned_to_euler_rfu_enu(np.array([att[0] * deg]), np.array([att[1] * deg]),
                                         np.array([att[2] * deg]))[0]
    nav0 = (pos[0] * deg, pos[1] * deg, pos[2], tuple(ned_to_enu(np.array([vel]))[0]), tuple(euler))
    pstd, vstd, astd = (_vec(doc, k, path) for k in ("initposstd", "initvelstd", "initattstd"))
    tilt = max(astd[0], astd[1]) * deg
    z3 = [0.0, 0.0, 0.0]
    bg0, ba0, sg0, sa0 = (_vec(doc, k, path, default=z3) for k in
                          ("initgyrbias", "initaccbias", "initgyrscale", "initaccscale"))
    sensors0 = np.r_[frd_to_rfu(np.array([bg0]))[0] * DEG_H, frd_to_rfu(np.array([ba0]))[0] * MGAL,
                     [sg0[1] * 1e-6, sg0[0] * 1e-6, sg0[2] * 1e-6],
                     [sa0[1] * 1e-6, sa0[0] * 1e-6, sa0[2] * 1e-6]]
    bgs, bas, sgs, sas = (_vec(doc, k, path, default=d) for k, d in
                          (("initbgstd", gb), ("initbastd", ab), ("initsgstd", gs), ("initsastd", as_)))
    # the initial 1-sigma is per axis in the filter too (gf_ins_initial_std)
    sensor_std = {"gyro_bias_std_rad_s": tuple(x * DEG_H for x in _swap(bgs)),
                  "accel_bias_std_m_s2": tuple(x * MGAL for x in _swap(bas)),
                  "gyro_scale_std": tuple(x * 1e-6 for x in _swap(sgs)),
                  "accel_scale_std": tuple(x * 1e-6 for x in _swap(sas))}
    lever = _vec(doc, "antlever", path)
    end = float(doc.get("endtime", -1))
    notes = [f"initattstd roll {astd[0]:g}, pitch {astd[1]:g} deg -> the tilt 1-sigma about east and north "
             f"{max(astd[0], astd[1]):g} deg each (the larger: our attitude error is a tilt about east and "
             f"north, not roll and pitch); yaw {astd[2]:g} deg -> the heading 1-sigma"]
    if "imudatarate" in doc:
        notes.append(f"imudatarate {doc['imudatarate']} Hz: not needed, the sample interval comes from the "
                     "IMU file's time column")
    return KfginsRun(imu=pathlib.Path(doc["imupath"]), gnss=pathlib.Path(doc["gnsspath"]),
                     output=pathlib.Path(doc["outputpath"]), imu_columns=int(doc.get("imudatalen", 7)),
                     start_s=float(doc.get("starttime", 0.0)), end_s=None if end < 0 else end,
                     noise=imu, scale_std=(top["gsstd"] * 1e-6, top["asstd"] * 1e-6), correlation_s=tau,
                     lever_arm_m=(lever[1], lever[0], -lever[2]), nav0=nav0,
                     position_std_m=(pstd[1], pstd[0], pstd[2]), velocity_std_m_s=(vstd[1], vstd[0], vstd[2]),
                     attitude_std_rad=(tilt, tilt, astd[2] * deg), sensors0=sensors0, sensor_std=sensor_std,
                     notes=notes)


def initial_state(run: KfginsRun, t_s: float, n_sensors: int) -> InitialState:
    """The filter's start of a KF-GINS configuration at time ``t_s``."""
    lat, lon, h, v, e = run.nav0
    sensors = np.zeros(n_sensors)
    sensors[:12] = run.sensors0
    nav = NavState(euler_to_quat(np.asarray(e)), np.asarray(v, float), lat, lon, h, t_s)
    return InitialState(nav, position_std_m=run.position_std_m, velocity_std_m_s=run.velocity_std_m_s,
                        attitude_std_rad=run.attitude_std_rad, sensors=sensors, **run.sensor_std)


def kfgins_outputs(folder) -> dict:
    """The files a KF-GINS run writes in ``folder``, by kind."""
    folder = pathlib.Path(folder)
    return {"nav": folder / NAV_FILE, "imu_err": folder / IMU_ERR_FILE, "std": folder / STD_FILE,
            "config": folder / CONFIG_FILE}


def _yaw_deg(heading_rad):
    """KF-GINS's yaw, in (-180, 180] deg."""
    y = np.degrees(heading_rad) % 360.0
    return np.where(y > 180.0, y - 360.0, y)


#: the writers' keywords of KF-GINS's text files (TableWriter)
KFGINS_TEXT = {"decimals": KFGINS_DECIMALS, "separator": " ", "header": False}
#: the columns of each output file (KF-GINS writes no header: names for our writer only)
KFGINS_COLUMNS = {"nav": 11, "imu_err": 13, "std": 22}


def kfgins_nav_columns(sol) -> list:
    """The rows of ``sol`` as KF_GINS_Navresult.nav's columns: week 0, time, lat, lon deg,
    h m, velocity N, E, D m/s, roll, pitch, yaw deg."""
    e = sol.euler_rad
    v = ned_to_enu(sol.v_n_m_s)                       # (N, E, D) from (E, N, U): the same swap
    return [np.zeros(len(sol)), sol.t_s, np.degrees(sol.lat_rad), np.degrees(sol.lon_rad), sol.h_m,
            v[:, 0], v[:, 1], v[:, 2], np.degrees(e[:, 2]), np.degrees(e[:, 1]), _yaw_deg(e[:, 0])]


def kfgins_tables(sol) -> dict:
    """The rows of ``sol`` as KF-GINS's three files' columns, by kind."""
    nav = kfgins_nav_columns(sol)
    s = sol.sensors
    bg, ba = frd_to_rfu(s[:, 0:3]) / DEG_H, frd_to_rfu(s[:, 3:6]) / MGAL   # RFU -> FRD: the same swap, z negated
    sg, sa = s[:, [7, 6, 8]] * 1e6, s[:, [10, 9, 11]] * 1e6
    err = [sol.t_s, *bg.T, *ba.T, *sg.T, *sa.T]
    st = sol.std
    std = [sol.t_s, st[:, 4], st[:, 3], st[:, 5], st[:, 1], st[:, 0], st[:, 2],
           *(np.degrees(st[:, i]) for i in (7, 6, 8)), *_sensor_std(sol)]
    return {"nav": nav, "imu_err": err, "std": std}


#: KF-GINS's sensor-error blocks in its std file (src/kf_gins.cpp writeSTD): our layout's
#: block, the factor from SI to its unit (deg/h, mGal, ppm, ppm)
_STD_BLOCKS = (("idx_bg", 1.0 / DEG_H), ("idx_ba", 1.0 / MGAL), ("idx_sg", 1e6), ("idx_sa", 1e6))


def _sensor_std(sol) -> list:
    """The 12 sensor-error 1-sigma columns of KF_GINS_STD.txt from the solution's
    ``state_std`` (the filter's 1-sigma of every error state): gyro bias deg/h,
    accelerometer bias mGal, gyro and accelerometer scale ppm, each forward, right, down
    (our right, front, up: y, x, z; a 1-sigma has no sign)."""
    if sol.state_std is None:
        raise ValueError("KF_GINS_STD.txt needs the 1-sigma of every error state: run the filter with "
                         "state_std=True")
    lay = sol.config.layout()
    cols = []
    for block, factor in _STD_BLOCKS:
        i = int(getattr(lay, block))
        if i < 0:
            raise ValueError(f"KF_GINS_STD.txt needs the {block[4:]} states (the KF-GINS run estimates biases and "
                             "scale factors: scale_factors=True)")
        cols += [sol.state_std[:, i + 1] * factor, sol.state_std[:, i] * factor, sol.state_std[:, i + 2] * factor]
    return cols


def open_kfgins_writers(outs, files: dict) -> dict:
    """TableWriters of the run's output set for KF-GINS's three files, by kind."""
    return {k: outs.table(files[k], [f"c{i}" for i in range(n)], **KFGINS_TEXT) for k, n in KFGINS_COLUMNS.items()}


def write_kfgins_outputs(outs, files: dict, sol) -> None:
    """The solution as KF-GINS's three text files, through the run's output set."""
    for k, cols in kfgins_tables(sol).items():
        outs.write_table(files[k], [f"c{i}" for i in range(KFGINS_COLUMNS[k])], cols, **KFGINS_TEXT)


def kfgins_noise_block(noise: ImuNoise, scale_ppm: float = 300.0) -> dict:
    """``imunoise`` in KF-GINS's units from an :class:`ImuNoise` (the same value on the three
    axes): ``arw`` deg/sqrt(h), ``vrw`` m/s/sqrt(h) (the Allan VRW: the one-sided density
    / sqrt(2)), ``gbstd`` deg/h, ``abstd`` mGal, ``gsstd``/``asstd`` ppm, ``corrtime`` h (the
    gyro's correlation time)."""
    vrw = float(noise.accel_vrw_ug_sqrt_hz * UG / math.sqrt(2.0) * 60.0)
    ab = float(noise.accel_bias_instability_ug * UG / MGAL)
    return {"arw": [float(noise.gyro_arw_deg_sqrt_h)] * 3, "vrw": [vrw] * 3,
            "gbstd": [float(noise.gyro_bias_instability_deg_h)] * 3, "abstd": [ab] * 3,
            "gsstd": [float(scale_ppm)] * 3, "asstd": [float(scale_ppm)] * 3,
            "corrtime": float(noise.gyro_correlation_time_s) / 3600.0}


def _yaml_vec(v) -> str:
    return "[ " + ", ".join(repr(float(x)) for x in v) + " ]"


def kfgins_config_text(imu, gnss, output, start_s: float, lat_rad: float, lon_rad: float, h_m: float,
                       v_enu_m_s, euler_rad, lever_arm_m, noise: dict, *,
                       position_std_m=(0.005, 0.004, 0.008), velocity_std_m_s=(0.003, 0.004, 0.004),
                       attitude_std_deg=(0.003, 0.003, 0.023), sensor_std: dict | None = None,
                       extra: str = "") -> str:
    """A KF-GINS configuration file (the inverse of :func:`read_kfgins_config`): paths, the
    start time (s), the initial state in our frames and units (position rad, rad, m;
    velocity east, north, up m/s; heading, pitch, roll rad; lever arm right, front, up m)
    written in KF-GINS's (north-east-down velocity, roll-pitch-yaw deg, antenna lever arm
    forward-right-down), ``noise`` in KF-GINS's keys and units (:func:`kfgins_noise_block`),
    the initial 1-sigma as KF-GINS types them (position and velocity north, east, down;
    attitude roll, pitch, yaw deg), ``sensor_std`` any of ``initbgstd``, ``initbastd``,
    ``initsgstd``, ``initsastd`` (KF-GINS's units, forward-right-down), ``extra`` lines
    appended as they are."""
    v_ned = ned_to_enu(np.array([v_enu_m_s], dtype=float))[0]     # the same swap both ways
    e = [math.degrees(float(x)) for x in euler_rad]
    arm_frd = frd_to_rfu(np.array([lever_arm_m], dtype=float))[0]   # likewise
    lines = [f'imupath: "{imu}"', f'gnsspath: "{gnss}"', f'outputpath: "{output}"', "imudatalen: 7",
             "imudatarate: 200", f"starttime: {float(start_s)!r}", "endtime: -1",
             f"initpos: {_yaml_vec([math.degrees(lat_rad), math.degrees(lon_rad), h_m])}",
             f"initvel: {_yaml_vec(v_ned)}", f"initatt: {_yaml_vec([e[2], e[1], e[0]])}",
             "initgyrbias: [ 0, 0, 0 ]", "initaccbias: [ 0, 0, 0 ]", "initgyrscale: [ 0, 0, 0 ]",
             "initaccscale: [ 0, 0, 0 ]", f"initposstd: {_yaml_vec(position_std_m)}",
             f"initvelstd: {_yaml_vec(velocity_std_m_s)}", f"initattstd: {_yaml_vec(attitude_std_deg)}"]
    lines += [f"{key}: {_yaml_vec(x)}" for key, x in (sensor_std or {}).items()]
    lines.append("imunoise:")
    lines += [f"  {key}: {_yaml_vec(x) if key != 'corrtime' else repr(float(x))}" for key, x in noise.items()]
    lines.append(f"antlever: {_yaml_vec(arm_frd)}")
    return "\n".join(lines) + "\n" + extra

