"""Transfer-alignment scenarios (issue 24): a host vehicle carrying a master INS and a
slave IMU, simulated from the vehicle and the rotating platform of the C core
(``gf_vehicle`` + ``gf_rot``, the code of the vehicle FMU, through
:func:`gfins_fmi.sim.rotation.simulate_on_vehicle`).

The host: a vehicle on a straight road (:class:`~gfins_fmi.sim.vehicle.VehicleProfile`)
whose instrument platform rolls (a :class:`~gfins_fmi.sim.rotation.RotationSchedule` of
turns about the base's forward axis y: :func:`roll_manoeuvre`); the master IMU sits at
the platform's centre, so its frame m is the rotating frame of ``simulate_on_vehicle``.
The master INS is a free-inertial strapdown run (:class:`~gfins_fmi.nav.strapdown.
Strapdown`) on that IMU with a navigation-grade :class:`~gfins_fmi.nav.imu_errors.ImuNoise`
and an initial attitude error: its outputs (attitude, velocity, position, angular rate)
carry its own, physically consistent errors. The slave IMU (:class:`SlaveInstallation`)
sits at the lever arm r from the master (master axes), its axes turned by the mounting
C_s^m = M(a) (heading, pitch, roll; gf_sins.h's Euler convention) plus an optional
structural flexure (second-order Gauss-Markov angles added to a), and its samples are
stamped ``time_offset_s`` later than the master's clock says.

The slave's increments come from the platform simulated on a finer grid (``substeps``
per slave sample): on each fine step dtheta_s = M^T dtheta_m + log(M_(i-1)^T M_i) (the
slave's turn relative to the master), dv_s = M^T [dv_m + (w_i - w_(i-1)) x r +
int w x (w x r) dt] (a point fixed in the body: f_P = f_O + w' x r + w x (w x r), the
centripetal integral by the trapezoidal rule: its error dt_f^3 / 12 of the third
derivative, below 1e-12 m/s per fine step here; the gravity gradient over r, 3e-7
m/s^2 per metre, left out); fine steps add up exactly (an increment is an integral).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gfins_fmi._lib import as_scalar
from gfins_fmi.io.records import ImuRecord, TruthRecord
from gfins_fmi.nav.earth import WGS84, euler_to_quat, quat_multiply, quat_to_dcm, radii
from gfins_fmi.nav.imu_errors import DEG_H, ImuNoise
from gfins_fmi.nav.strapdown import NavState, SinsConfig, Strapdown, quat_to_euler
from gfins_fmi.sim.rotation import RotationSchedule, Turn, rest, simulate_on_vehicle
from gfins_fmi.sim.scenarios import NAVIGATION
from gfins_fmi.sim.vehicle import VehicleProfile

__all__ = ["SlaveInstallation", "TransferScenario", "roll_manoeuvre", "straight_road",
           "simulate_transfer", "mount_matrix", "FLEX_BETA_TAU", "MEMS_SLAVE"]

_DEG = np.pi / 180.0
_MG = 9.80665e-3
#: the flexure's b = FLEX_BETA_TAU / tau (gf_ins_gnss.h; Kain & Cloutier 1989)
FLEX_BETA_TAU = 2.146
#: the slave's white noise (a consumer MEMS IMU: ARW 0.3 deg/sqrt(h), 100 ug/sqrt(Hz));
#: its biases are random constants drawn per run (simulate_transfer)
MEMS_SLAVE = ImuNoise(gyro_arw_deg_sqrt_h=0.3, accel_vrw_ug_sqrt_hz=100.0)


@dataclass(frozen=True)
class SlaveInstallation:
    """How the slave IMU sits on the host, relative to the master IMU.

    Attributes
    ----------
    mount_rad : (heading, pitch, roll) of the slave's axes in the master's, rad
        (C_s^m = Rz(-heading) Rx(pitch) Ry(roll)).
    lever_arm_m : the slave IMU from the master IMU, master axes right, front, up, m.
    time_offset_s : slave stamp - master stamp of one instant, s (a multiple of the fine
        step dt_s / substeps of :func:`simulate_transfer`).
    flexure_std_rad, flexure_tau_s : structural flexure added to the mounting angles, a
        second-order Gauss-Markov process per axis (f'' + 2 b f' + b^2 f = w, b = 2.146 /
        tau, stationary std sigma); std 0: a rigid mount.
    """
    mount_rad: tuple = (0.0, 0.0, 0.0)
    lever_arm_m: tuple = (0.0, 0.0, 0.0)
    time_offset_s: float = 0.0
    flexure_std_rad: float = 0.0
    flexure_tau_s: float = 1.0


@dataclass
class TransferScenario:
    """A simulated transfer alignment: the records a user would have and the truth.

    Attributes
    ----------
    slave_imu : ImuRecord of the slave's increments, stamped by the slave's clock.
    master : TruthRecord of the master INS's outputs (its errors included) at its rate,
        stamped by its clock (the true time).
    master_rate_rad_s : (m, 3) the master's angular rate w_im^m at those epochs (its gyros,
        errors included), master axes.
    truth : TruthRecord of the slave's true state at the start of its record (the first
        interval's start) and at its stamps (each row the instant the stamp describes:
        true time = stamp - time offset).
    master_truth : TruthRecord of the master's true state at the master's epochs.
    slave_gyro_bias_rad_s, slave_accel_bias_m_s2 : (3,) the slave's constant biases.
    flexure_rad : (n + 1, 3) the true flexure angles at the rows of ``truth`` (zeros if rigid).
    installation : SlaveInstallation.
    """
    slave_imu: ImuRecord
    master: TruthRecord
    master_rate_rad_s: np.ndarray
    truth: TruthRecord
    master_truth: TruthRecord
    slave_gyro_bias_rad_s: np.ndarray
    slave_accel_bias_m_s2: np.ndarray
    flexure_rad: np.ndarray
    installation: SlaveInstallation
    info: dict = field(default_factory=dict)


def roll_manoeuvre(amplitude_deg: float = 30.0, rate_deg_s: float = 30.0, ramp_s: float = 1.0,
                   dwell_s: float = 0.5, lead_s: float = 0.0) -> RotationSchedule:
    """A repeated roll of the platform about the host's forward axis (base y): +a, then
    -2a, then back to level (a = ``amplitude_deg``), each turn at ``rate_deg_s`` with
    smooth ramps of ``ramp_s``, ``dwell_s`` at each end, after ``lead_s`` level."""
    a = as_scalar("amplitude_deg", amplitude_deg, "deg", above=0.0, at_most=90.0)
    cycle = [Turn("y", a, None, 0.0, rate_deg_s, ramp_s, dwell_s),
             Turn("y", -2 * a, None, 0.0, rate_deg_s, ramp_s, dwell_s),
             Turn("y", a, None, 0.0, rate_deg_s, ramp_s, dwell_s)]
    if lead_s > 0:
        cycle = [rest(lead_s)] + cycle
    return RotationSchedule(cycle, repeat=True)


def straight_road(speed_m_s: float = 10.0, heading_deg: float = 30.0, **start) -> VehicleProfile:
    """A vehicle cruising on a straight road (no segment: constant speed and heading)."""
    return VehicleProfile(speed0_m_s=speed_m_s, heading0_rad=heading_deg * _DEG, segments=[],
                          **start)


def mount_matrix(angles_rad) -> np.ndarray:
    """C_s^m of mounting angles (heading, pitch, roll), rad: (3, 3), or (n, 3, 3) for (n, 3)."""
    a = np.asarray(angles_rad, float)
    return quat_to_dcm(euler_to_quat(a[..., 0], a[..., 1], a[..., 2]))


def _rotvec_of(R: np.ndarray) -> np.ndarray:
    """Rotation vectors of (n, 3, 3) small rotations (angle < pi/2), via the quaternion."""
    tr = np.trace(R, axis1=1, axis2=2)
    w = 0.5 * np.sqrt(np.maximum(1.0 + tr, 0.0))
    v = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], 1) / (4 * w[:, None])
    s = np.linalg.norm(v, axis=1)
    k = np.where(s > 1e-12, 2.0 * np.arctan2(s, w) / np.maximum(s, 1e-300), 2.0 / w)
    return v * k[:, None]


def _flexure(n: int, dt_s: float, std: float, tau: float, rng) -> np.ndarray:
    """(n + 1, 3) samples of the second-order Markov flexure started in steady state: the
    exact discretisation (the matrix exponential and its noise integral, Van Loan)."""
    if std <= 0:
        return np.zeros((n + 1, 3))
    from scipy.linalg import expm   # lazy: scipy's linalg (~0.2 s) only with a flexure
    b = FLEX_BETA_TAU / tau
    F = np.array([[0.0, 1.0], [-b * b, -2.0 * b]])
    Q = np.array([[0.0, 0.0], [0.0, 4.0 * b ** 3 * std ** 2]])
    V = expm(np.block([[-F, Q], [np.zeros((2, 2)), F.T]]) * dt_s)
    Phi = V[2:, 2:].T
    Qd = Phi @ V[:2, 2:]
    L = np.linalg.cholesky(Qd + 1e-30 * np.eye(2))
    P0 = np.diag([std ** 2, (b * std) ** 2])
    x = np.linalg.cholesky(P0) @ rng.standard_normal((2, 3))
    out = np.empty((n + 1, 3))
    out[0] = x[0]
    w = rng.standard_normal((n, 2, 3))
    for i in range(n):          # a recursion: each sample needs the previous one
        x = Phi @ x + L @ w[i]
        out[i + 1] = x[0]
    return out


def simulate_transfer(duration_s: float = 100.0, dt_s: float = 0.01, *,
                      installation: SlaveInstallation = SlaveInstallation(),
                      profile: VehicleProfile | None = None,
                      schedule: RotationSchedule | None = None,
                      slave_noise: ImuNoise = MEMS_SLAVE,
                      slave_gyro_bias_std_rad_s: float = 200.0 * DEG_H,
                      slave_accel_bias_std_m_s2: float = 3.0 * _MG,
                      master_noise: ImuNoise = NAVIGATION,
                      master_attitude_std_rad=(5e-6, 5e-6, 3e-4),
                      master_rate_hz: float = 10.0, substeps: int = 10,
                      master_model: str = "ins", master_white=(0.01, 1e-5, 0.5),
                      baro_std_m: float = 0.5, seed: int = 0, host=None) -> TransferScenario:
    """Simulate a slave IMU beside a master INS on a rolling host (module docstring).

    Parameters
    ----------
    duration_s, dt_s : the slave record's length and sampling interval (s); the master
        IMU runs at the same interval.
    installation : the slave's mounting, lever arm, time offset and flexure.
    profile : the host vehicle (default :func:`straight_road`: 10 m/s, heading 30 deg).
    schedule : the platform's turns (default :func:`roll_manoeuvre`: +-30 deg).
    slave_noise : the slave's white noise (its bias instability is not used).
    slave_gyro_bias_std_rad_s, slave_accel_bias_std_m_s2 : std of the slave's constant
        biases, drawn per run (defaults 200 deg/h, 3 mg: a consumer MEMS IMU).
    master_noise : the master IMU (default navigation grade).
    master_attitude_std_rad : std of the master INS's initial attitude error (east, north
        tilt, heading; n frame), drawn per run (defaults 1", 1", 1').
    master_rate_hz : the master's output rate (its epochs at multiples of 1 / rate).
    substeps : fine steps per slave sample of the platform simulation.
    seed : the random draws (slave biases and noise, master noise and attitude error,
        flexure).
    master_model : "ins": the master is a strapdown INS on its IMU (free inertial
        horizontally, its vertical channel damped by a barometer of white noise
        ``baro_std_m`` per sample through the third-order loop of gf_sins: what a land
        vehicle's master has), its errors those of its sensors and its start; "white": the
        master's outputs are its truth plus white noise of the stds ``master_white`` =
        (velocity m/s, attitude rad about the n frame's axes, position m; each one value or
        east, north, up) and its rate its gyros' — the errors the slave filter models, for
        consistency checks.
    host : the platform simulation of an earlier call with the same duration, dt_s,
        substeps, time offset, profile and schedule (``scenario.info["host"]``): Monte
        Carlo runs share it, only the errors change.

    """
    dur = as_scalar("duration_s", duration_s, "s", above=0.0)
    dt = as_scalar("dt_s", dt_s, "s", above=0.0, at_most=0.1)
    if not isinstance(substeps, (int, np.integer)) or substeps < 1:
        raise ValueError(f"substeps must be an integer >= 1; got {substeps!r}")
    inst = installation
    dtf = dt / substeps
    tau = float(inst.time_offset_s)
    k_tau = int(round(tau / dtf))
    if abs(k_tau * dtf - tau) > 1e-9:
        raise ValueError(f"installation.time_offset_s = {tau} s must be a multiple of the fine step "
                         f"dt_s / substeps = {dtf} s")
    per_master = int(round(1.0 / (master_rate_hz * dt)))
    if per_master < 1 or abs(per_master * dt * master_rate_hz - 1.0) > 1e-9:
        raise ValueError(f"master_rate_hz = {master_rate_hz} Hz must divide 1 / dt_s = {1 / dt} Hz")
    rng = np.random.default_rng(seed)
    profile = profile or straight_road()
    schedule = schedule or roll_manoeuvre()
    n = int(round(dur / dt))
    # slave stamp t_k = s0 + k dt (k = 1..n) describes the true time t_k - tau; the host is
    # simulated from true time 0 on the fine grid, one slave sample of margin either side
    s0 = dt * (1 + max(0, int(np.ceil(tau / dt - 1e-9))))
    t_end_true = s0 - tau + (n + 1) * dt + 1.0 / master_rate_hz   # the master covers the end
    N = int(round(t_end_true / dtf))
    if host is None:
        host = simulate_on_vehicle(schedule, profile, N * dtf, dtf)
    elif len(host.t_s) != N or abs(host.dt_s - dtf) > 1e-12:
        raise ValueError("host is a platform simulation of another duration or step: simulate it "
                         "again (host=None)")
    veh = host.vehicle
    # fine-grid arrays with index i = true time i dtf (i = 0 .. N); the start from the first
    # sample's values (the platform and the road are at rest or constant there)
    qmn = np.vstack([host.initial.q_bn[None], host.q_mn])
    w = np.vstack([host.w_im_m_rad_s[:1], host.w_im_m_rad_s])
    v_m = np.vstack([host.initial.v_n_m_s[None], veh["v_n_m_s"]])
    lat = np.r_[host.initial.lat_rad, veh["lat_rad"]]
    lon = np.r_[host.initial.lon_rad, veh["lon_rad"]]
    h = np.r_[host.initial.h_m, veh["h_m"]]
    r = np.asarray(inst.lever_arm_m, float)
    a0 = np.asarray(inst.mount_rad, float)
    flex = _flexure(N, dtf, float(inst.flexure_std_rad), float(inst.flexure_tau_s), rng)
    q_sm = euler_to_quat(*(a0[None, :] + flex).T)               # C_s^m at every fine point
    M = quat_to_dcm(q_sm)
    # fine slave increments (interval i: true time (i - 1) dtf .. i dtf, i = 1..N)
    Mmid = mount_matrix(a0[None, :] + 0.5 * (flex[1:] + flex[:-1]))
    rel = _rotvec_of(np.einsum("nji,njk->nik", M[:-1], M[1:]))   # log(M_(i-1)^T M_i)
    dth_f = np.einsum("nji,nj->ni", Mmid, host.dtheta_rad) + rel
    cen = np.cross(w, np.cross(w, r))
    dv_m_f = host.dv_m_s + np.cross(w[1:] - w[:-1], r) + 0.5 * dtf * (cen[1:] + cen[:-1])
    dv_f = np.einsum("nji,nj->ni", Mmid, dv_m_f)
    # slave samples: true interval (t_k - tau - dt, t_k - tau] = fine steps j0+1 .. j0+substeps
    end = np.round((s0 + dt * np.arange(1, n + 1) - tau) / dtf).astype(int)
    csum_th = np.vstack([np.zeros(3), np.cumsum(dth_f, axis=0)])
    csum_dv = np.vstack([np.zeros(3), np.cumsum(dv_f, axis=0)])
    dth_s = csum_th[end] - csum_th[end - substeps]
    dv_s = csum_dv[end] - csum_dv[end - substeps]
    bg = rng.normal(0.0, slave_gyro_bias_std_rad_s, 3)
    ba = rng.normal(0.0, slave_accel_bias_std_m_s2, 3)
    parts = slave_noise.sample_parts(n, dt, rng)
    t_slave = s0 + dt * np.arange(1, n + 1)
    slave_imu = ImuRecord(t_slave, dth_s + (bg + parts["gyro_white"]) * dt,
                          dv_s + (ba + parts["accel_white"]) * dt, "increments",
                          f"simulate_transfer(seed={seed}) slave")
    # the slave's truth at the instants its stamps describe (fine index end)
    RM, RN = radii(lat)[:2]
    C_mn = quat_to_dcm(qmn)
    w_ie = WGS84.omega_ie * np.stack([np.zeros_like(lat), np.cos(lat), np.sin(lat)], 1)
    w_em = w - np.einsum("nji,nj->ni", C_mn, w_ie)
    v_s = v_m + np.einsum("nij,nj->ni", C_mn, np.cross(w_em, r))
    u = np.einsum("nij,j->ni", C_mn, r)                       # lever arm, ENU metres
    lat_s = lat + u[:, 1] / (RM + h)
    lon_s = lon + u[:, 0] / ((RN + h) * np.cos(lat))
    q_s = quat_multiply(qmn, q_sm)                            # C_s^n = C_m^n C_s^m
    at = np.r_[end[0] - substeps, end]                          # the record's start too
    truth = _truth(np.r_[s0, t_slave], lat_s[at], lon_s[at], h[at] + u[at, 2], v_s[at], q_s[at],
                   "simulate_transfer: the slave's truth")
    # the master IMU (the platform at its centre) and its free-inertial INS
    m_end = np.arange(substeps, N + 1, substeps)               # master samples at j dt (true)
    cm_th = np.vstack([np.zeros(3), np.cumsum(host.dtheta_rad, axis=0)])
    cm_dv = np.vstack([np.zeros(3), np.cumsum(host.dv_m_s, axis=0)])
    dth_m = cm_th[m_end] - cm_th[m_end - substeps]
    dv_m = cm_dv[m_end] - cm_dv[m_end - substeps]
    mp = master_noise.sample_parts(len(m_end), dt, rng)
    g_err = mp["gyro_white"] + mp["gyro_bias"] + mp["gyro_band"]
    a_err = mp["accel_white"] + mp["accel_bias"] + mp["accel_band"]
    phi0 = rng.normal(0.0, 1.0, 3) * np.asarray(master_attitude_std_rad, float)
    q0 = quat_multiply(_rotvec_quat(phi0), qmn[0])            # C = exp([phi x]) C_true
    start = NavState(q0, v_m[0].copy(), float(lat[0]), float(lon[0]), float(h[0]), 0.0)
    if master_model not in ("ins", "white"):
        raise ValueError(f"master_model must be 'ins' or 'white'; got {master_model!r}")
    h_ext = h[m_end] + rng.normal(0.0, baro_std_m, len(m_end))
    sol = Strapdown(start, SinsConfig(vertical="baro")).run(dth_m + g_err * dt, dv_m + a_err * dt,
                                                            dt_s=dt, h_ext_m=h_ext)
    # epochs at multiples of 1 / rate, the start (time 0) first
    sel = np.arange(per_master - 1, len(m_end), per_master)
    t_m = np.r_[0.0, m_end[sel] * dtf]
    master = _truth(t_m, np.r_[start.lat_rad, sol.lat_rad[sel]], np.r_[start.lon_rad, sol.lon_rad[sel]],
                    np.r_[start.h_m, sol.h_m[sel]], np.vstack([start.v_n_m_s, sol.v_n_m_s[sel]]),
                    np.vstack([start.q_bn, sol.q_bn[sel]]), "simulate_transfer: the master INS")
    fi = np.r_[0, m_end[sel]]
    master_rate = w[fi] + np.vstack([g_err[:1], g_err[sel]])
    master_truth = _truth(t_m, lat[fi], lon[fi], h[fi], v_m[fi], qmn[fi],
                          "simulate_transfer: the master's truth")
    if master_model == "white":
        sv, sa, sp = (np.broadcast_to(np.asarray(x, float), (3,)) for x in master_white)
        m = len(fi)
        dq = np.array([_rotvec_quat(x) for x in rng.normal(0.0, sa, (m, 3))])
        du = rng.normal(0.0, sp, (m, 3))
        RMm, RNm = radii(lat[fi])[:2]
        master = _truth(t_m, lat[fi] + du[:, 1] / (RMm + h[fi]),
                        lon[fi] + du[:, 0] / ((RNm + h[fi]) * np.cos(lat[fi])), h[fi] + du[:, 2],
                        v_m[fi] + rng.normal(0.0, sv, (m, 3)), quat_multiply(dq, qmn[fi]),
                        "simulate_transfer: the master (truth + white noise)")
    info = {"fine_step_s": dtf, "slave_start_s": s0, "master_attitude_error0_rad": phi0,
            "master_gyro_bias_rad_s": mp["gyro_bias"][sel], "master_accel_bias_m_s2": mp["accel_bias"][sel],
            "host": host}
    return TransferScenario(slave_imu, master, master_rate, truth, master_truth, bg, ba,
                            flex[at], inst, info)


def _rotvec_quat(phi: np.ndarray) -> np.ndarray:
    a = float(np.linalg.norm(phi))
    if a < 1e-12:
        return np.r_[1.0, 0.5 * phi]
    return np.r_[np.cos(a / 2), np.sin(a / 2) * phi / a]


def _truth(t, lat, lon, h, v, q, source: str) -> TruthRecord:
    e = quat_to_euler(np.asarray(q, float))
    e[:, 0] = np.mod(e[:, 0], 2 * np.pi)
    return TruthRecord(np.asarray(t, float), np.asarray(lat, float), np.asarray(lon, float),
                       np.asarray(h, float), np.asarray(v, float), e, source)
