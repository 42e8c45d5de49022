"""Accuracy of the N-subsample strapdown update (SinsConfig(subsamples=N), N = 1..4)
against closed-form motions, at several sample rates: the table of docs/sins.md
("Subsamples").

    python bench/study_subsamples.py

1. Classic coning in a fixed frame without gravity (half-angle a, cone rate W):
   q_b^n(t) = [cos(a/2), sin(a/2) cos Wt, sin(a/2) sin Wt, 0], body rate
   w = W [-sin a sin Wt, sin a cos Wt, -2 sin^2(a/2)], exact increments
   dtheta = sin a [cos Wt1 - cos Wt0, sin Wt1 - sin Wt0, -2 tan(a/2) ... ] (see
   coning_increments). Measured: the attitude drift about the cone axis (slope of the
   error angle's z component); theory: sin^2 a e_N(lambda) / (N h) with lambda = W h and
   e_N(l) = (N l - sin N l)/2 - 4 sin^2(l/2) sum_(i<N) k_i sin((N - i) l) (docs/sins.md;
   N = 1: the one-sample update with the previous sample's 1/12 term).
2. Classic sculling in the same frame: a roll a sin(Wt) about x with a specific force
   A sin(Wt) along body y; the exact mean vertical acceleration is A J1(a) (Bessel).
   Measured: the missed acceleration A J1(a) - slope of v_up; theory a A e_N(lambda) /
   (N lambda).
3. The sine-velocity motion on the WGS-84 Earth (gfins_fmi.sim.trajectory.SineVelocity,
   exact increments, height held), 10 min: maximum horizontal, velocity and attitude
   errors; these are the navigation update's own truncation (mid-point extrapolation,
   trapezoidal position), second order in the update interval N h.
"""
from __future__ import annotations

import numpy as np

import gfins_fmi as gf
from gfins_fmi.sim import trajectory as tj
from gfins_fmi.nav import earth

SINE = tj.SineVelocity(amplitude_m_s=(2.0, 3.0, 0.0))    # horizontal: the height is held
K = {1: [1 / 12], 2: [2 / 3], 3: [9 / 20, 27 / 20], 4: [54 / 105, 92 / 105, 214 / 105]}


def e_theory(N: int, lam: float) -> float:
    """Residual per update of the N-subsample set (units sin^2 a for coning, a A / W for
    sculling); N = 1: the previous-sample form (dtheta_(k-1) x dtheta_k / 12)."""
    if N == 1:
        return 0.5 * (lam - np.sin(lam)) - 4 * np.sin(lam / 2) ** 2 * np.sin(lam) / 12
    s = sum(k * np.sin((N - i) * lam) for i, k in enumerate(K[N], start=1))
    return 0.5 * (N * lam - np.sin(N * lam)) - 4 * np.sin(lam / 2) ** 2 * s


def coning_increments(a: float, W: float, t: np.ndarray) -> np.ndarray:
    """Exact increments of the classic coning body rate over [t_k, t_(k+1)]."""
    c, s = np.cos(W * t), np.sin(W * t)
    d = np.empty((t.size - 1, 3))
    d[:, 0] = np.sin(a) * (c[1:] - c[:-1])
    d[:, 1] = np.sin(a) * (s[1:] - s[:-1])
    d[:, 2] = -2 * np.sin(a / 2) ** 2 * W * np.diff(t)
    return d


def coning_truth(a: float, W: float, t: np.ndarray) -> np.ndarray:
    return np.c_[np.full(t.size, np.cos(a / 2)), np.sin(a / 2) * np.cos(W * t),
                 np.sin(a / 2) * np.sin(W * t), np.zeros(t.size)]


FLAT0 = dict(v_n_m_s=np.zeros(3), lat_rad=0.0, lon_rad=0.0, h_m=0.0, t_s=0.0, pos_m=np.zeros(3))


def coning_drift(N: int, rate_hz: float, a: float = np.radians(1.0), f_hz: float = 10.0,
                 dur_s: float = 12.0) -> tuple[float, float]:
    """(measured, theory) drift about the cone axis, rad/s."""
    W, h = 2 * np.pi * f_hz, 1.0 / rate_hz
    t = np.arange(int(round(dur_s * rate_hz)) + 1) * h
    dth = coning_increments(a, W, t)
    qt = coning_truth(a, W, t)
    x0 = gf.NavState(qt[0], **FLAT0)
    sol = gf.Strapdown(x0, gf.SinsConfig(earth="flat", subsamples=N)).run(dth, np.zeros_like(dth),
                                                                          dt_s=h)
    idx = np.minimum(np.arange(1, len(sol) + 1) * N, t.size - 1)
    err = earth.attitude_error_rad(sol.q_bn, qt[idx])
    slope = np.polyfit(sol.t_s, err[:, 2], 1)[0]
    return abs(slope), np.sin(a) ** 2 * e_theory(N, W * h) / (N * h)


def sculling_drift(N: int, rate_hz: float, a: float = 0.01, A: float = 10.0, f_hz: float = 10.0,
                   dur_s: float = 24.0) -> tuple[float, float]:
    """(measured, theory) missed mean vertical acceleration, m/s^2."""
    from scipy.special import j1
    W, h = 2 * np.pi * f_hz, 1.0 / rate_hz
    t = np.arange(int(round(dur_s * rate_hz)) + 1) * h
    dth = np.zeros((t.size - 1, 3))
    dth[:, 0] = np.diff(a * np.sin(W * t))
    dv = np.zeros((t.size - 1, 3))
    dv[:, 1] = A / W * (np.cos(W * t[:-1]) - np.cos(W * t[1:]))
    x0 = gf.NavState(np.array([1.0, 0, 0, 0]), **FLAT0)
    sol = gf.Strapdown(x0, gf.SinsConfig(earth="flat", subsamples=N)).run(dth, dv, dt_s=h)
    drift = A * j1(a) - np.polyfit(sol.t_s, sol.v_n_m_s[:, 2], 1)[0]
    lam = W * h
    return drift, a * A * e_theory(N, lam) / (N * lam)


def sine_errors(N: int, rate_hz: float, tr=None, dur_s: float = 600.0):
    """(horizontal m, velocity m/s, attitude rad) maximum errors on the sine motion."""
    h = 1.0 / rate_hz
    if tr is None:
        tr = tj.sample(SINE, dur_s, h)
    x0 = gf.NavState.from_trajectory(tr, 0)
    sol = gf.Strapdown(x0, gf.SinsConfig(vertical="hold", subsamples=N)).run(tr.dtheta_rad, tr.dv_m_s,
                                                                            dt_s=h)
    idx = np.minimum(np.arange(1, len(sol) + 1) * N, tr.t_s.size - 1)
    R = 6378137.0
    horiz = np.hypot((sol.lat_rad - tr.lat_rad[idx]) * R,
                     (sol.lon_rad - tr.lon_rad[idx]) * R * np.cos(tr.lat_rad[idx])).max()
    dv = np.abs(sol.v_n_m_s[:, :2] - tr.v_n_m_s[idx, :2]).max()
    att = np.linalg.norm(earth.attitude_error_rad(sol.q_bn, tr.q_bn[idx]), axis=1).max()
    return horiz, dv, att


def main() -> None:
    rates = (100.0, 200.0, 400.0)
    for title, fn in (("1. coning, a = 1 deg, cone 10 Hz, 12 s, fixed frame: drift about the cone "
                       "axis, rad/s (measured / theory)", coning_drift),
                      ("2. sculling, a = 0.01 rad, A = 10 m/s^2, 10 Hz, 24 s: missed acceleration, "
                       "m/s^2 (measured / theory)", sculling_drift)):
        print(title)
        for N in (1, 2, 3, 4):
            cells = ["{:.3e} / {:.3e}".format(*fn(N, r)) for r in rates]
            print(f"  N = {N}: " + "   ".join(f"{r:.0f} Hz: {c}" for r, c in zip(rates, cells)))
    print("3. sine velocity, 10 min, WGS-84, height held: max horizontal m, velocity m/s, attitude rad")
    for r in (100.0, 200.0):
        tr = tj.sample(SINE, 600.0, 1.0 / r)
        for N in (1, 2, 3, 4):
            hz, dv, att = sine_errors(N, r, tr)
            print(f"  {r:.0f} Hz, N = {N} (update {N / r * 1e3:.0f} ms): {hz:.3e} m  {dv:.3e} m/s  "
                  f"{att:.3e} rad")


if __name__ == "__main__":
    main()
