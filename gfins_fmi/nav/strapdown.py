"""Strapdown inertial navigation (C core ``gf_sins``): ENU quaternion mechanization on
WGS-84, forward and reverse in time. Equations and conventions: ``csrc/nav/gf_sins.h``.

>>> import gfins_fmi as gf
>>> from gfins_fmi.sim import trajectory as tj
>>> truth = tj.sample(tj.Stationary(), duration_s=10.0, dt_s=0.01)
>>> nav = gf.Strapdown(gf.NavState.from_trajectory(truth, 0))
>>> sol = nav.run(truth.dtheta_rad, truth.dv_m_s, dt_s=0.01)
>>> bool(abs(sol.lat_rad[-1] - truth.lat_rad[-1]) < 1e-12)
True
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gfins_fmi._lib import (NonFiniteInputError, SampleError, as_array, as_rows, as_scalar,
                            as_start_index, check_status, done_before, ffi, first_nonfinite, lib,
                            ptr, status_text)
from gfins_fmi.nav.earth import WGS84

__all__ = ["SinsConfig", "NavState", "NavSolution", "Strapdown", "euler_to_quat",
           "quat_to_euler", "SampleError", "INPUT_KINDS", "VERTICAL_MODES", "EARTH_MODELS"]

#: the C core's codes of SinsConfig.input, .vertical and .earth (also FMU parameters)
INPUT_KINDS = {"increments": lib.GF_SINS_INPUT_INCREMENTS, "rates": lib.GF_SINS_INPUT_RATES}
VERTICAL_MODES = {"free": lib.GF_SINS_VERTICAL_FREE, "hold": lib.GF_SINS_VERTICAL_HOLD,
             "baro": lib.GF_SINS_VERTICAL_BARO}
EARTH_MODELS = {"wgs84": lib.GF_SINS_EARTH_WGS84, "flat": lib.GF_SINS_EARTH_FLAT}


@dataclass
class SinsConfig:
    """Mechanization options.

    Parameters
    ----------
    input : {"increments", "rates"}
        Increments: gyro = dtheta (rad), accel = dv (m/s) per interval. Rates: gyro =
        w_ib^b (rad/s), accel = f^b (m/s^2) at the sample times.
    coning : bool
        Two-sample coning and sculling corrections (off: the one-sample algorithm).
    vertical : {"free", "hold", "baro"}
        Vertical channel: free (unstable, time constant ~570 s), held at
        ``hold_height_m``, or damped by an external height (``h_ext_m`` in :meth:`run`)
        through a third-order loop with a triple pole at -1/``baro_tau_s``.
    hold_height_m : float or None
        Height held with ``vertical="hold"`` (m); None (default): the initial state's.
    max_rate_rad_s, max_specific_force_m_s2 : float
        Samples beyond these are refused as absurd.
    earth : {"wgs84", "flat"}
        The rotating WGS-84 Earth with gravity, or a fixed (non-rotating) frame with
        constant gravity ``flat_gravity_m_s2`` along -z and position in metres
        (``NavState.pos_m``, ``NavSolution.pos_m``): the idealised setting of seed
        000's simulation. Vertical modes apply to "wgs84" only.
    flat_gravity_m_s2 : float
        Gravity of the flat frame (m/s^2, >= 0).
    subsamples : int
        Increments per navigation update, 1 to 4 (default 1: one update per sample, with
        the previous sample's coning and sculling terms). N > 1 makes one update of
        N h from N consecutive increments with the N-sample coning and sculling set
        (2/3 for N = 2; 9/20, 27/20 and 54/105, 92/105, 214/105 for N = 3, 4; see
        ``csrc/nav/gf_sins.h`` and docs/sins.md for the derivation and accuracy): the usual
        processing of a high-rate IMU, 1.9x (N = 2) to 3.1-3.7x (N = 4) the throughput
        (docs/benchmarks.md).
        :meth:`Strapdown.run` then returns one row per update (``ceil(n / N)`` rows;
        the last update takes the samples left when N does not divide n). Increments
        only (``input="increments"``).
    """

    input: str = "increments"
    coning: bool = True
    vertical: str = "free"
    hold_height_m: float | None = None
    baro_tau_s: float = 10.0
    max_rate_rad_s: float = 50.0
    max_specific_force_m_s2: float = 1000.0
    earth: str = "wgs84"
    flat_gravity_m_s2: float = 0.0
    subsamples: int = 1

    def checked_subsamples(self) -> int:
        """``subsamples`` checked: an integer in 1..4, and 1 with rate input."""
        n = self.subsamples
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= 4:
            raise ValueError(f"subsamples must be an integer from 1 to 4 (increments per "
                             f"navigation update); got {n!r}")
        if n > 1 and self.input != "increments":
            raise ValueError(f"subsamples = {n} needs input='increments' (rate samples are "
                             "navigated one update per sample): use subsamples=1 with rates")
        return int(n)

    def held_height_m(self, initial_h_m: float | None) -> float:
        """The height held with ``vertical="hold"`` for an initial height (m)."""
        if self.hold_height_m is not None:
            return float(self.hold_height_m)
        if initial_h_m is None:
            if self.vertical == "hold":
                raise ValueError("hold_height_m=None holds the initial height, which is not "
                                 "known here: give hold_height_m")
            return 0.0                                  # unused outside "hold"
        return float(initial_h_m)

    def _c(self, initial_h_m: float | None = None):
        """The C configuration; ``initial_h_m`` resolves ``hold_height_m=None``."""
        if self.input not in INPUT_KINDS:
            raise ValueError(f"input must be one of {sorted(INPUT_KINDS)}; got {self.input!r}")
        if self.earth not in EARTH_MODELS:
            raise ValueError(f"earth must be one of {sorted(EARTH_MODELS)}; got {self.earth!r}")
        if self.vertical not in VERTICAL_MODES:
            raise ValueError(f"vertical must be one of {sorted(VERTICAL_MODES)}; got {self.vertical!r}")
        for name, unit in (("baro_tau_s", "s"), ("max_rate_rad_s", "rad/s"),
                           ("max_specific_force_m_s2", "m/s^2")):
            as_scalar(name, getattr(self, name), unit, above=0.0)
        hold = self.held_height_m(initial_h_m)
        if self.hold_height_m is not None:
            as_scalar("hold_height_m", hold, "m", above=-0.5 * WGS84.a)   # below -a/2: absurd
        as_scalar("flat_gravity_m_s2", self.flat_gravity_m_s2, "m/s^2", at_least=0.0)
        subsamples = self.checked_subsamples()
        c = ffi.new("gf_sins_config *")
        lib.gf_sins_config_default(c)
        c.input = INPUT_KINDS[self.input]
        c.coning = int(bool(self.coning))
        c.vertical = VERTICAL_MODES[self.vertical]
        c.hold_height_m = hold
        c.baro_tau_s = self.baro_tau_s
        c.max_rate_rad_s = self.max_rate_rad_s
        c.max_specific_force_m_s2 = self.max_specific_force_m_s2
        c.earth = EARTH_MODELS[self.earth]
        c.flat_gravity_m_s2 = float(self.flat_gravity_m_s2)
        c.subsamples = subsamples
        return c


def euler_to_quat(euler_rad) -> np.ndarray:
    """q_b^n (4,) of (heading, pitch, roll) in rad (heading clockwise from north)."""
    e = as_array("euler_rad", euler_rad, (3,), "rad (heading, pitch, roll)")
    q = np.empty(4)
    check_status(lib.gf_euler_to_quat(ptr(e, 3), ptr(q, 4)), "gf_euler_to_quat")
    return q


def quat_to_euler(q_bn) -> np.ndarray:
    """(heading, pitch, roll) in rad of quaternions q_b^n, shape (4,) or (n, 4)."""
    q = np.asarray(q_bn)
    single = q.ndim == 1
    q = as_rows("q_bn", q.reshape(1, -1) if single else q, 4, "unit quaternions")
    n = q.shape[0]
    out = np.empty((n, 3))
    done = ffi.new("size_t *")
    status = lib.gf_quat_to_euler_batch(n, ptr(q, 4 * n), ptr(out, 3 * n), done)
    if status != lib.GF_OK:
        k = int(done[0])
        raise ValueError(f"q_bn[{k}] = {q[k].tolist()} is not a unit quaternion (norm "
                         f"{np.linalg.norm(q[k]):.17g}; non-finite or off by more than 1e-6): "
                         "normalise it first")
    return out[0] if single else out


@dataclass
class NavState:
    """A navigation state: attitude q_b^n, ENU velocity (m/s), latitude and longitude
    (rad), height (m), time (s); ``pos_m`` (east, north, up) replaces the geodetic
    position with ``SinsConfig(earth="flat")``."""

    q_bn: np.ndarray
    v_n_m_s: np.ndarray
    lat_rad: float
    lon_rad: float
    h_m: float
    t_s: float = 0.0
    pos_m: np.ndarray | None = None

    @classmethod
    def from_euler(cls, euler_rad, v_n_m_s, lat_rad, lon_rad, h_m, t_s=0.0) -> "NavState":
        """From (heading, pitch, roll) in rad."""
        return cls(euler_to_quat(euler_rad), np.asarray(v_n_m_s, float), lat_rad, lon_rad,
                   h_m, t_s)

    @classmethod
    def from_trajectory(cls, trajectory, k: int = 0) -> "NavState":
        """The true state of a :class:`gfins_fmi.sim.trajectory.Trajectory` at sample k."""
        tr = trajectory
        return cls(tr.q_bn[k].copy(), tr.v_n_m_s[k].copy(), float(tr.lat_rad[k]),
                   float(tr.lon_rad[k]), float(tr.h_m[k]), float(tr.t_s[k]))

    @property
    def euler_rad(self) -> np.ndarray:
        """(heading, pitch, roll), rad."""
        return quat_to_euler(self.q_bn)

    def checked(self, flat: bool = False) -> "NavState":
        """This state with every field checked: C-contiguous float64 arrays of the right
        shape, finite values, latitude inside the mechanization's limit (+-89.9 deg; a
        fixed frame: +-90 deg), height in (-a/2, a/3) (a fixed frame: above -a/2), a quaternion
        that can be normalised; ``pos_m`` (3,) for a fixed frame (``flat``; None: the
        origin). Every navigator checks its initial state here before C reads it.

        Raises
        ------
        ValueError, TypeError
            The message names the field (``initial.v_n_m_s`` ...) and the fault.
        """
        q = as_array("initial.q_bn", self.q_bn, (4,), "(quaternion q_b^n)")
        if not np.linalg.norm(q) > 0:
            raise ValueError(f"initial.q_bn = {q.tolist()} cannot be normalised: give a non-zero "
                             "attitude quaternion")
        v = as_array("initial.v_n_m_s", self.v_n_m_s, (3,), "m/s (east, north, up)")
        lat = as_scalar("initial.lat_rad", self.lat_rad, "rad")
        lim = 90.0 if flat else lib.GF_SINS_LAT_LIMIT_MDEG / 1000.0
        if not abs(np.degrees(lat)) < lim:
            raise ValueError(f"initial.lat_rad = {lat!r} rad ({np.degrees(lat):.6g} deg) is outside "
                             f"(-{lim:g}, {lim:g}) deg" + ("" if flat else
                             ": the latitude limit of the ENU mechanization (its frame is "
                             "singular at the poles)"))
        lon = as_scalar("initial.lon_rad", self.lon_rad, "rad")
        h = as_scalar("initial.h_m", self.h_m, "m")
        if not h > -0.5 * WGS84.a:
            raise ValueError(f"initial.h_m = {h!r} m is below -a/2 (-3189 km): absurd height")
        if not flat and not h < WGS84.a / 3.0:
            raise ValueError(f"initial.h_m = {h!r} m is above a/3 (+2126 km), the Earth model's "
                             "range (its gravity expansion in height): give the height above "
                             "the ellipsoid in m")
        t = as_scalar("initial.t_s", self.t_s, "s")
        pos = None
        if flat:
            pos = as_array("initial.pos_m", (0.0, 0.0, 0.0) if self.pos_m is None else self.pos_m,
                           (3,), "m")
        return NavState(q, v, lat, lon, h, t, pos)


@dataclass
class NavSolution:
    """Navigation solution, row k = the state after sample k (with
    ``SinsConfig(subsamples=N)``: after update k, i.e. after sample min(n, N (k + 1)) - 1).

    Attributes: t_s (n,), q_bn (n, 4), v_n_m_s (n, 3), lat_rad, lon_rad, h_m (n,);
    with ``earth="flat"``, ``pos_m`` (n, 3) instead (the geodetic columns are NaN);
    ``euler_rad`` (n, 3) is computed on demand.
    """

    t_s: np.ndarray
    q_bn: np.ndarray
    v_n_m_s: np.ndarray
    lat_rad: np.ndarray
    lon_rad: np.ndarray
    h_m: np.ndarray
    pos_m: np.ndarray | None = None
    _euler: np.ndarray | None = field(default=None, repr=False)

    def __len__(self) -> int:
        return int(self.t_s.shape[0])

    @property
    def euler_rad(self) -> np.ndarray:
        """(heading, pitch, roll) per row, rad."""
        if self._euler is None:
            self._euler = quat_to_euler(self.q_bn)
        return self._euler

    def _rows(self, sl) -> "NavSolution":
        return NavSolution(self.t_s[sl].copy(), self.q_bn[sl].copy(), self.v_n_m_s[sl].copy(),
                           self.lat_rad[sl].copy(), self.lon_rad[sl].copy(), self.h_m[sl].copy(),
                           None if self.pos_m is None else self.pos_m[sl].copy())

    @staticmethod
    def _from_pos(t, q, v, pos, flat: bool) -> "NavSolution":
        if flat:
            nan = np.full(len(t), np.nan)
            return NavSolution(t, q, v, nan, nan.copy(), nan.copy(), pos)
        return NavSolution(t, q, v, pos[:, 0].copy(), pos[:, 1].copy(), pos[:, 2].copy())


class Strapdown:
    """A strapdown navigator (one C state); :meth:`run` continues where it stopped.

    Parameters
    ----------
    initial : NavState
    config : SinsConfig
    """

    def __init__(self, initial: NavState, config: SinsConfig | None = None):
        self.config = config or SinsConfig()
        flat = self.config.earth == "flat"
        x0 = initial.checked(flat)
        self._state = ffi.new("gf_sins_state *")
        status = lib.gf_sins_init(self._state, self.config._c(x0.h_m), ptr(x0.q_bn, 4),
                                  ptr(x0.v_n_m_s, 3), x0.lat_rad, x0.lon_rad, x0.h_m, x0.t_s)
        check_status(status, "gf_sins_init")
        if flat:
            check_status(lib.gf_sins_set_flat_position(self._state, ptr(x0.pos_m, 3)),
                         "flat position")
        self._backward = False
        self._origin_t_s = x0.t_s   # where a backward increment record starts
        self._pending_short = 0     # subsamples > 1: a run ended in a short group

    @property
    def state(self) -> NavState:
        """The current state (after the last sample)."""
        s = self._state
        sign = -1.0 if self._backward else 1.0
        flat = self.config.earth == "flat"
        return NavState(np.array(list(s.q_bn)), sign * np.array(list(s.v_n_m_s)),
                        float(s.lat_rad), float(s.lon_rad), float(s.h_m), float(s.time_s),
                        np.array(list(s.flat_pos_m)) if flat else None)

    def reverse(self) -> None:
        """Turn around in time: following :meth:`run` calls take records backward (the
        samples are given in their recorded order and processed last to first)."""
        check_status(lib.gf_sins_reverse(self._state), "gf_sins_reverse")
        self._backward = not self._backward
        self._pending_short = 0

    def run(self, gyro, accel, dt_s: float | None = None, t_s=None, h_ext_m=None,
            progress: bool = False, chunk: int = 1_000_000, *, start_index: int = 0) -> NavSolution:
        """Navigate a record in one C call (or in chunks of ``chunk`` with a progress bar).

        Parameters
        ----------
        gyro, accel : array_like (n, 3)
            Increments (rad, m/s) or rates (rad/s, m/s^2) per ``config.input``.
        dt_s : float, optional
            Fixed sampling interval (s). Either this or ``t_s``.
        t_s : array_like (n,), optional
            Sample times (s), strictly increasing. For increments, t_k ends interval k.
        h_ext_m : array_like (n,), optional
            External height at the sample times for ``vertical="baro"`` (NaN where
            there is none); required in that mode.
        progress : bool
            Show a progress bar (tqdm) while running.
        chunk : int
            Samples per C call (default 10^6; the record is always cut into chunks of
            this size, which gives the same result as one call).
        start_index : int
            When a record is navigated in pieces (one call per piece, each continuing
            the last): the index of this piece's first sample in the record, so that
            error messages and the exceptions' ``index`` count from the record's start.

        For a backward run of increments with ``t_s``, interval 0 is taken to start at
        the navigator's initial time (its ``initial.t_s``).

        With ``config.subsamples = N > 1`` the samples are grouped in recorded order
        (group j: samples N j .. N j + N - 1; the last group shorter when N does not
        divide n), one navigation update per group, and the solution has one row per
        group (``ceil(n / N)`` rows; backward: the state at the start of each group).
        ``chunk`` is rounded up to a multiple of N, and a record navigated in pieces
        gives the same result as one call when every piece but the record's last has a
        multiple of N samples (forward, a piece after a shorter one is refused; backward,
        give the pieces last to first). ``h_ext_m`` is used at the
        update times only (the group's last sample in processing order).

        Raises
        ------
        NonFiniteInputError, SampleError
            With ``index`` of the bad sample and ``partial``: this call's solution up
            to it.
        """
        s0 = as_start_index(start_index)
        g = as_rows("gyro", gyro, 3, "rad or rad/s")
        a = as_rows("accel", accel, 3, "m/s or m/s^2")
        n = g.shape[0]
        if a.shape[0] != n:
            raise ValueError(f"gyro has {n} samples but accel has {a.shape[0]}")
        if isinstance(chunk, bool) or not isinstance(chunk, (int, np.integer)) or chunk < 1:
            raise ValueError(f"chunk must be an integer >= 1; got {chunk!r}")
        if self.config.vertical == "baro" and h_ext_m is None:
            raise ValueError('vertical="baro" needs h_ext_m, the external height per sample '
                             "(NaN where there is none)")
        N = int(self._state.cfg.subsamples)      # as the C state was initialised
        rows = -(-n // N)
        if N > 1:
            chunk = -(-chunk // N) * N
            if self._pending_short and not self._backward:
                raise ValueError(f"the previous run ended with {self._pending_short} samples "
                                 f"(not a multiple of subsamples = {N}): it was the end of the "
                                 "record; give records in pieces of a multiple of N samples")
        if (dt_s is None) == (t_s is None):
            raise ValueError("give exactly one of dt_s (fixed interval, s) and t_s (sample times, s)")
        dt = 0.0
        if dt_s is not None:
            dt = as_scalar("dt_s", dt_s, "s", above=0.0)
        # NaN is data here (h_ext_m: no height at that sample) or is located by the core
        tt = None if t_s is None else as_array("t_s", t_s, (n,), "s", finite=False)
        he = None if h_ext_m is None else as_array("h_ext_m", h_ext_m, (n,), "m", finite=False)
        sol = NavSolution(np.empty(rows), np.empty((rows, 4)), np.empty((rows, 3)),
                          np.empty(rows), np.empty(rows), np.empty(rows))
        pos = np.empty((rows, 3))
        done_total = 0
        bar = None
        if progress:
            from tqdm import tqdm   # lazy: tqdm (~25 ms) only with a progress bar
            bar = tqdm(total=n, unit="sample", unit_scale=True, desc="navigating")
        if N == 1:
            order = range(n, 0, -chunk) if self._backward else range(0, n, chunk)
        else:   # chunk boundaries at multiples of N from the record's start, both ways
            order = reversed(range(0, n, chunk)) if self._backward else range(0, n, chunk)
        status = lib.GF_OK
        done = ffi.new("size_t *")
        try:
            for start in order:
                if N == 1:
                    lo, hi = ((max(0, start - chunk), start) if self._backward
                              else (start, min(n, start + chunk)))
                else:
                    lo, hi = start, min(n, start + chunk)
                m = hi - lo
                r0, r1 = lo // N, -(-hi // N)       # output rows of this chunk
                # a chunk continues the previous one: times come from the state, so t_s
                # must include the sample before the chunk for interval lengths
                tptr, dt_chunk = ffi.NULL, dt
                if tt is not None:
                    tptr = ptr(tt[lo:hi], m)
                    if self._backward and self.config.input == "increments":
                        # the C core needs the length of the chunk's first interval; the
                        # record's first interval starts at the navigator's initial time
                        dt_chunk = tt[lo] - tt[lo - 1] if lo > 0 else tt[0] - self._origin_t_s
                status = lib.gf_sins_run(
                    self._state, m, ptr(g[lo:hi], 3 * m), ptr(a[lo:hi], 3 * m), dt_chunk, tptr,
                    ptr(he[lo:hi], m) if he is not None else ffi.NULL, int(self._backward),
                    ptr(sol.q_bn[r0:r1], 4 * (r1 - r0)), ptr(sol.v_n_m_s[r0:r1], 3 * (r1 - r0)),
                    ptr(pos[r0:r1], 3 * (r1 - r0)), ptr(sol.t_s[r0:r1], r1 - r0), done)
                done_total += int(done[0])
                if bar:
                    bar.update(int(done[0]))
                if status != lib.GF_OK:
                    bad = (hi - 1 - int(done[0])) if self._backward else lo + int(done[0])
                    break
        finally:
            if bar:
                bar.close()
        if self.config.earth == "flat":
            sol.pos_m = pos
            sol.lat_rad[:] = sol.lon_rad[:] = sol.h_m[:] = np.nan
        else:
            sol.lat_rad[:], sol.lon_rad[:], sol.h_m[:] = pos[:, 0], pos[:, 1], pos[:, 2]
        if N > 1 and status == lib.GF_OK:
            self._pending_short = n % N
        group = ""
        if status != lib.GF_OK:
            if N == 1:
                good = slice(bad + 1, n) if self._backward else slice(0, bad)
                partial = sol._rows(good)
                done = (done_before(len(partial), s0 + bad + 1, "navigated") if self._backward
                        else done_before(len(partial), s0, "navigated"))
            else:
                # the update that failed: the group holding sample `bad` (the first sample
                # it did not complete, in processing order); its rows are not written
                g0 = (bad // N) * N
                g1 = min(n, g0 + N)
                good = slice(g0 // N + 1, rows) if self._backward else slice(0, g0 // N)
                partial = sol._rows(good)
                bad = self._culprit(g, a, tt, dt, he, g0, g1, int(status))
                group = f" (in the update of samples {s0 + g0}..{s0 + g1 - 1})"
                lo_s, n_s = (g1, n - g1) if self._backward else (0, g0)
                done = (f"{len(partial)} updates of samples {s0 + lo_s}..{s0 + lo_s + n_s - 1} "
                        "were navigated (see .partial)" if n_s else
                        "no sample was navigated before it (.partial is empty)")
            if status == lib.GF_ERR_NONFINITE_INPUT:
                for name, arr in (("gyro", g), ("accel", a)):
                    col = first_nonfinite(arr, bad)
                    if col >= 0:
                        raise NonFiniteInputError(f"{name}[{s0 + bad}, {col}] = {arr[bad, col]} is "
                                                  f"not finite{group}; {done}", s0 + bad, col, partial)
                raise NonFiniteInputError(f"sample {s0 + bad}: time or external height is not "
                                          f"finite{group}; {done}", s0 + bad, -1, partial)
            hints = {
                lib.GF_ERR_OUT_OF_RANGE: (f"sample {s0 + bad} exceeds |w| <= {self.config.max_rate_rad_s} "
                                          f"rad/s or |f| <= {self.config.max_specific_force_m_s2} m/s^2 "
                                          f"(gyro {g[bad].tolist()}, accel {a[bad].tolist()}; "
                                          f"input = {self.config.input!r})"),
                lib.GF_ERR_BAD_TIME: self._time_hint(tt, s0, bad),
                lib.GF_ERR_DIVERGED: (f"sample {s0 + bad}: the navigation state left its domain "
                                      "(pole reached or absurd height)"),
            }
            msg = hints.get(status, f"sample {s0 + bad}: {status_text(status)}")
            raise SampleError(f"{msg}{group}; {done}", int(status), s0 + bad, partial)
        return sol

    def _time_hint(self, tt, s0: int, bad: int) -> str:
        """Why sample ``bad``'s time was refused: it does not follow the time before it
        (the previous sample's, or for the first the navigator's own: NavState.t_s)."""
        if tt is None or self._backward or not np.isfinite(tt[bad]):
            return f"sample {s0 + bad}: sample times must be strictly increasing"
        prev = float(self._state.time_s)      # after the last good sample
        first = s0 + bad == 0 and bad == 0
        what = ("the navigator's initial time (NavState.t_s: the state's time must come "
                "before the record's first sample)" if first else "the previous sample's")
        return (f"sample {s0 + bad} at t = {float(tt[bad])!r} s does not come after {prev!r} s, "
                f"{what}; sample times must increase strictly")

    def _culprit(self, g, a, tt, dt, he, g0: int, g1: int, status: int) -> int:
        """The sample of group [g0, g1) (recorded order) that made its update fail:
        the first, in processing order, that is not finite, has a bad interval or exceeds
        the limits; the group's last sample in processing order when no single sample is
        at fault (a diverged update)."""
        idx = range(g1 - 1, g0 - 1, -1) if self._backward else range(g0, g1)
        cfg = self.config
        for k in idx:
            # the sample's interval as the core takes it: from the previous sample, the
            # first from the state's time (backward: from the navigator's initial time)
            h = dt
            if tt is not None:
                h = tt[k] - (tt[k - 1] if k > 0 else
                             (self._origin_t_s if self._backward else float(self._state.time_s)))
            if status == lib.GF_ERR_NONFINITE_INPUT:
                if (not np.all(np.isfinite(g[k])) or not np.all(np.isfinite(a[k]))
                        or (tt is not None and not np.isfinite(tt[k]))
                        or (he is not None and np.isinf(he[k]))):
                    return k
            elif status == lib.GF_ERR_BAD_TIME and tt is not None:
                if not h > 0:
                    return k
            elif status == lib.GF_ERR_OUT_OF_RANGE:
                if (np.linalg.norm(g[k]) > cfg.max_rate_rad_s * h
                        or np.linalg.norm(a[k]) > cfg.max_specific_force_m_s2 * h):
                    return k
        return idx[-1]
