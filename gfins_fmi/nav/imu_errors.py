"""IMU error model (C core ``gf_imu_error``) in datasheet units: one definition for
simulation (:meth:`ImuErrors.apply`) and compensation (:meth:`ImuErrors.compensate`).
Model and seed equations: ``csrc/nav/gf_imu_error.h``.

Units at this boundary (SI inside): gyro bias in deg/h, accelerometer bias in ug
(1 ug = 9.80665e-6 m/s^2), scale factors in ppm, misalignments in arcsec, K2 in ug/g^2,
inner lever arms in cm, the accelerometer delay in ms, temperatures in degC; temperature
coefficients in the same unit per degC^(k+1).

Inner lever arms: accelerometer i sits at r_i from the reference point; ``lever_arm_cm``
is either the three offsets along the own axes (seed 001's model, (3,)) or the three
positions (3, 3), row i = r_i in IMU axes. Arms across the sensing axes feel the angular
acceleration (w_dot x r_i); :meth:`ImuErrors.apply` and :meth:`ImuErrors.compensate` take
it as ``omega_dot_rad_s2``, the increment methods estimate it from the rates.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gfins_fmi._lib import NonFiniteInputError, as_array, as_rows, ffi, lib, ptr
from gfins_fmi.nav.noise import first_order_lowpass_noise

__all__ = ["ImuErrors", "ImuNoise", "G0", "DEG_H", "UG", "PPM", "ARCSEC",
           "seed001_gyro_misalignment", "seed001_accel_misalignment"]

G0 = 9.80665                          #: standard gravity, m/s^2
DEG_H = np.pi / 180.0 / 3600.0        #: 1 deg/h in rad/s
UG = 1e-6 * G0                        #: 1 ug in m/s^2
PPM = 1e-6                            #: 1 ppm
ARCSEC = np.pi / 180.0 / 3600.0       #: 1 arcsec in rad

_FIELDS = {1: "gyro_scale_ppm (|s| < 0.5 = 500000 ppm)",
           2: "gyro_misalignment_arcsec (|N| < 0.1 rad = 20626 arcsec, zero diagonal)",
           3: "accel_scale_ppm (|s| < 500000 ppm)",
           4: "accel_misalignment_arcsec (|N| < 20626 arcsec, zero diagonal)",
           5: "accel_k2_ug_g2 (|K2| * 1000 m/s^2 < 0.1)",
           6: "lever_arm_cm (every |r_ij| < 100 cm)",
           7: "temperature order (at most 4 coefficients)",
           8: "gyro_bias_deg_h (|b| < 50 rad/s = 1.03e10 deg/h)",
           9: "accel_bias_ug (|b| < 1000 m/s^2 = 1.02e8 ug)",
           10: "accel_delay_ms (|d| < 1000 ms)"}


def _vec(name, value, shape):
    arr = np.zeros(shape) if value is None else np.asarray(value, float)
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape}; got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    return arr


@dataclass
class ImuErrors:
    """Deterministic errors of a gyro triad and an accelerometer triad (datasheet units).

    Parameters
    ----------
    gyro_bias_deg_h, gyro_scale_ppm : (3,)
    gyro_misalignment_arcsec : (3, 3)
        Cross-coupling N_g (zero diagonal): w_out = (I + diag s)(I + N) w + b.
    accel_bias_ug, accel_scale_ppm, accel_k2_ug_g2 : (3,)
    accel_misalignment_arcsec : (3, 3)
    lever_arm_cm : (3,) or (3, 3)
        Inner lever arms: (3,) the offset of each accelerometer along its own axis (seed
        001); (3, 3) the positions, row i = accelerometer i's position from the
        reference point (IMU axes). See :attr:`lever_arm_matrix_cm`.
    t0_C : float
        Reference temperature of the biases and scale factors.
    gyro_bias_tc, gyro_scale_tc, accel_bias_tc, accel_scale_tc : (order, 3)
        Temperature coefficients: row k multiplies (T - t0)^(k+1), in the unit of the
        quantity per degC^(k+1); at most 4 rows, all four with the same number of rows.
    accel_delay_ms : float
        The accelerometers sample this late behind the gyros (first order:
        f(t - d) = f + d (w x f); csrc/nav/gf_imu_error.h).
    """

    gyro_bias_deg_h: np.ndarray | None = None
    gyro_scale_ppm: np.ndarray | None = None
    gyro_misalignment_arcsec: np.ndarray | None = None
    accel_bias_ug: np.ndarray | None = None
    accel_scale_ppm: np.ndarray | None = None
    accel_misalignment_arcsec: np.ndarray | None = None
    accel_k2_ug_g2: np.ndarray | None = None
    lever_arm_cm: np.ndarray | None = None
    t0_C: float = 20.0
    gyro_bias_tc: np.ndarray | None = None
    gyro_scale_tc: np.ndarray | None = None
    accel_bias_tc: np.ndarray | None = None
    accel_scale_tc: np.ndarray | None = None
    accel_delay_ms: float = 0.0
    _c: object = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        c = ffi.new("gf_imu_errors *")
        c.g_bias_rad_s = list(_vec("gyro_bias_deg_h", self.gyro_bias_deg_h, (3,)) * DEG_H)
        c.g_scale = list(_vec("gyro_scale_ppm", self.gyro_scale_ppm, (3,)) * PPM)
        c.g_misalign_rad = list(_vec("gyro_misalignment_arcsec", self.gyro_misalignment_arcsec,
                                     (3, 3)).ravel() * ARCSEC)
        c.a_bias_m_s2 = list(_vec("accel_bias_ug", self.accel_bias_ug, (3,)) * UG)
        c.a_scale = list(_vec("accel_scale_ppm", self.accel_scale_ppm, (3,)) * PPM)
        c.a_misalign_rad = list(_vec("accel_misalignment_arcsec", self.accel_misalignment_arcsec,
                                     (3, 3)).ravel() * ARCSEC)
        # K2 [ug/g^2]: error = K2 u^2 with u in g  ->  K2 * 1e-6 g / g^2 = K2 * 1e-6 / g per m/s^2
        c.a_k2_s2_m = list(_vec("accel_k2_ug_g2", self.accel_k2_ug_g2, (3,)) * 1e-6 / G0)
        lev = np.zeros(3) if self.lever_arm_cm is None else np.asarray(self.lever_arm_cm, float)
        lev = _vec("lever_arm_cm", lev, lev.shape if lev.shape in ((3,), (3, 3)) else (3, 3))
        c.a_lever_pos_m = list((np.diag(lev) if lev.ndim == 1 else lev).ravel() * 0.01)
        d = np.asarray(self.accel_delay_ms, float)
        if d.shape != () or not np.isfinite(d):
            raise ValueError(f"accel_delay_ms must be a finite number; got {self.accel_delay_ms!r}")
        c.a_delay_s = float(d) * 1e-3
        c.t0 = float(self.t0_C)
        tcs = {"gyro_bias_tc": DEG_H, "gyro_scale_tc": PPM, "accel_bias_tc": UG,
               "accel_scale_tc": PPM}
        orders = {np.asarray(getattr(self, k)).shape[0] for k in tcs if getattr(self, k) is not None}
        if len(orders) > 1:
            raise ValueError("the temperature coefficient arrays must have the same number of rows")
        order = orders.pop() if orders else 0
        if order > int(lib.GF_IMU_TEMP_ORDER_MAX):
            raise ValueError(f"at most {int(lib.GF_IMU_TEMP_ORDER_MAX)} temperature coefficients "
                             f"per quantity; got {order}")
        c.temp_order = order
        for name, unit in tcs.items():
            arr = _vec(name, getattr(self, name), (order, 3)) if order else np.zeros((0, 3))
            flat = np.zeros(3 * int(lib.GF_IMU_TEMP_ORDER_MAX))
            flat[:arr.size] = arr.ravel() * unit
            setattr(c, {"gyro_bias_tc": "g_bias_tc", "gyro_scale_tc": "g_scale_tc",
                        "accel_bias_tc": "a_bias_tc", "accel_scale_tc": "a_scale_tc"}[name], list(flat))
        bad = ffi.new("int *")
        status = lib.gf_imu_errors_check(c, bad)
        if status != lib.GF_OK:
            raise ValueError(f"IMU error parameter out of its physical range: "
                             f"{_FIELDS.get(int(bad[0]), 'a non-finite value')}")
        object.__setattr__(self, "_c", c)

    @property
    def lever_arm_matrix_cm(self) -> np.ndarray:
        """The accelerometers' positions (3, 3), cm: row i = accelerometer i's position from
        the reference point, IMU axes (the diagonal: seed 001's offsets along the axes)."""
        return np.array(list(self._c.a_lever_pos_m)).reshape(3, 3) / 0.01

    @property
    def has_transverse_lever_arms(self) -> bool:
        """True when an accelerometer is offset across its sensing axis (the model then
        needs the angular acceleration)."""
        m = self.lever_arm_matrix_cm
        return bool(np.any(m[~np.eye(3, dtype=bool)] != 0.0))

    def fmu_parameters(self) -> dict:
        """The model as start values of the SINS and vehicle FMUs (SI units, FMI 3.0
        array names; the FMUs work at the reference temperature only).

        Raises
        ------
        ValueError
            The model has temperature coefficients (the FMUs do not take them).
        """
        c = self._c
        if c.temp_order:
            raise ValueError("the FMUs model the IMU at the reference temperature only: "
                             "temperature coefficients are not passed to them")
        pos = list(c.a_lever_pos_m)
        return dict(gyro_bias=list(c.g_bias_rad_s), gyro_scale=list(c.g_scale),
                    gyro_misalign=list(c.g_misalign_rad), accel_bias=list(c.a_bias_m_s2),
                    accel_scale=list(c.a_scale), accel_misalign=list(c.a_misalign_rad),
                    accel_k2=list(c.a_k2_s2_m), lever_arm=pos[0::4],
                    lever_arm_transverse=[pos[k] for k in (1, 2, 3, 5, 6, 7)],
                    accel_delay=float(c.a_delay_s))

    @classmethod
    def random(cls, rng: np.random.Generator, gyro_bias_deg_h=0.0, gyro_scale_ppm=0.0,
               gyro_misalignment_arcsec=0.0, accel_bias_ug=0.0, accel_scale_ppm=0.0,
               accel_misalignment_arcsec=0.0, accel_k2_ug_g2=0.0, lever_arm_cm=0.0,
               temp_order: int = 0, temp_scale_per_C: float = 0.01, t0_C: float = 20.0):
        """A set drawn from zero-mean normals with the given stds (datasheet units);
        temperature coefficients of order k get std temp_scale_per_C^(k+1) times the
        quantity's std."""
        def off(std):
            m = rng.normal(0, std, (3, 3))
            np.fill_diagonal(m, 0.0)
            return m
        tc = {}
        for name, std in (("gyro_bias_tc", gyro_bias_deg_h), ("gyro_scale_tc", gyro_scale_ppm),
                          ("accel_bias_tc", accel_bias_ug), ("accel_scale_tc", accel_scale_ppm)):
            tc[name] = np.array([rng.normal(0, std * temp_scale_per_C ** (k + 1), 3)
                                 for k in range(temp_order)]).reshape(temp_order, 3)
        return cls(rng.normal(0, gyro_bias_deg_h, 3), rng.normal(0, gyro_scale_ppm, 3),
                   off(gyro_misalignment_arcsec), rng.normal(0, accel_bias_ug, 3),
                   rng.normal(0, accel_scale_ppm, 3), off(accel_misalignment_arcsec),
                   rng.normal(0, accel_k2_ug_g2, 3), rng.normal(0, lever_arm_cm, 3), t0_C,
                   **(tc if temp_order else {}))

    def _run(self, fn, a, b, temp_C, names, omega_dot=None):
        x = as_rows(names[0], a, 3, "rad/s")
        y = as_rows(names[1], b, 3, "m/s^2")
        if x.shape[0] != y.shape[0]:
            raise ValueError(f"{names[0]} and {names[1]} must have the same number of rows")
        n = x.shape[0]
        wd = None if omega_dot is None else as_rows("omega_dot_rad_s2", omega_dot, 3, "rad/s^2")
        if wd is not None and wd.shape[0] != n:
            raise ValueError(f"omega_dot_rad_s2 must have {n} rows like {names[0]}; got {wd.shape[0]}")
        t = None
        if temp_C is not None:
            temp = np.asarray(temp_C)
            t = as_array("temp_C", np.broadcast_to(temp, (n,)) if temp.ndim == 0 else temp, (n,),
                         "degC", finite=False)
        out_w, out_f = np.empty((n, 3)), np.empty((n, 3))
        done = ffi.new("size_t *")
        tp = ptr(t, n) if t is not None else ffi.NULL
        if wd is None:
            status = fn(self._c, n, ptr(x, 3 * n), ptr(y, 3 * n), tp, ptr(out_w, 3 * n), ptr(out_f, 3 * n), done)
        else:
            fn_dw = lib.gf_imu_apply_dw if fn == lib.gf_imu_apply else lib.gf_imu_compensate_dw
            status = fn_dw(self._c, n, ptr(x, 3 * n), ptr(wd, 3 * n), ptr(y, 3 * n), tp,
                           ptr(out_w, 3 * n), ptr(out_f, 3 * n), done)
        if status != lib.GF_OK:
            k = int(done[0])
            what = ("is not finite" if status == lib.GF_ERR_NONFINITE_INPUT else
                    "is outside the error model's range (a scale factor at that temperature "
                    "not in (-0.5, 0.5), an output overflowing, or in compensate a K2 "
                    "quadratic without a real root)")
            raise NonFiniteInputError(f"sample {k} ({names[0]}, {names[1]}, temperature) {what}; "
                                      "rows before it are in .partial", k, -1,
                                      (out_w[:k].copy(), out_f[:k].copy()))
        return out_w, out_f

    def apply(self, omega_rad_s, f_m_s2, temp_C=None, omega_dot_rad_s2=None):
        """Sensor outputs (rad/s, m/s^2) of true rates and specific forces (n, 3) at the
        temperatures ``temp_C`` (scalar or (n,); default t0), with the angular
        acceleration ``omega_dot_rad_s2`` ((n, 3); default 0: it matters only for lever
        arms across the sensing axes)."""
        return self._run(lib.gf_imu_apply, omega_rad_s, f_m_s2, temp_C, ("omega_rad_s", "f_m_s2"),
                         omega_dot_rad_s2)

    def compensate(self, gyro_out_rad_s, accel_out_m_s2, temp_C=None, omega_dot_rad_s2=None):
        """Rates and specific forces from sensor outputs: the exact inverse of apply
        (with the same ``omega_dot_rad_s2``)."""
        return self._run(lib.gf_imu_compensate, gyro_out_rad_s, accel_out_m_s2, temp_C,
                         ("gyro_out_rad_s", "accel_out_m_s2"), omega_dot_rad_s2)

    @staticmethod
    def rate_derivative(omega_rad_s, dt_s) -> np.ndarray:
        """The angular acceleration the increment methods use: the backward difference of
        consecutive mean rates (n, 3) over intervals ``dt_s`` (scalar or (n,)), 0 for the
        first sample (as the compensation of a stream can make it, gf_imu_compensate_step)."""
        w = np.asarray(omega_rad_s, float)
        dt = np.broadcast_to(np.asarray(dt_s, float), (w.shape[0],))
        out = np.zeros_like(w)
        out[1:] = np.diff(w, axis=0) / dt[1:, None]
        return out

    def apply_increments(self, dtheta_rad, dv_m_s, dt_s, temp_C=None, omega_dot_rad_s2=None):
        """Sensor increments of true increments over intervals dt_s (scalar or (n,)):
        the model applied to the mean rates over each interval, as the vehicle FMU and
        the calibration filter (gf_syscal) do. ``omega_dot_rad_s2``: the mean angular
        acceleration over each interval (a simulator knows it); default
        :meth:`rate_derivative` of the true rates, which makes
        :meth:`compensate_increments` the exact inverse."""
        dt = np.broadcast_to(np.asarray(dt_s, float), (np.shape(dtheta_rad)[0],))[:, None]
        w_true = np.asarray(dtheta_rad) / dt
        wd = omega_dot_rad_s2
        if wd is None and self.has_transverse_lever_arms:
            wd = self.rate_derivative(w_true, dt[:, 0])
        w, f = self.apply(w_true, np.asarray(dv_m_s) / dt, temp_C, wd)
        return w * dt, f * dt

    def compensate_increments(self, dtheta_rad, dv_m_s, dt_s, temp_C=None):
        """The inverse of :meth:`apply_increments` (mean rates over each interval; the
        angular acceleration from the compensated rates, :meth:`rate_derivative`)."""
        dt = np.broadcast_to(np.asarray(dt_s, float), (np.shape(dtheta_rad)[0],))[:, None]
        wo, fo = np.asarray(dtheta_rad) / dt, np.asarray(dv_m_s) / dt
        wd = None
        if self.has_transverse_lever_arms:
            w0, _ = self.compensate(wo, fo, temp_C)      # the rates do not depend on w_dot
            wd = self.rate_derivative(w0, dt[:, 0])
        w, f = self.compensate(wo, fo, temp_C, wd)
        return w * dt, f * dt


@dataclass
class ImuNoise:
    """Random errors of a gyro and an accelerometer triad, for simulation.

    Parameters (per axis, scalars apply to all three)
    ----------
    gyro_arw_deg_sqrt_h : angle random walk N: the rate noise per sample has std
        N / sqrt(dt) (N in rad/sqrt(s)); the integrated angle grows as N sqrt(t).
    gyro_bias_instability_deg_h, gyro_correlation_time_s : first-order Gauss-Markov
        bias: stationary std and correlation time.
    gyro_rrw_deg_h_sqrt_h : rate random walk K: the bias wanders as K sqrt(t).
    accel_vrw_ug_sqrt_hz : white specific-force noise as a one-sided amplitude spectral
        density; std per sample = ASD sqrt(fs / 2).
    accel_bias_instability_ug, accel_correlation_time_s : Gauss-Markov accelerometer bias.
    accel_rrw_ug_sqrt_s : random walk of the accelerometer bias (ug/sqrt(s)).
    gyro_band_deg_h, accel_band_ug, band_hz : band-limited noise: white noise through a
        first-order low-pass of corner band_hz, scaled to the given std.
    """

    gyro_arw_deg_sqrt_h: float = 0.0
    gyro_bias_instability_deg_h: float = 0.0
    gyro_correlation_time_s: float = 100.0
    gyro_rrw_deg_h_sqrt_h: float = 0.0
    accel_vrw_ug_sqrt_hz: float = 0.0
    accel_bias_instability_ug: float = 0.0
    accel_correlation_time_s: float = 100.0
    accel_rrw_ug_sqrt_s: float = 0.0
    gyro_band_deg_h: float = 0.0
    accel_band_ug: float = 0.0
    band_hz: float = 1.0

    def __post_init__(self):
        for k, v in self.__dict__.items():
            if not (np.isfinite(v) and v >= 0):
                raise ValueError(f"{k} must be finite and >= 0; got {v!r}")
        for k in ("gyro_correlation_time_s", "accel_correlation_time_s", "band_hz"):
            if not getattr(self, k) > 0:
                raise ValueError(f"{k} must be > 0")

    def fmu_parameters(self) -> dict:
        """The model as start values of the vehicle FMU (SI; its noise = 1 switches it
        on): the FMU draws from its own seeded generator with the same per-sample
        conventions as :meth:`sample` (csrc/sim/gf_noise.h)."""
        deg = np.pi / 180.0
        return dict(gyro_arw=self.gyro_arw_deg_sqrt_h * deg / 60.0,
                    gyro_bias_instability=self.gyro_bias_instability_deg_h * DEG_H,
                    gyro_correlation_time=self.gyro_correlation_time_s,
                    gyro_rrw=self.gyro_rrw_deg_h_sqrt_h * DEG_H / 60.0,
                    accel_vrw=self.accel_vrw_ug_sqrt_hz * UG,
                    accel_bias_instability=self.accel_bias_instability_ug * UG,
                    accel_correlation_time=self.accel_correlation_time_s,
                    accel_rrw=self.accel_rrw_ug_sqrt_s * UG,
                    gyro_band=self.gyro_band_deg_h * DEG_H, accel_band=self.accel_band_ug * UG,
                    band_hz=self.band_hz)

    @staticmethod
    def _gauss_markov(n, dt, sigma, tau, rng):
        # the first-order low-pass recursion with a = exp(-dt/tau), i.e. corner 1/(2 pi tau)
        return first_order_lowpass_noise(n, 3, sigma, 1.0 / (2 * np.pi * tau), dt, rng)

    def sample_parts(self, n: int, dt_s: float, rng: np.random.Generator) -> dict:
        """The noise of :meth:`sample` by component, each (n, 3): ``gyro_white``,
        ``gyro_bias`` (Gauss-Markov + rate random walk, rad/s), ``gyro_band``,
        ``accel_white``, ``accel_bias`` (m/s^2), ``accel_band``. The bias parts are what an
        integrated-navigation filter estimates (its truth in simulations)."""
        if n < 0 or not (np.isfinite(dt_s) and dt_s > 0):
            raise ValueError("n must be >= 0 and dt_s finite and > 0")
        deg = np.pi / 180.0
        out = {}
        out["gyro_white"] = rng.normal(0.0, self.gyro_arw_deg_sqrt_h * deg / 60.0 / np.sqrt(dt_s), (n, 3))
        out["gyro_bias"] = self._gauss_markov(n, dt_s, self.gyro_bias_instability_deg_h * DEG_H,
                                              self.gyro_correlation_time_s, rng)
        if self.gyro_rrw_deg_h_sqrt_h:
            K = self.gyro_rrw_deg_h_sqrt_h * DEG_H / 60.0     # rad/s per sqrt(s)
            out["gyro_bias"] = out["gyro_bias"] + np.cumsum(rng.normal(0.0, K * np.sqrt(dt_s), (n, 3)), axis=0)
        out["accel_white"] = rng.normal(0.0, self.accel_vrw_ug_sqrt_hz * UG * np.sqrt(0.5 / dt_s), (n, 3))
        out["accel_bias"] = self._gauss_markov(n, dt_s, self.accel_bias_instability_ug * UG,
                                               self.accel_correlation_time_s, rng)
        if self.accel_rrw_ug_sqrt_s:
            out["accel_bias"] = out["accel_bias"] + np.cumsum(
                rng.normal(0.0, self.accel_rrw_ug_sqrt_s * UG * np.sqrt(dt_s), (n, 3)), axis=0)
        out["gyro_band"] = first_order_lowpass_noise(n, 3, self.gyro_band_deg_h * DEG_H, self.band_hz, dt_s, rng)
        out["accel_band"] = first_order_lowpass_noise(n, 3, self.accel_band_ug * UG, self.band_hz, dt_s, rng)
        return out

    def sample(self, n: int, dt_s: float, rng: np.random.Generator):
        """Noise to add to rates (rad/s) and specific forces (m/s^2): two (n, 3) arrays."""
        p = self.sample_parts(n, dt_s, rng)
        return (p["gyro_white"] + p["gyro_bias"] + p["gyro_band"],
                p["accel_white"] + p["accel_bias"] + p["accel_band"])


def seed001_gyro_misalignment(gamma_yz: float, gamma_zy: float, gamma_zx: float) -> np.ndarray:
    """Cross-coupling N_g (3 x 3, same unit as the angles) of seed 001's three gyro
    angles: x_g = x_m; y_g turned about z_m by gamma_yz; z_g turned about x_m by gamma_zx
    and about y_m by gamma_zy (right-handed rotations of the m axes; the seed's matrix
    image is lost, so this states the convention used). Gyro i measures the rate along
    its axis e_g,i, so row i of I + N is e_g,i in m axes, to first order."""
    return np.array([[0.0, 0.0, 0.0],
                     [-gamma_yz, 0.0, 0.0],
                     [gamma_zy, -gamma_zx, 0.0]])


def seed001_accel_misalignment(a_xz: float, a_xy: float, a_yz: float, a_yx: float,
                               a_zy: float, a_zx: float) -> np.ndarray:
    """Cross-coupling N_a of seed 001's six accelerometer angles (alpha_ij: axis i turned
    about the m frame's axis j, right-handed), first order, same unit as the angles."""
    return np.array([[0.0, a_xz, -a_xy],
                     [-a_yz, 0.0, a_yx],
                     [a_zy, -a_zx, 0.0]])
