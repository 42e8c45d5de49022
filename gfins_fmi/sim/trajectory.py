"""Closed-form motions and the exact outputs of the sensors that would ride them — the
truth for tests, benchmarks and demonstrations.

A motion gives, as functions of time, the geodetic position (latitude L, longitude
lambda, height h) with its first and second derivatives, and the attitude q_b^n with the
body rate relative to the navigation frame w_nb^b. From these, with the WGS-84 model of
:mod:`gfins_fmi.nav.earth` (numpy, independent of the C core, so that it can serve as
truth; the tests check that both agree to round-off):

    v^n  = [(R_N + h) cos L dlambda, (R_M + h) dL, dh]                       (ENU)
    f^n  = dv^n/dt + (2 w_ie^n + w_en^n) x v^n - g^n,   g^n = [0, 0, -gamma(L, h)]
    w_en^n = [-dL, dlambda cos L, dlambda sin L],  w_ie^n = W [0, cos L, sin L]
    f^b  = C_n^b f^n,   w_ib^b = w_nb^b + C_n^b (w_ie^n + w_en^n)

dv^n/dt is differentiated by hand (including dR/dL), never by finite differences.
Increments over each sampling interval are integrated with Gauss-Legendre quadrature of
order 2m (m = 8 nodes: exact for polynomials of degree 15; for the smooth motions here
the quadrature error is below double round-off).

Frames and angles follow the C core (gf_sins.h): body right-front-up, navigation ENU,
heading clockwise from north, C_b^n = Rz(-psi) Rx(theta) Ry(gamma).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gfins_fmi.gyrofree.array import forward_model
from gfins_fmi.nav.earth import WGS84, deg, euler_to_quat, gravity, quat_multiply, quat_to_dcm, radii

__all__ = ["Motion", "Stationary", "ConstantVelocity", "SineVelocity", "Circle", "Coning",
           "Airdrop", "VehicleRun", "Trajectory", "sample"]


def _euler_body_rate(heading, pitch, roll, dheading, dpitch, droll):
    """w_nb^b of Euler angles and their rates for C_b^n = Rz(-psi) Rx(theta) Ry(gamma):
    w = Ry(g)^T Rx(t)^T [0, 0, -dpsi] + Ry(g)^T [dtheta, 0, 0] + [0, dgamma, 0]."""
    ct, st = np.cos(pitch), np.sin(pitch)
    cg, sg = np.cos(roll), np.sin(roll)
    # Rx(t)^T [0,0,-dpsi] = [0, -st*(-dpsi)... ] written out:
    a = np.stack([np.zeros_like(dheading), -st * dheading, -ct * dheading], -1)  # Rx^T [0,0,-dpsi]
    a[..., 0] += dpitch
    # Ry(g)^T v = [cg v0 - sg v2, v1, sg v0 + cg v2]
    w = np.stack([cg * a[..., 0] - sg * a[..., 2], a[..., 1] + droll, sg * a[..., 0] + cg * a[..., 2]], -1)
    return w


class Motion:
    """A closed-form motion. Subclasses define :meth:`position` and :meth:`attitude`."""

    #: whether the motion's functions are smooth everywhere (quadrature is then exact)
    def position(self, t):
        """Return (L, lam, h), (dL, dlam, dh), (ddL, ddlam, ddh) at times t (arrays, rad, m, s)."""
        raise NotImplementedError

    def attitude(self, t):
        """Return q_b^n (n, 4) and w_nb^b (n, 3) at times t."""
        raise NotImplementedError

    # -- derived quantities -------------------------------------------------------------
    def state(self, t):
        """True navigation state and sensor rates at times t.

        Returns a dict with lat, lon, h (n,), v_n (n, 3), q_bn (n, 4), gyro w_ib^b (n, 3)
        and accel f^b (n, 3).
        """
        t = np.atleast_1d(np.asarray(t))
        dtype = complex if np.iscomplexobj(t) else float   # complex: see gyro_dot
        t = t.astype(dtype)
        (L, lam, h), (dL, dlam, dh), (ddL, ddlam, ddh) = [
            tuple(np.broadcast_to(np.asarray(x, dtype=dtype), t.shape) for x in trip)
            for trip in self.position(t)]
        RM, RN, dRM, dRN = radii(L)
        sL, cL = np.sin(L), np.cos(L)
        v = np.stack([(RN + h) * cL * dlam, (RM + h) * dL, dh], -1)
        dv = np.stack([
            (dRN * dL + dh) * cL * dlam - (RN + h) * sL * dL * dlam + (RN + h) * cL * ddlam,
            (dRM * dL + dh) * dL + (RM + h) * ddL,
            ddh], -1)
        w_ie = WGS84.omega_ie * np.stack([np.zeros_like(L), cL, sL], -1)
        w_en = np.stack([-dL, dlam * cL, dlam * sL], -1)
        g_n = np.stack([np.zeros_like(L), np.zeros_like(L), -gravity(L, h)], -1)
        f_n = dv + np.cross(2 * w_ie + w_en, v) - g_n
        q, w_nb = self.attitude(t)
        C = quat_to_dcm(q)                                   # C_b^n
        f_b = np.einsum("nji,nj->ni", C, f_n)                # C_n^b f^n
        w_ib = w_nb + np.einsum("nji,nj->ni", C, w_ie + w_en)
        return dict(t=t, lat=L, lon=lam, h=h, v_n=v, q_bn=q, gyro=w_ib, accel=f_b)

    def gyro_dot(self, t):
        """d/dt of w_ib^b (rad/s^2, body axes) at times t, by complex-step
        differentiation: for the analytic closed forms here, Im(w(t + i h))/h with
        h = 1e-30 s equals the derivative to round-off (no subtraction, so no
        cancellation: this is not a finite difference)."""
        h = 1e-30
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return np.imag(self.state(t + 1j * h)["gyro"]) / h


class _EulerAttitude:
    """Attitude from Euler-angle functions (heading, pitch, roll) and their rates."""

    def euler(self, t):
        raise NotImplementedError

    def attitude(self, t):
        (psi, th, ga), (dpsi, dth, dga) = self.euler(t)
        shape = np.shape(t)
        dtype = complex if np.iscomplexobj(t) else float
        psi, th, ga, dpsi, dth, dga = (np.broadcast_to(np.asarray(x, dtype), shape)
                                       for x in (psi, th, ga, dpsi, dth, dga))
        return euler_to_quat(psi, th, ga), _euler_body_rate(psi, th, ga, dpsi, dth, dga)


@dataclass
class _Local:
    """Reference point; local displacements (m) become geodetic coordinates with the
    radii of the reference point, so L and lam are exact closed forms of t."""
    lat: float = 30 * deg
    lon: float = 114 * deg
    h: float = 100.0

    def _geo(self, E, N, U, dE, dN, dU, ddE, ddN, ddU):
        RM, RN, _, _ = radii(self.lat)
        kN = 1.0 / (RM + self.h)
        kE = 1.0 / ((RN + self.h) * np.cos(self.lat))
        return ((self.lat + kN * N, self.lon + kE * E, self.h + U),
                (kN * dN, kE * dE, dU), (kN * ddN, kE * ddE, ddU))


@dataclass
class Stationary(_Local, _EulerAttitude, Motion):
    """At rest on the Earth with a fixed attitude (rad)."""
    heading: float = 30 * deg
    pitch: float = 2 * deg
    roll: float = -1 * deg

    def position(self, t):
        z = np.zeros_like(t)
        return self._geo(z, z, z, z, z, z, z, z, z)

    def euler(self, t):
        z = np.zeros_like(t)
        return (self.heading + z, self.pitch + z, self.roll + z), (z, z, z)


@dataclass
class ConstantVelocity(_Local, _EulerAttitude, Motion):
    """Constant rates of latitude, longitude and height giving ``v_enu_m_s`` at the
    reference point; heading along the track, level."""
    v_enu_m_s: tuple = (10.0, 5.0, 0.0)

    def position(self, t):
        vE, vN, vU = self.v_enu_m_s
        z = np.zeros_like(t)
        return self._geo(vE * t, vN * t, vU * t, vE + z, vN + z, vU + z, z, z, z)

    def euler(self, t):
        vE, vN, _ = self.v_enu_m_s
        z = np.zeros_like(t)
        return (np.arctan2(vE, vN) % (2 * np.pi) + z, z, z), (z, z, z)


@dataclass
class SineVelocity(_Local, _EulerAttitude, Motion):
    """Velocity oscillating sinusoidally in each axis (amplitudes m/s, period s), with a
    slowly oscillating attitude."""
    amplitude_m_s: tuple = (2.0, 3.0, 0.5)
    period_s: float = 100.0
    attitude_amplitude_rad: tuple = (5 * deg, 2 * deg, 3 * deg)

    def position(self, t):
        w = 2 * np.pi / self.period_s
        (aE, aN, aU) = self.amplitude_m_s
        s, c = np.sin(w * t), np.cos(w * t)
        # v = a sin(w t): displacement (a/w)(1 - cos w t)
        return self._geo(aE / w * (1 - c), aN / w * (1 - c), aU / w * (1 - c),
                         aE * s, aN * s, aU * s, aE * w * c, aN * w * c, aU * w * c)

    def euler(self, t):
        w = 2 * np.pi / self.period_s
        a0, a1, a2 = self.attitude_amplitude_rad
        return ((1.0 + a0 * np.sin(w * t), a1 * np.sin(2 * w * t), a2 * np.cos(w * t)),
                (a0 * w * np.cos(w * t), 2 * a1 * w * np.cos(2 * w * t), -a2 * w * np.sin(w * t)))


@dataclass
class Circle(_Local, _EulerAttitude, Motion):
    """Counter-clockwise circle of radius r at speed v (seen from above), heading along
    the track, banked (roll) and pitching sinusoidally."""
    radius_m: float = 100.0
    speed_m_s: float = 10.0
    pitch_amplitude_rad: float = 3 * deg
    roll_rad: float = -5 * deg

    def position(self, t):
        r, w = self.radius_m, self.speed_m_s / self.radius_m
        s, c = np.sin(w * t), np.cos(w * t)
        z = np.zeros_like(t)
        # centre at (-r, 0): E = r (cos wt - 1), N = r sin wt
        return self._geo(r * (c - 1), r * s, z, -r * w * s, r * w * c, z,
                         -r * w * w * c, -r * w * w * s, z)

    def euler(self, t):
        w = self.speed_m_s / self.radius_m
        # velocity direction (E, N) = (-sin wt, cos wt): heading = -wt (clockwise from N);
        # not wrapped into [0, 2 pi): the attitude is the same and t may be complex
        psi = -w * t
        return ((psi, self.pitch_amplitude_rad * np.sin(2 * w * t), self.roll_rad + 0 * t),
                (-w + 0 * t, 2 * w * self.pitch_amplitude_rad * np.cos(2 * w * t), 0 * t))


@dataclass
class Coning(_Local, Motion):
    """Classic coning at rest: the body's up axis sweeps a cone of half-angle
    ``half_angle_rad`` about the navigation up axis at ``frequency_hz``:
    q_b^n = [cos(a/2), sin(a/2) cos(W t), sin(a/2) sin(W t), 0] (x) q0, q0 the base
    attitude."""
    half_angle_rad: float = 1 * deg
    frequency_hz: float = 5.0
    heading: float = 0.0

    def attitude(self, t):
        a, W = self.half_angle_rad, 2 * np.pi * self.frequency_hz
        ca, sa = np.cos(a / 2), np.sin(a / 2)
        qc = np.stack([ca + 0 * t, sa * np.cos(W * t), sa * np.sin(W * t), 0 * t], -1)
        dqc = np.stack([0 * t, -sa * W * np.sin(W * t), sa * W * np.cos(W * t), 0 * t], -1)
        q0 = euler_to_quat(self.heading, 0.0, 0.0)
        q = quat_multiply(qc, np.broadcast_to(q0, qc.shape))
        dq = quat_multiply(dqc, np.broadcast_to(q0, qc.shape))
        conj = q * np.array([1, -1, -1, -1])
        w = 2 * quat_multiply(conj, dq)[..., 1:]          # w_nb^b = 2 q* dq/dt (vector part)
        return q, w

    def position(self, t):
        z = np.zeros_like(t)
        return self._geo(z, z, z, z, z, z, z, z, z)


@dataclass
class Airdrop(_Local, _EulerAttitude, Motion):
    """An airdrop-like fall (seed 002: an instrumented water tank dropped from an aircraft
    under a parachute): the forward speed decays from the aircraft's by drag,
    v_N = v0 exp(-t/tau_h); the descent rate approaches the terminal speed,
    v_U = -v_t (1 - exp(-t/tau_v)); the load swings in pitch and roll with a decaying
    amplitude. All closed forms."""
    h: float = 1500.0
    v0_m_s: float = 60.0
    tau_h_s: float = 8.0
    v_terminal_m_s: float = 7.0
    tau_v_s: float = 3.0
    swing_rad: float = 15 * deg
    swing_period_s: float = 6.0
    swing_decay_s: float = 40.0
    heading: float = 20 * deg

    def position(self, t):
        v0, th, vt, tv = self.v0_m_s, self.tau_h_s, self.v_terminal_m_s, self.tau_v_s
        eh, ev = np.exp(-t / th), np.exp(-t / tv)
        along, d_along, dd_along = v0 * th * (1 - eh), v0 * eh, -v0 / th * eh
        U, dU, ddU = -vt * (t - tv * (1 - ev)), -vt * (1 - ev), -vt / tv * ev
        sh, ch = np.sin(self.heading), np.cos(self.heading)
        return self._geo(sh * along, ch * along, U, sh * d_along, ch * d_along, dU,
                         sh * dd_along, ch * dd_along, ddU)

    def euler(self, t):
        A, w, td = self.swing_rad, 2 * np.pi / self.swing_period_s, self.swing_decay_s
        e = np.exp(-t / td)
        p = A * e * np.sin(w * t)
        dp = A * e * (w * np.cos(w * t) - np.sin(w * t) / td)
        r = 0.5 * A * e * np.cos(w * t)
        dr = 0.5 * A * e * (-w * np.sin(w * t) - np.cos(w * t) / td)
        return (self.heading + 0 * t, p, r), (0 * t, dp, dr)


def _smoothstep(u):
    """S(u) = u - sin(2 pi u)/(2 pi) on [0, 1], 0 before, 1 after, with S' and S''
    (both vanish at the ends, so a profile built from it has continuous acceleration and
    jerk). Complex u (complex-step differentiation) is kept inside the interval; outside
    it the constants have no imaginary part, as the derivative there is 0."""
    ur = np.real(u)
    inside = (ur > 0.0) & (ur < 1.0)
    uu = np.where(inside, u, np.where(ur >= 1.0, 1.0, 0.0))
    w = 2 * np.pi * uu
    return uu - np.sin(w) / (2 * np.pi), 1 - np.cos(w), 2 * np.pi * np.sin(w)


@dataclass
class VehicleRun(_Local, _EulerAttitude, Motion):
    """The vehicle test of seed 001: at rest for ``align_s`` (alignment), a smooth
    start to ``speed_m_s``, a straight run, a 180 deg turn at ``turn_times_s[0]`` after
    the start of motion and another at ``turn_times_s[1]``, each lasting ``turn_s``
    (heading by a C2 smooth step, so the lateral acceleration is smooth).
    The path has no closed form: north/east displacements are integrated from the
    closed-form velocity with 8-node Gauss-Legendre quadrature per 0.25 s knot interval
    (error far below round-off for these smooth profiles)."""
    align_s: float = 600.0
    speed_m_s: float = 15.0
    accel_s: float = 20.0
    turn_times_s: tuple = (240.0, 480.0)
    turn_s: float = 30.0
    heading: float = 0.0
    knot_s: float = 0.25

    def _speed_heading(self, t):
        """speed, d speed, heading, d heading, dd heading at t (complex t allowed)."""
        tm = t - self.align_s
        S, dS, ddS = _smoothstep(tm / self.accel_s)
        v = self.speed_m_s * S
        dv = self.speed_m_s * dS / self.accel_s
        ddv = self.speed_m_s * ddS / self.accel_s ** 2
        psi, dpsi, ddpsi = self.heading + 0 * t, 0 * t, 0 * t
        for t_turn in self.turn_times_s:
            St, dSt, ddSt = _smoothstep((tm - t_turn) / self.turn_s)
            psi = psi + np.pi * St
            dpsi = dpsi + np.pi * dSt / self.turn_s
            ddpsi = ddpsi + np.pi * ddSt / self.turn_s ** 2
        return v, dv, ddv, psi, dpsi, ddpsi

    def _velocity_en(self, t):
        v, _, _, psi, _, _ = self._speed_heading(t)
        return v * np.sin(psi), v * np.cos(psi)

    def _displacement(self, t):
        """(E, N) at times t: knots every knot_s, Gauss-Legendre inside."""
        x, w = np.polynomial.legendre.leggauss(8)
        tr = np.real(t)
        tmax = float(np.max(tr)) if np.size(tr) else 0.0
        nk = int(np.ceil(max(tmax, 0.0) / self.knot_s)) + 1
        kt = np.arange(nk + 1) * self.knot_s
        a, b = kt[:-1], kt[1:]
        nodes = (a[:, None] + 0.5 * (b - a)[:, None] * (x[None, :] + 1)).ravel()
        vE, vN = self._velocity_en(nodes)
        wq = 0.5 * self.knot_s * w
        cumE = np.r_[0.0, np.cumsum((vE.reshape(nk, 8) * wq).sum(1))]
        cumN = np.r_[0.0, np.cumsum((vN.reshape(nk, 8) * wq).sum(1))]
        k = np.clip(np.floor(tr / self.knot_s).astype(int), 0, nk - 1)
        t0 = kt[k]
        half = 0.5 * (t - t0)
        tn = t0[..., None] + half[..., None] * (x + 1)
        vEn, vNn = self._velocity_en(tn)
        E = cumE[k] + half * (vEn * w).sum(-1)
        N = cumN[k] + half * (vNn * w).sum(-1)
        return E, N

    def position(self, t):
        E, N = self._displacement(t)
        v, dv, _, psi, dpsi, _ = self._speed_heading(t)
        s, c = np.sin(psi), np.cos(psi)
        z = 0 * t
        return self._geo(E, N, z, v * s, v * c, z,
                         dv * s + v * c * dpsi, dv * c - v * s * dpsi, z)

    def euler(self, t):
        _, _, _, psi, dpsi, _ = self._speed_heading(t)
        z = 0 * t
        return (psi, z, z), (dpsi, z, z)   # heading beyond 2 pi is the same attitude


@dataclass
class Trajectory:
    """A sampled motion: truth at t_k and sensor outputs.

    Attributes
    ----------
    t_s : (n,)
    lat_rad, lon_rad, h_m : (n,)
    v_n_m_s : (n, 3)  ENU velocity
    q_bn : (n, 4)     attitude
    gyro_rad_s, accel_m_s2 : (n, 3)   w_ib^b and f^b at t_k (rate sensors)
    dtheta_rad, dv_m_s : (n - 1, 3)   increments over (t_(k-1), t_k], k = 1..n-1
    """

    t_s: np.ndarray
    lat_rad: np.ndarray
    lon_rad: np.ndarray
    h_m: np.ndarray
    v_n_m_s: np.ndarray
    q_bn: np.ndarray
    gyro_rad_s: np.ndarray
    accel_m_s2: np.ndarray
    dtheta_rad: np.ndarray
    dv_m_s: np.ndarray
    motion: Motion | None = None

    @property
    def dt_s(self) -> float:
        return float(self.t_s[1] - self.t_s[0])

    def array_outputs(self, geometry) -> np.ndarray:
        """Outputs (n, N) of an accelerometer array of any geometry riding the motion,
        at the sample times: A_i = theta_i . [f + w_dot x u_i + w x (w x u_i)] with
        w = w_ib^b, w_dot its derivative (complex step) and f the specific force at the
        array centre (the C forward model of gfins_fmi.gyrofree.array)."""
        if self.motion is None:
            raise ValueError("this Trajectory has no motion attached (make it with sample())")
        return forward_model(geometry, self.accel_m_s2, self.gyro_rad_s,
                             self.motion.gyro_dot(self.t_s))


def sample(motion: Motion, duration_s: float, dt_s: float, nodes: int = 8,
           chunk: int = 200_000) -> Trajectory:
    """Sample ``motion`` every ``dt_s`` over ``duration_s`` (n = duration/dt + 1 points)."""
    n = int(round(duration_s / dt_s)) + 1
    t = np.arange(n) * dt_s
    st = motion.state(t)
    x, w = np.polynomial.legendre.leggauss(nodes)
    dth = np.empty((n - 1, 3))
    dv = np.empty((n - 1, 3))
    for a in range(0, n - 1, chunk):  # bounded memory for long records
        b = min(n - 1, a + chunk)
        t0 = t[a:b]
        tq = (t0[:, None] + 0.5 * dt_s * (x[None, :] + 1.0)).ravel()
        s = motion.state(tq)
        wq = 0.5 * dt_s * w
        dth[a:b] = np.einsum("knj,n->kj", s["gyro"].reshape(b - a, nodes, 3), wq)
        dv[a:b] = np.einsum("knj,n->kj", s["accel"].reshape(b - a, nodes, 3), wq)
    return Trajectory(t, st["lat"], st["lon"], st["h"], st["v_n"], st["q_bn"],
                      st["gyro"], st["accel"], dth, dv, motion)
