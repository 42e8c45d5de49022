"""Accelerometer arrays for gyro-free inertial navigation (seed 000, Qin, Xu, Li).

Output of single-axis accelerometer i at body position ``u_i`` (m) with unit sensing
direction ``theta_i``::

    A_i = theta_i . [ f + omega_dot x u_i + omega x (omega x u_i) ]      (m/s^2)

``f`` is the specific force at the array centre (m/s^2, gravity enters through it),
``omega`` the body rate (rad/s) and ``omega_dot`` its derivative (rad/s^2), all in body
axes. The solver of the 9-accelerometer layout recovers f (eq. 3), omega^2 (eq. 4) and
omega_dot (eq. 6) as linear combinations of the outputs; |omega| comes from omega^2 and
its sign from omega_dot integrated (trapezoid) from omega_init, the rate at the first
sample.

All numerics run in the C core, one call per record.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gfins_fmi._lib import (NonFiniteInputError, SampleError, as_positive_scalar, as_rows,
                            as_start_index, as_vector3, check_status, done_before, ffi,
                            first_nonfinite, lib, ptr, status_text)
from gfins_fmi.nav.plausibility import interval_problem, report

__all__ = ["ArrayGeometry", "accel9_geometry", "forward_model", "Accel9Solution",
           "Accel9Solver", "solve_accel9", "FLAG_NEG_OMEGA_SQ", "FLAG_SIGN_UNKNOWN",
           "MAX_SENSORS", "MAX_RATE_RAD_S", "MAX_SPECIFIC_FORCE_M_S2"]

MAX_SENSORS: int = int(lib.GF_ARRAY_MAX_SENSORS)
#: smallest lever arm the solvers accept (m): below it 1/l turns round-off into rates
MIN_LEVER_ARM_M: float = 1e-6
#: physical limits of the 9-accelerometer solver (the navigators' defaults, SinsConfig):
#: samples whose rate or specific force go beyond them are refused as absurd
MAX_RATE_RAD_S: float = float(lib.GF9_MAX_RATE_RAD_S)
MAX_SPECIFIC_FORCE_M_S2: float = float(lib.GF9_MAX_SPECIFIC_FORCE_M_S2)
#: flags bits 0..2: omega_k^2 < 0 (noise); the rate component was propagated from omega_dot
FLAG_NEG_OMEGA_SQ: tuple[int, int, int] = (int(lib.GF9_FLAG_NEG_OMEGA_SQ_X),
                                           int(lib.GF9_FLAG_NEG_OMEGA_SQ_Y),
                                           int(lib.GF9_FLAG_NEG_OMEGA_SQ_Z))
#: flags bits 3..5: the propagated rate was exactly 0, so the sign was taken positive
FLAG_SIGN_UNKNOWN: tuple[int, int, int] = (int(lib.GF9_FLAG_SIGN_UNKNOWN_X),
                                           int(lib.GF9_FLAG_SIGN_UNKNOWN_Y),
                                           int(lib.GF9_FLAG_SIGN_UNKNOWN_Z))


@dataclass(frozen=True, eq=False)
class ArrayGeometry:
    """Geometry of an array of N single-axis accelerometers.

    Parameters
    ----------
    u_m : array_like, shape (N, 3)
        Sensor positions in body axes, m.
    theta : array_like, shape (N, 3)
        Unit sensing directions (|theta_i| = 1 within 1e-9).

    Raises
    ------
    ValueError
        Wrong shapes, N outside 1..MAX_SENSORS, a non-finite entry, a zero or
        non-unit sensing direction (the message names the sensor).
    """

    u_m: np.ndarray
    theta: np.ndarray
    _c: object = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        u = as_rows("u_m", self.u_m, 3, "m")
        t = as_rows("theta", self.theta, 3, "unit vectors")
        if u.shape[0] != t.shape[0]:
            raise ValueError(f"u_m has {u.shape[0]} sensors but theta has {t.shape[0]}")
        c = ffi.new("gf_array_geometry *")
        bad = ffi.new("size_t *")
        n = u.shape[0]
        status = lib.gf_array_geometry_set(c, n, ptr(u, 3 * n), ptr(t, 3 * n), bad)
        if status != lib.GF_OK:
            i = int(bad[0])
            if status == lib.GF_ERR_BAD_SIZE:
                msg = f"the array must have 1..{MAX_SENSORS} sensors; got {u.shape[0]}"
            elif status == lib.GF_ERR_NONFINITE_INPUT:
                msg = f"sensor {i}: position or direction is not finite"
            elif status == lib.GF_ERR_SINGULAR_GEOMETRY:
                msg = f"sensor {i}: the sensing direction is zero"
            elif status == lib.GF_ERR_BAD_PARAMETER:
                msg = (f"sensor {i}: the sensing direction {t[i].tolist()} has norm "
                       f"{np.linalg.norm(t[i]):.12g}; normalise it to 1")
            else:
                msg = status_text(status)
            raise ValueError(msg)
        u.setflags(write=False)
        t.setflags(write=False)
        object.__setattr__(self, "u_m", u)
        object.__setattr__(self, "theta", t)
        object.__setattr__(self, "_c", c)

    def __reduce__(self):
        # pickled as its positions and directions (the C struct is rebuilt from them),
        # so a Monte-Carlo task that captured a geometry can be shipped to a worker process
        return (ArrayGeometry, (self.u_m, self.theta))

    @property
    def n_sensors(self) -> int:
        """Number of accelerometers N."""
        return int(self.u_m.shape[0])


def _lever_arm(l_m) -> float:
    l_m = as_positive_scalar("l_m (lever arm)", l_m, "m")
    if l_m < MIN_LEVER_ARM_M:
        raise ValueError(f"l_m (lever arm) = {l_m!r} m is below {MIN_LEVER_ARM_M:g} m: the "
                         "solution divides by l, so such an array only amplifies round-off")
    return l_m


def accel9_geometry(l_m: float) -> ArrayGeometry:
    """The 9-accelerometer layout of seed 000 with lever arm ``l_m`` (m).

    Sensors 1-3 at l e_x, l e_y, l e_z sensing along those axes, 4-6 opposite and
    sensing outward, 7-9 at l[1,-1,0], l[1,0,-1], l[0,1,-1] sensing along
    [1,1,0]/sqrt2, [1,0,1]/sqrt2, [0,1,1]/sqrt2.
    """
    l_m = _lever_arm(l_m)
    c = ffi.new("gf_array_geometry *")
    check_status(lib.gf9_geometry(l_m, c), "gf9_geometry")
    u = np.array([[c.u_m[i][k] for k in range(3)] for i in range(9)])
    t = np.array([[c.theta[i][k] for k in range(3)] for i in range(9)])
    return ArrayGeometry(u, t)


def forward_model(geometry: ArrayGeometry, f_m_s2, omega_rad_s, omega_dot_rad_s2) -> np.ndarray:
    """Accelerometer outputs of a rigid-body motion.

    Parameters
    ----------
    geometry : ArrayGeometry
        The array (N sensors).
    f_m_s2, omega_rad_s, omega_dot_rad_s2 : array_like, shape (n, 3)
        Specific force at the centre (m/s^2), body rate (rad/s) and angular
        acceleration (rad/s^2) per sample, body axes.

    Returns
    -------
    numpy.ndarray, shape (n, N)
        Outputs A_i in m/s^2.

    Raises
    ------
    NonFiniteInputError
        A sample holds NaN/Inf (``index`` names it; ``partial`` holds the rows before).
    """
    if not isinstance(geometry, ArrayGeometry):
        raise TypeError("geometry must be an ArrayGeometry (e.g. accel9_geometry(l_m))")
    f = as_rows("f_m_s2", f_m_s2, 3, "m/s^2")
    w = as_rows("omega_rad_s", omega_rad_s, 3, "rad/s")
    wd = as_rows("omega_dot_rad_s2", omega_dot_rad_s2, 3, "rad/s^2")
    n = f.shape[0]
    if w.shape[0] != n or wd.shape[0] != n:
        raise ValueError(f"f, omega and omega_dot must have the same number of samples; "
                         f"got {n}, {w.shape[0]}, {wd.shape[0]}")
    A = np.empty((n, geometry.n_sensors))
    done = ffi.new("size_t *")
    status = lib.gf_array_forward(geometry._c, n, ptr(f, 3 * n), ptr(w, 3 * n), ptr(wd, 3 * n),
                                  ptr(A, n * geometry.n_sensors), done)
    if status == lib.GF_ERR_NONFINITE_INPUT:
        k = int(done[0])
        for name, arr in (("f_m_s2", f), ("omega_rad_s", w), ("omega_dot_rad_s2", wd)):
            col = first_nonfinite(arr, k)
            if col >= 0:
                raise NonFiniteInputError(f"{name}[{k}, {col}] = {arr[k, col]} is not finite; "
                                          + done_before(k, verb="computed"),
                                          k, col, A[:k].copy())
    if status == lib.GF_ERR_OUT_OF_RANGE:
        k = int(done[0])
        raise NonFiniteInputError(f"sample {k}: the outputs overflow (inputs too large for a "
                                  "double); " + done_before(k, verb="computed"),
                                  k, -1, A[:k].copy())
    check_status(status, "forward model")
    return A


@dataclass
class Accel9Solution:
    """Solution of a record by the 9-accelerometer solver (one row per sample).

    Attributes
    ----------
    f_m_s2 : ndarray (n, 3)
        Specific force at the array centre, eq. 3.
    omega_rad_s : ndarray (n, 3)
        Angular rate; magnitude from eq. 4, sign from eq. 6 integrated.
    omega_dot_rad_s2 : ndarray (n, 3)
        Angular acceleration, eq. 6.
    omega_sq_rad2_s2 : ndarray (n, 3)
        Squared rates as measured, eq. 4 (negative under noise near zero rate).
    flags : ndarray (n,), uint8
        Bits ``FLAG_NEG_OMEGA_SQ`` (rate propagated from omega_dot because
        omega_k^2 < 0) and ``FLAG_SIGN_UNKNOWN`` (sign taken positive).
    """

    f_m_s2: np.ndarray
    omega_rad_s: np.ndarray
    omega_dot_rad_s2: np.ndarray
    omega_sq_rad2_s2: np.ndarray
    flags: np.ndarray

    def __len__(self) -> int:
        return int(self.flags.shape[0])

    def flag_counts(self) -> dict[str, int]:
        """Number of samples carrying each flag, by name."""
        names = {}
        for axis, bit in zip("xyz", FLAG_NEG_OMEGA_SQ):
            names[f"neg_omega_sq_{axis}"] = int(np.count_nonzero(self.flags & bit))
        for axis, bit in zip("xyz", FLAG_SIGN_UNKNOWN):
            names[f"sign_unknown_{axis}"] = int(np.count_nonzero(self.flags & bit))
        return names

    def _head(self, n: int) -> "Accel9Solution":
        return Accel9Solution(self.f_m_s2[:n].copy(), self.omega_rad_s[:n].copy(),
                              self.omega_dot_rad_s2[:n].copy(),
                              self.omega_sq_rad2_s2[:n].copy(), self.flags[:n].copy())


class Accel9Solver:
    """Streaming 9-accelerometer solver: each :meth:`solve` call continues the last.

    Parameters
    ----------
    l_m : float
        Lever arm l (m), > 0.
    omega_init_rad_s : array_like, shape (3,)
        Rate at the first sample (rad/s): its signs are the first signs and the
        integral of omega_dot that gives every later sign starts from it, so give the
        best value known, not just signs. Default zero (first signs positive, flagged
        where ambiguous). At most :data:`MAX_RATE_RAD_S` in magnitude.

    Samples are refused (:class:`~gfins_fmi.SampleError`) beyond the physical limits
    the navigators apply (:data:`MAX_RATE_RAD_S`, :data:`MAX_SPECIFIC_FORCE_M_S2`):
    specific force, measured |omega|^2, or the rate output (the integrated reference
    where omega_k^2 < 0).
    """

    def __init__(self, l_m: float, omega_init_rad_s=(0.0, 0.0, 0.0)):
        self.l_m = _lever_arm(l_m)
        w0 = as_vector3("omega_init_rad_s", omega_init_rad_s, "rad/s")
        if not np.linalg.norm(w0) <= MAX_RATE_RAD_S:
            raise ValueError(f"omega_init_rad_s = {w0.tolist()} exceeds the physical limit "
                             f"|omega| <= {MAX_RATE_RAD_S:g} rad/s")
        self._state = ffi.new("gf9_state *")
        check_status(lib.gf9_init(self._state, self.l_m, ptr(w0, 3)), "gf9_init")
        self._looked = False     # the record's interval checked against its rates (solve)

    @property
    def n_samples(self) -> int:
        """Samples solved so far."""
        return int(self._state.n_samples)

    def solve(self, A_m_s2, dt_s: float, *, start_index: int = 0) -> Accel9Solution:
        """Solve a record of accelerometer outputs in one C call.

        Parameters
        ----------
        A_m_s2 : array_like, shape (n, 9)
            Outputs of accelerometers 1..9 (m/s^2), one row per sample.
        dt_s : float
            Sampling interval (s), > 0.
        start_index : int
            When a record is solved in pieces: the index of this piece's first sample
            in the record. Error messages and the exceptions' ``index`` count from the
            record's start; ``partial`` holds this call's samples before the bad one.

        Returns
        -------
        Accel9Solution

        Raises
        ------
        NonFiniteInputError
            A sample holds NaN/Inf; ``.index``/``.column`` locate it and ``.partial``
            holds the solution of the samples before it (the solver state continues
            from the last good sample).
        SampleError
            A sample beyond the physical limits (or whose solution overflows); same
            ``.index`` and ``.partial``.
        """
        A = as_rows("A_m_s2", A_m_s2, 9, "m/s^2")
        dt_s = as_positive_scalar("dt_s (sampling interval)", dt_s, "s")
        s0 = as_start_index(start_index)
        n = A.shape[0]
        out = Accel9Solution(np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)),
                             np.empty((n, 3)), np.empty(n, dtype=np.uint8))
        done = ffi.new("size_t *")
        status = lib.gf9_solve(self._state, n, ptr(A, 9 * n), dt_s, ptr(out.f_m_s2, 3 * n),
                               ptr(out.omega_rad_s, 3 * n), ptr(out.omega_dot_rad_s2, 3 * n),
                               ptr(out.omega_sq_rad2_s2, 3 * n), ptr(out.flags, n, "uint8_t"),
                               done)
        if status == lib.GF_ERR_NONFINITE_INPUT:
            k = int(done[0])
            col = first_nonfinite(A, k)
            raise NonFiniteInputError(
                f"A_m_s2[{s0 + k}, {col}] = {A[k, col]} (accelerometer {col + 1}) is not finite; "
                + done_before(k, s0), s0 + k, col, out._head(k))
        if status == lib.GF_ERR_OUT_OF_RANGE:
            k = int(done[0])
            raise SampleError(
                f"sample {s0 + k} is beyond the physical limits |omega| <= {MAX_RATE_RAD_S:g} "
                f"rad/s (measured or integrated over dt_s = {dt_s:g} s) and |f| <= "
                f"{MAX_SPECIFIC_FORCE_M_S2:g} m/s^2 (A_m_s2[{s0 + k}] = {A[k].tolist()}); "
                + done_before(k, s0), int(status), s0 + k, out._head(k))
        check_status(status, "gf9_solve")
        if not self._looked and n >= 8:
            # once per record: a time unit off (ms read as s) integrates omega_dot over the
            # wrong interval and gives wrong signs without any flag (issue 21)
            self._looked = True
            report([interval_problem(dt_s, out.omega_sq_rad2_s2, out.omega_dot_rad_s2,
                                     "the 9-accelerometer record")], "warn", stacklevel=3)
        return out


def solve_accel9(A_m_s2, dt_s: float, l_m: float,
                 omega_init_rad_s=(0.0, 0.0, 0.0)) -> Accel9Solution:
    """Solve a record of 9-accelerometer outputs (seed 000, eq. 3, 4, 6) in one C call.

    Parameters
    ----------
    A_m_s2 : array_like, shape (n, 9)
        Outputs of accelerometers 1..9 (m/s^2) in the layout of :func:`accel9_geometry`.
    dt_s : float
        Sampling interval, s.
    l_m : float
        Lever arm, m.
    omega_init_rad_s : array_like, shape (3,)
        Rate at the first sample (rad/s): the first signs and the start of the
        omega_dot integral that gives the later signs.

    Returns
    -------
    Accel9Solution

    Raises
    ------
    NonFiniteInputError, SampleError
        As :meth:`Accel9Solver.solve` (NaN/Inf; beyond the physical limits).

    Examples
    --------
    >>> import numpy as np, gfins_fmi as gf
    >>> g = gf.accel9_geometry(0.1)
    >>> n = 5
    >>> A = gf.forward_model(g, np.tile([0, 0, 9.8], (n, 1)),
    ...                      np.tile([0.1, -0.2, 0.3], (n, 1)), np.zeros((n, 3)))
    >>> sol = gf.solve_accel9(A, 0.01, 0.1, omega_init_rad_s=[1, -1, 1])
    >>> np.allclose(sol.omega_rad_s, [0.1, -0.2, 0.3])
    True
    """
    return Accel9Solver(l_m, omega_init_rad_s).solve(A_m_s2, dt_s)
