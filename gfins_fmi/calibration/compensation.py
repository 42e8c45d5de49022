"""The two conventions of an IMU's calibration and the conversion between them
(docs/calibration_conventions.md).

* **Forward model** (ours, :class:`gfins_fmi.ImuErrors`, csrc/nav/gf_imu_error.h): sensor
  = model(truth) in the IMU frame m, w_out = D_g (I + N_g) w + b_g; the accelerometers
  a = D_a u + K2 o u^2 + b_a with u = (I + N_a) f_d + lever terms, f_d the specific force
  sampled d late. Seed 001's parameters take m as the *gyro* frame (x_m = x_g, y_m in the
  x_g-y_g plane: N_g lower triangular).
* **Compensation form** (what most laboratory tools report, PSINS's ``clbt`` fields):
  truth = model^-1(sensor) in the *accelerometer* frame c (Ka lower triangular: x_c = x_a,
  y_c in the x_a-y_a plane):
      w = Kg w_out - eb,      f = Ka a - db - Ka2 o a^2 - fL - tGA (w x f),
      fL_i = e_i^T W r_i,  W = [w_dot x] + [w x]^2,  r_x, r_y, r_z the accelerometers'
      positions (rz = 0 puts the reference point at the z accelerometer).

The conversion (:func:`to_compensation`, :func:`from_compensation`) is exact and
invertible: the frame change is the rotation Q that makes the other triad's matrix lower
triangular (an RQ decomposition, unique with a positive diagonal), v^c = Q v^m; then
Kg = (M_g Q^T)^-1, eb = Kg b_g, Ka = (M_a Q^T)^-1, db = Ka b_a, Ka2 = K2^c / D_c^3 (the
quadratic on the raw output: a_i = y_i + K2_i y_i^2 / D_i^2 + b_i with y = M f, to first
order f = Ka (a - b) - Ka2 o a^2), positions r^c = Q r^m, tGA = d. Both directions
round-trip to round-off (tests/calibration/test_compensation.py: 1e-12 relative). What is
*not* exact is the equality of the two *functions*: they agree to first order in the
errors (second-order differences: K2 against N and b, the lever terms against N; all
below 1e-8 g for a navigation-grade IMU). The delay: PSINS's C++ compensation
(CIMU::Update) and imuclbt subtract tGA (w x f), as here; its imutclbt adds it — check the
sign of any other tool's tGA on a record with a known delay.

Files: JSON or TOML with the PSINS field names in SI (Kg, eb rad/s, Ka, db m/s^2, Ka2
s^2/m, rx, ry, rz m, tGA s) and the rotation from the gyro frame; and PSINS's flat array
of 37 values [Kg row-major (9), eb, Ka row-major (9), db, Ka2, rx, ry, rz, tGA] as text
(one value a line or whitespace-separated) or binary float64 (clbtfile's ``.bin``).
"""
from __future__ import annotations

import json
import pathlib
from dataclasses import dataclass

import numpy as np

from gfins_fmi.nav.imu_errors import ARCSEC, DEG_H, G0, PPM, UG, ImuErrors

try:                       # the standard library's TOML reader (Python >= 3.11)
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.9 / 3.10
    tomllib = None

__all__ = ["CompensationForm", "frame_rotation", "rotate_frame", "to_gyro_frame",
           "to_compensation", "from_compensation", "read_compensation", "write_compensation",
           "laboratory_example", "random_compensation"]

_FIELDS = ("Kg", "eb", "Ka", "db", "Ka2", "rx", "ry", "rz", "tGA")
_SHAPES = {"Kg": (3, 3), "eb": (3,), "Ka": (3, 3), "db": (3,), "Ka2": (3,), "rx": (3,), "ry": (3,),
           "rz": (3,), "tGA": ()}
_UNITS = {"Kg": "1", "eb": "rad/s", "Ka": "1", "db": "m/s^2", "Ka2": "s^2/m", "rx": "m", "ry": "m",
          "rz": "m", "tGA": "s"}


@dataclass(frozen=True)
class CompensationForm:
    """An IMU calibration in the compensation form (PSINS ``clbt``), SI: ``Kg`` (3, 3),
    ``eb`` rad/s, ``Ka`` (3, 3), ``db`` m/s^2, ``Ka2`` s^2/m, ``rx``, ``ry``, ``rz`` m,
    ``tGA`` s; ``rotation_rad``: the small rotation from the forward model's frame to
    this one's (v^c = Q v^m, Q = exp([rotation x])), informational."""
    Kg: np.ndarray
    eb: np.ndarray
    Ka: np.ndarray
    db: np.ndarray
    Ka2: np.ndarray
    rx: np.ndarray
    ry: np.ndarray
    rz: np.ndarray
    tGA: float = 0.0
    rotation_rad: np.ndarray = None

    def __post_init__(self):
        for k in _FIELDS:
            v = np.array(getattr(self, k), float)
            if v.shape != _SHAPES[k] or not np.all(np.isfinite(v)):
                raise ValueError(f"compensation form: {k} must be finite with shape {_SHAPES[k]}; "
                                 f"got {np.shape(getattr(self, k))}")
            object.__setattr__(self, k, float(v) if k == "tGA" else v)
        r = np.zeros(3) if self.rotation_rad is None else np.asarray(self.rotation_rad, float)
        object.__setattr__(self, "rotation_rad", r)

    def to_array(self) -> np.ndarray:
        """PSINS's flat layout (37): [Kg row-major, eb, Ka row-major, db, Ka2, rx, ry, rz, tGA]."""
        return np.concatenate([self.Kg.ravel(), self.eb, self.Ka.ravel(), self.db, self.Ka2,
                               self.rx, self.ry, self.rz, [self.tGA]])

    @classmethod
    def from_array(cls, a) -> "CompensationForm":
        a = np.asarray(a, float).ravel()
        if a.size != 37:
            raise ValueError(f"the PSINS calibration array holds 37 values (Kg 9, eb 3, Ka 9, db 3, Ka2 3, "
                             f"rx 3, ry 3, rz 3, tGA 1); got {a.size}")
        return cls(a[0:9].reshape(3, 3), a[9:12], a[12:21].reshape(3, 3), a[21:24], a[24:27],
                   a[27:30], a[30:33], a[33:36], float(a[36]))

    def to_dict(self) -> dict:
        d = {k: (getattr(self, k).tolist() if k != "tGA" else self.tGA) for k in _FIELDS}
        d["units"] = dict(_UNITS)
        d["rotation_from_gyro_frame_rad"] = self.rotation_rad.tolist()
        d["convention"] = ("w = Kg w_out - eb; f = Ka a - db - Ka2 o a^2 - fL - tGA (w x f), "
                           "fL_i = e_i^T ([w_dot x] + [w x]^2) r_i; accelerometer frame (Ka lower "
                           "triangular); gfins_fmi docs/calibration_conventions.md")
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "CompensationForm":
        missing = [k for k in _FIELDS if k not in d and k not in ("rz", "tGA")]
        if missing:
            raise ValueError(f"compensation form: missing {', '.join(missing)} (fields: {', '.join(_FIELDS)}, SI)")
        return cls(*(d.get(k, np.zeros(3) if k == "rz" else 0.0) for k in _FIELDS),
                   rotation_rad=d.get("rotation_from_gyro_frame_rad"))

    def text(self) -> str:
        """The fields in the units PSINS's clbtfile shows (eb deg/h, db ug, Ka2 ug/g^2,
        rx ry rz cm, tGA ms)."""
        def m(a):
            return "\n".join("  " + " ".join(f"{x: .9f}" for x in row) for row in a)
        def v(a, k):
            return "  " + " ".join(f"{x / k: .6g}" for x in a)
        return "\n".join(["Kg", m(self.Kg), "eb (deg/h)", v(self.eb, DEG_H), "Ka", m(self.Ka),
                          "db (ug)", v(self.db, UG), "Ka2 (ug/g^2)", v(self.Ka2, 1e-6 / G0),
                          "rx, ry, rz (cm)", v(self.rx, 0.01), v(self.ry, 0.01), v(self.rz, 0.01),
                          f"tGA (ms)\n  {self.tGA * 1e3:.6g}"])


def laboratory_example() -> CompensationForm:
    """The error set a laboratory tool injects by default (PSINS's ``imuclbt`` example):
    gyro scale 10, 20, 30 ppm and misalignment 10-60 arcsec (any off-diagonal), bias 0.1,
    0.2, 0.3 deg/h; accelerometer scale 10, 20, 30 ppm, lower-triangular misalignment
    10-30 arcsec, bias 10, 20, 30 ug, K_a2 10, 20, 30 ug/g^2; the x accelerometer at
    [1, 2, 3] cm and the y accelerometer at [4, 5, 6] cm from the z accelerometer; delay
    1 ms. (The values as that tool writes them; here they are the compensation form.)"""
    sec, ppm = ARCSEC, PPM
    return CompensationForm(
        Kg=np.eye(3) - np.diag([10.0, 20.0, 30.0]) * ppm + np.array([[0, 10, 20], [30, 0, 40], [50, 60, 0]]) * sec,
        eb=np.array([0.1, 0.2, 0.3]) * DEG_H,
        Ka=np.eye(3) - np.diag([10.0, 20.0, 30.0]) * ppm + np.array([[0, 0, 0], [10, 0, 0], [20, 30, 0]]) * sec,
        db=np.array([10.0, 20.0, 30.0]) * UG, Ka2=np.array([10.0, 20.0, 30.0]) * 1e-6 / G0,
        rx=np.array([1.0, 2.0, 3.0]) / 100, ry=np.array([4.0, 5.0, 6.0]) / 100, rz=np.zeros(3), tGA=1e-3)


def random_compensation(rng: np.random.Generator) -> CompensationForm:
    """A random error set at the magnitudes of :func:`laboratory_example` (a Monte Carlo's
    truth): every value of magnitude uniform in the example's range with a random sign
    (scale 10-30 ppm, gyro misalignment 0-60 arcsec off the diagonal, accelerometer 0-30
    arcsec below it, gyro bias 0.1-0.3 deg/h, accelerometer bias 10-30 ug, K_a2 10-30
    ug/g^2, lever-arm components 1-6 cm, delay 0.5-1.5 ms)."""
    def signed(lo, hi, shape):
        return rng.uniform(lo, hi, shape) * rng.choice([-1.0, 1.0], shape)
    off_g = signed(0, 60, (3, 3)) * ARCSEC
    np.fill_diagonal(off_g, 0.0)
    off_a = np.tril(signed(0, 30, (3, 3)), -1) * ARCSEC
    return CompensationForm(np.eye(3) + np.diag(signed(10, 30, 3)) * PPM + off_g,
                            signed(0.1, 0.3, 3) * DEG_H,
                            np.eye(3) + np.diag(signed(10, 30, 3)) * PPM + off_a,
                            signed(10, 30, 3) * UG, signed(10, 30, 3) * 1e-6 / G0,
                            signed(1, 6, 3) / 100, signed(1, 6, 3) / 100, np.zeros(3),
                            float(rng.uniform(0.5, 1.5)) * 1e-3)


# ---- frames ---------------------------------------------------------------------------

def _matrices(e: ImuErrors):
    c = e._c
    Ng = np.array(list(c.g_misalign_rad)).reshape(3, 3)
    Na = np.array(list(c.a_misalign_rad)).reshape(3, 3)
    Mg = np.diag(1.0 + np.array(list(c.g_scale))) @ (np.eye(3) + Ng)
    Ma = np.diag(1.0 + np.array(list(c.a_scale))) @ (np.eye(3) + Na)
    return Mg, Ma


def _rq_lower(M: np.ndarray) -> np.ndarray:
    """Q (orthogonal, det +1) with M Q^T lower triangular with a positive diagonal."""
    q, r = np.linalg.qr(M.T)                    # M^T = q r  ->  M = r^T q^T, r^T lower
    s = np.sign(np.diag(r))
    s[s == 0] = 1.0
    q, r = q * s, (r.T * s).T                   # positive diagonal
    return q.T


def frame_rotation(errors: ImuErrors, triad: str = "gyro") -> np.ndarray:
    """Q with v^c = Q v^m: the frame in which the ``triad``'s ("gyro" or "accel") matrix
    D (I + N) is lower triangular (x along its x sensor, y in the plane of its x and y)."""
    Mg, Ma = _matrices(errors)
    return _rq_lower(Mg if triad == "gyro" else Ma)


def _rotvec(Q: np.ndarray) -> np.ndarray:
    a = np.arccos(np.clip((np.trace(Q) - 1.0) / 2.0, -1.0, 1.0))
    v = np.array([Q[2, 1] - Q[1, 2], Q[0, 2] - Q[2, 0], Q[1, 0] - Q[0, 1]])
    return v * (0.5 if a < 1e-8 else a / (2.0 * np.sin(a)))


def _split(M: np.ndarray):
    D = np.diag(M).copy()
    N = M / D[:, None] - np.eye(3)
    np.fill_diagonal(N, 0.0)
    return D - 1.0, N


def rotate_frame(errors: ImuErrors, Q) -> ImuErrors:
    """The same IMU's forward model in the frame c, v^c = Q v^m (Q orthogonal): M' = M Q^T
    for both triads, positions Q r, K2 kept on the same physical quadratic (K2' = K2 D'^2 /
    D^2); biases, delay and temperature terms unchanged (reference temperature only)."""
    Q = np.asarray(Q, float)
    if Q.shape != (3, 3) or not np.allclose(Q @ Q.T, np.eye(3), atol=1e-12):
        raise ValueError("Q must be a 3 x 3 rotation matrix")
    c = errors._c
    if c.temp_order:
        raise ValueError("rotate_frame: the model has temperature coefficients; rotate at the "
                         "reference temperature only")
    Mg, Ma = _matrices(errors)
    sg, Ng = _split(Mg @ Q.T)
    sa, Na = _split(Ma @ Q.T)
    Da = 1.0 + np.array(list(c.a_scale))
    k2 = np.array(list(c.a_k2_s2_m)) * ((1.0 + sa) / Da) ** 2
    pos = np.array(list(c.a_lever_pos_m)).reshape(3, 3) @ Q.T        # rows r_i -> (Q r_i)^T
    return ImuErrors(gyro_bias_deg_h=np.array(list(c.g_bias_rad_s)) / DEG_H, gyro_scale_ppm=sg / PPM,
                     gyro_misalignment_arcsec=Ng / ARCSEC, accel_bias_ug=np.array(list(c.a_bias_m_s2)) / UG,
                     accel_scale_ppm=sa / PPM, accel_misalignment_arcsec=Na / ARCSEC,
                     accel_k2_ug_g2=k2 / (1e-6 / G0), lever_arm_cm=pos / 0.01, t0_C=errors.t0_C,
                     accel_delay_ms=float(c.a_delay_s) * 1e3)


def to_gyro_frame(errors: ImuErrors) -> tuple:
    """(the model in its gyro frame, Q): N_g lower triangular, as seed 001's parameters
    need (:func:`gfins_fmi.calibration.syscal_filter.imu_errors_to_params`); Q rotates the
    given frame's coordinates into it (the navigation attitude of the IMU frame changes by
    the same rotation)."""
    Q = frame_rotation(errors, "gyro")
    return rotate_frame(errors, Q), Q


# ---- forward <-> compensation ---------------------------------------------------------------

def to_compensation(errors: ImuErrors) -> CompensationForm:
    """The compensation form (accelerometer frame) of a forward model."""
    Q = frame_rotation(errors, "accel")
    e = rotate_frame(errors, Q)
    c = e._c
    Mg, Ma = _matrices(e)
    Kg, Ka = np.linalg.inv(Mg), np.linalg.inv(Ma)
    Ka = np.tril(Ka)                       # exactly lower triangular (the frame makes it so)
    Da = 1.0 + np.array(list(c.a_scale))
    pos = np.array(list(c.a_lever_pos_m)).reshape(3, 3)
    return CompensationForm(Kg, Kg @ np.array(list(c.g_bias_rad_s)), Ka, Ka @ np.array(list(c.a_bias_m_s2)),
                            np.array(list(c.a_k2_s2_m)) / Da ** 3, pos[0], pos[1], pos[2],
                            float(c.a_delay_s), rotation_rad=_rotvec(Q))


def from_compensation(cf: CompensationForm, frame: str = "gyro") -> ImuErrors:
    """The forward model of a compensation form, in the gyro frame (``frame="gyro"``, seed
    001's parameters; the default) or in the compensation form's own frame ("accel")."""
    Mg, Ma = np.linalg.inv(cf.Kg), np.linalg.inv(cf.Ka)
    sg, Ng = _split(Mg)
    sa, Na = _split(Ma)
    e = ImuErrors(gyro_bias_deg_h=Mg @ cf.eb / DEG_H, gyro_scale_ppm=sg / PPM,
                  gyro_misalignment_arcsec=Ng / ARCSEC, accel_bias_ug=Ma @ cf.db / UG,
                  accel_scale_ppm=sa / PPM, accel_misalignment_arcsec=Na / ARCSEC,
                  accel_k2_ug_g2=cf.Ka2 * (1.0 + sa) ** 3 / (1e-6 / G0),
                  lever_arm_cm=np.array([cf.rx, cf.ry, cf.rz]) / 0.01, accel_delay_ms=cf.tGA * 1e3)
    if frame == "accel":
        return e
    if frame != "gyro":
        raise ValueError(f"frame must be 'gyro' or 'accel'; got {frame!r}")
    return to_gyro_frame(e)[0]


# ---- files ------------------------------------------------------------------------------

def _toml(d: dict) -> str:
    lines = ["# IMU calibration, compensation form (PSINS clbt fields), SI units",
             f"# {d['convention']}"]
    for k in _FIELDS + ("rotation_from_gyro_frame_rad",):
        v = d[k]
        lines.append(f"{k} = {json.dumps(v)}")
    lines.append("[units]")
    lines += [f'{k} = "{u}"' for k, u in d["units"].items()]
    return "\n".join(lines) + "\n"


def write_compensation(cf: CompensationForm, path) -> pathlib.Path:
    """Write ``cf`` by the suffix of ``path``: ``.json``, ``.toml``, ``.bin`` (PSINS's 37
    float64) or anything else as text (PSINS's 37 values, one a line)."""
    path = pathlib.Path(path)
    suffix = path.suffix.lower()
    if suffix == ".json":
        path.write_text(json.dumps(cf.to_dict(), indent=1) + "\n", encoding="utf-8")
    elif suffix == ".toml":
        path.write_text(_toml(cf.to_dict()), encoding="utf-8")
    elif suffix == ".bin":
        cf.to_array().astype("<f8").tofile(path)
    else:
        path.write_text("\n".join(repr(float(x)) for x in cf.to_array()) + "\n", encoding="utf-8")
    return path


def read_compensation(path) -> CompensationForm:
    """Read a compensation form written by :func:`write_compensation` or by PSINS (its 37
    values as ``.bin`` float64 or as text)."""
    path = pathlib.Path(path)
    suffix = path.suffix.lower()
    if suffix == ".json":
        return CompensationForm.from_dict(json.loads(path.read_text(encoding="utf-8")))
    if suffix == ".toml":
        if tomllib is None:
            raise ValueError(f"{path}: reading TOML needs Python >= 3.11 (tomllib); use .json")
        return CompensationForm.from_dict(tomllib.loads(path.read_text(encoding="utf-8")))
    if suffix == ".bin":
        return CompensationForm.from_array(np.fromfile(path, dtype="<f8"))
    return CompensationForm.from_array(np.array(path.read_text(encoding="utf-8").split(), float))
