"""Integrated navigation: the error-state INS/GNSS filter of the C core (``gf_ins_gnss``),
EKF or UKF, with GNSS position and velocity, barometer, odometer, non-holonomic and
zero-velocity aiding, reverse-time filtering and forward-backward passes (seed 003).

Equations, state layout and conventions: ``csrc/est/gf_ins_gnss.h`` and
``docs/estimation.md``. The error model's definition is
:func:`gfins_fmi.estimation.error_model.ins_error_matrices`.

A record goes to C in chunks (one call per chunk, default 2·10⁵ IMU samples) with all the
measurements that fall in it; nothing is looped per sample in Python.
"""
from __future__ import annotations

import tempfile

import numpy as np

from gfins_fmi._lib import check_status, ffi, lib, ptr, status_text
from gfins_fmi.estimation.config import (N_SENSORS, N_TRANSFER, SENSOR_NAMES, FilterConfig,
                                         FilterError, InitialState, vector3)
from gfins_fmi.estimation.measurement_checks import check_measurements
from gfins_fmi.estimation.measurements import INNOVATION_DTYPE, PASS_DTYPE, gather_measurements
from gfins_fmi.estimation.solution import IntegratedSolution
from gfins_fmi.nav.plausibility import report, specific_force_problem

__all__ = ["IntegratedNavigator", "integrate"]

class _Epochs:
    """Storage of the smoother's epochs: numpy arrays (or memory-mapped files beyond
    ``spill_bytes``) behind a gf_ins_epochs struct."""

    def __init__(self, n_states: int, capacity: int, spill_bytes: int, spill_dir=None):
        n = n_states
        tri = n * (n + 1) // 2
        self.n = n
        widths = {"t_s": 1, "nav": 10, "sensors": N_SENSORS, "dx": n, "P_prior": tri,
                  "P_post": tri, "Phi": n * n}
        self.bytes_per_epoch = 8 * sum(widths.values())
        total = self.bytes_per_epoch * capacity
        self._tmp = None
        self.arrays = {}
        if total > spill_bytes:
            self._tmp = tempfile.TemporaryDirectory(prefix="gfins_epochs_", dir=spill_dir)
            for k, w in widths.items():
                self.arrays[k] = np.lib.format.open_memmap(f"{self._tmp.name}/{k}.npy", "w+",
                                                           np.float64, (capacity, w))
        else:
            for k, w in widths.items():
                self.arrays[k] = np.empty((capacity, w))
        self.c = ffi.new("gf_ins_epochs *")
        self.c.capacity = capacity
        self.c.count = 0
        for k in widths:
            setattr(self.c, k, ptr(self.arrays[k], self.arrays[k].size))

    @property
    def count(self) -> int:
        return int(self.c.count)

    def trimmed(self) -> dict:
        c = self.count
        out = {k: v[:c] for k, v in self.arrays.items()}
        out["t_s"] = out["t_s"][:, 0]
        out["n_states"] = self.n
        out["bytes"] = self.bytes_per_epoch * c
        out["_keepalive"] = self
        return out


class IntegratedNavigator:
    """The integrated-navigation filter (one C state); :meth:`run` continues where it
    stopped, so a long record can be fed in pieces.

    Parameters
    ----------
    config : FilterConfig
    initial : InitialState
    """

    def __init__(self, config: FilterConfig, initial: InitialState):
        if not isinstance(config, FilterConfig):
            raise TypeError("config must be a FilterConfig")
        if not isinstance(initial, InitialState):
            raise TypeError("initial must be an InitialState")
        self.config = config
        nav = initial.nav
        q = np.ascontiguousarray(nav.q_bn, dtype=float)
        v = np.ascontiguousarray(nav.v_n_m_s, dtype=float)
        if q.shape != (4,) or v.shape != (3,):
            raise ValueError("initial.nav.q_bn must have 4 elements and initial.nav.v_n_m_s 3")
        for name in ("lat_rad", "lon_rad", "h_m", "t_s"):
            if not np.isfinite(getattr(nav, name)):
                raise ValueError(f"initial.nav.{name} = {float(getattr(nav, name))!r} must be finite")
        P0 = np.ascontiguousarray(initial.covariance(config))
        sens = np.zeros(N_SENSORS) if initial.sensors is None else np.ascontiguousarray(initial.sensors, float)
        if sens.shape != (N_SENSORS,) or not np.all(np.isfinite(sens)):
            raise ValueError(f"initial.sensors must be {N_SENSORS} finite numbers ({SENSOR_NAMES})")
        self._cfg = config._c()
        self._f = ffi.new("gf_ins_filter *")
        bad = ffi.new("int32_t *")
        st = lib.gf_ins_init(self._f, self._cfg, float(nav.t_s), ptr(q, 4), ptr(v, 3), float(nav.lat_rad),
                             float(nav.lon_rad), float(nav.h_m), ptr(sens, N_SENSORS), ptr(P0, P0.size), bad)
        if st != lib.GF_OK:
            field = ffi.string(lib.gf_ins_config_field(bad[0])).decode() if bad[0] else ""
            if field == "odometer_mount_rad":   # the angles used: configured + initial correction
                raise ValueError("FilterConfig.odometer_mount_rad + the initial boresight correction "
                                 "(InitialState.sensors odo_pitch_rad, odo_heading_rad) must stay "
                                 "inside (-pi/2, pi/2)")
            hint = f" (field {field})" if field else ""
            raise ValueError(f"gf_ins_init: {status_text(st)}{hint}")
        self.n_states = int(self._f.n_states)
        self._epochs_started = False

    @property
    def t_s(self) -> float:
        """Time of the filter's state (s)."""
        return float(self._f.t_s)

    @property
    def covariance(self) -> np.ndarray:
        """The current error covariance (n x n)."""
        n = self.n_states
        return np.frombuffer(ffi.buffer(self._f.kf.P), dtype=np.float64)[:n * n].reshape(n, n).copy()

    @property
    def counts(self) -> dict:
        """IMU samples, accepted and rejected updates so far."""
        f = self._f
        return {"imu": int(f.n_imu), "updates": int(f.n_updates), "rejected": int(f.n_rejected)}

    def error_model(self, f_b_m_s2, w_ib_b_rad_s):
        """F (n x n), G (n x n-3), q (n-3) of the C filter at its current nominal state."""
        n = self.n_states
        fb = vector3("f_b_m_s2", f_b_m_s2, "m/s^2")
        wb = vector3("w_ib_b_rad_s", w_ib_b_rad_s, "rad/s")
        F, G, q = np.empty((n, n)), np.empty((n, n - 3)), np.empty(n - 3)
        check_status(lib.gf_ins_error_model(self._f, ptr(fb, 3), ptr(wb, 3), ptr(F, n * n), ptr(G, n * (n - 3)),
                                             ptr(q, n - 3)),
                     "gf_ins_error_model")
        return F, G, q

    def run(self, imu, gnss=None, baro=None, odometer=None, *, speed=None, gnss_velocity: bool = True,
            master=None, state_std: bool = False, smoother: bool = False, chunk: int = 200_000,
            progress: bool = False, spill_bytes: int = 1 << 30, spill_dir=None,
            checks: str = "raise", epoch_sink=None) -> IntegratedSolution:
        """Process a record.

        Parameters
        ----------
        imu : record with ``t_s`` (n,) (end of each interval), ``gyro``, ``accel`` (n, 3)
            body right-front-up, as ``config.input`` says (``gfins_fmi.io.ImuRecord``).
        gnss : record with ``t_s``, ``lat_rad``, ``lon_rad``, ``h_m``, ``pos_std_m`` (m, 3:
            E, N, U), optionally ``vel_enu_m_s``, ``vel_std_m_s`` (used unless
            ``gnss_velocity=False``). Times of validity.
        baro : record with ``t_s``, ``h_m``, ``std_m``.
        odometer : record with ``t_s``, ``speed_m_s``, ``std_m_s``.
        speed : tachometer record (horizontal speed magnitude, seed 003) with ``t_s``,
            ``speed_m_s``, ``std_m_s`` (an ``OdometerRecord`` serves).
        master : a master INS's measurements for transfer alignment (an array of
            ``MEAS_DTYPE`` rows of the master kinds:
            :func:`gfins_fmi.estimation.transfer.master_measurements`).
        state_std : also keep the 1-sigma of every error state per row
            (``IntegratedSolution.state_std``, n x n_states).
        smoother : keep what the RTS smoother needs (at the covariance epochs: ~4 kB per
            epoch with 15 states) for :meth:`IntegratedSolution.smooth`; beyond
            ``spill_bytes`` it goes to memory-mapped files in ``spill_dir``.
        epoch_sink : where the smoother's epochs go instead, run after run (the record fed
            in pieces): an object with ``reserve(filter, room)`` (a ``gf_ins_epochs *``
            with room for ``room`` more epochs) and ``flush()`` (after the run), such as
            :class:`~gfins_fmi.estimation.smoother_stream.StreamingSmoother`'s, which uses
            it; not with ``smoother=True``.
        chunk : IMU samples per C call (rounded up to a multiple of ``config.subsamples``,
            so that the cut does not change the result).
        progress : a progress bar (tqdm).
        checks : {"raise", "warn", "off"}
            Before the run, a measurement record with epochs but none inside this IMU
            record (from the filter's time to the last sample: two time scales, most
            likely) raises :class:`UnusableMeasurementError` (``"raise"``), is a
            :class:`UnusableMeasurementWarning` (``"warn"``: a piece of a longer record
            that falls in an outage), or is not looked for (``"off"``). Unless ``"off"``,
            an IMU record whose median specific force is far from gravity (units, rates
            against increments, times in ms) is a
            :class:`~gfins_fmi.nav.plausibility.PlausibilityWarning`.

        Returns
        -------
        IntegratedSolution
            One row per IMU sample, or per navigation update with ``config.subsamples``
            > 1 (``t_s`` says when).

        Raises
        ------
        FilterError
            With ``index`` (IMU sample) and ``partial`` (the solution before it).
        UnusableMeasurementError
            See ``checks``.
        """
        cfg = self.config
        t, g, a = self._record(imu)
        n = t.shape[0]
        if isinstance(chunk, bool) or not isinstance(chunk, (int, np.integer)) or chunk < 1:
            raise ValueError(f"chunk must be an integer >= 1; got {chunk!r}")
        # the C core groups samples on the grid of its sample count: chunks of a multiple
        # of the group size are processed as the whole record would be
        chunk = -(-int(chunk) // cfg.subsamples) * cfg.subsamples
        if self.reversed:
            raise ValueError("the filter is reversed in time: use run_backward(), or reverse() it again")
        meas = gather_measurements(gnss, baro, odometer, gnss_velocity, speed, master)
        if n and checks != "off":
            check_measurements(self.t_s, float(t[-1]), checks, stacklevel=3, gnss=gnss, baro=baro,
                               odometer=odometer, speed=speed)
            report([specific_force_problem(self._specific_force(t, a), "the IMU record")], "warn",
                   stacklevel=3)
        # capacity: one epoch per propagation and up to two per measurement
        duration = float(t[-1] - self.t_s) if n else 0.0
        if cfg.propagation_interval_s > 0:
            n_prop = int(duration / cfg.propagation_interval_s) + 2
            n_prop = min(n_prop, n + 2)
        else:
            n_prop = n + 2
        cap_epochs = n_prop + 2 * len(meas) + 4
        epochs = None
        c_epochs = ffi.NULL
        if smoother and epoch_sink is not None:
            raise ValueError("smoother=True keeps the epochs in the solution; epoch_sink sends them elsewhere: "
                             "give one of them")
        if epoch_sink is not None:
            c_epochs = epoch_sink.reserve(self._f, cap_epochs)
        if smoother:
            if self._epochs_started:
                raise ValueError("the smoother needs the whole record in one run() call")
            epochs = _Epochs(self.n_states, cap_epochs, spill_bytes, spill_dir)
            check_status(lib.gf_ins_epochs_begin(self._f, epochs.c), "gf_ins_epochs_begin")
            self._epochs_started = True
            c_epochs = epochs.c
        internal = (int(cfg.nhc) + 2 * int(cfg.zupt)) * n_prop
        log_arr = np.zeros(len(meas) + internal + 16, INNOVATION_DTYPE)
        log = ffi.new("gf_ins_log *")
        log.capacity = len(log_arr)
        log.entries = ptr(log_arr, len(log_arr), "gf_ins_innovation")
        out = {"t_s": np.empty(n), "q_bn": np.empty((n, 4)), "v_n_m_s": np.empty((n, 3)),
               "pos": np.empty((n, 3)), "std": np.empty((n, 9)), "sensors": np.empty((n, N_SENSORS)),
               "standstill": np.zeros(n, np.int8)}
        transfer = cfg.master_mount or cfg.master_lever or cfg.master_time_offset or cfg.flexure
        if transfer:
            out["transfer"] = np.empty((n, N_TRANSFER))
        if state_std:
            out["state_std"] = np.empty((n, self.n_states))
        c_out = ffi.new("gf_ins_output *")
        n_done, m_done = ffi.new("size_t *"), ffi.new("size_t *")
        bar = None
        if progress:
            from tqdm import tqdm   # lazy: tqdm (~25 ms) only with a progress bar
            bar = tqdm(total=n, unit="sample", unit_scale=True, desc=f"{cfg.filter.upper()} filter")
        j = row = 0
        status, bad = lib.GF_OK, n
        try:
            for lo in range(0, n, chunk):
                hi = min(n, lo + chunk)
                # the measurements valid up to the chunk's last sample
                j_hi = int(np.searchsorted(meas["t_s"], t[hi - 1] + 1e-9, side="right"))
                sub = meas[j:j_hi]
                # rows: one per sample, or fewer (subsamples > 1); written from row on
                r_hi = row + hi - lo
                c_out.t_s = ptr(out["t_s"][row:r_hi], hi - lo)
                c_out.q_bn = ptr(out["q_bn"][row:r_hi], 4 * (hi - lo))
                c_out.v_n_m_s = ptr(out["v_n_m_s"][row:r_hi], 3 * (hi - lo))
                c_out.pos = ptr(out["pos"][row:r_hi], 3 * (hi - lo))
                c_out.std = ptr(out["std"][row:r_hi], 9 * (hi - lo))
                c_out.sensors = ptr(out["sensors"][row:r_hi], N_SENSORS * (hi - lo))
                c_out.standstill = ptr(out["standstill"][row:r_hi], hi - lo, "int8_t")
                if transfer:
                    c_out.transfer = ptr(out["transfer"][row:r_hi], N_TRANSFER * (hi - lo))
                if state_std:
                    c_out.state_std = ptr(out["state_std"][row:r_hi], self.n_states * (hi - lo))
                mptr = ptr(sub, len(sub), "gf_ins_meas") if len(sub) else ffi.NULL
                status = lib.gf_ins_run(self._f, hi - lo, ptr(t[lo:hi], hi - lo), ptr(g[lo:hi], 3 * (hi - lo)),
                                        ptr(a[lo:hi], 3 * (hi - lo)),
                                        len(sub), mptr, c_out, c_epochs, log,
                                        n_done, m_done)
                j += int(m_done[0])
                row += int(c_out.n_rows)
                if bar:
                    bar.update(int(n_done[0]))
                if status != lib.GF_OK:
                    bad = lo + int(n_done[0])
                    break
        finally:
            if bar:
                bar.close()
            if epoch_sink is not None:
                epoch_sink.flush()
        if log.n_dropped:
            raise RuntimeError(f"innovation log overflow ({log.n_dropped} entries): please report")
        k = row
        sol = IntegratedSolution(out["t_s"][:k], out["q_bn"][:k], out["v_n_m_s"][:k],
                                 out["pos"][:k, 0].copy(), out["pos"][:k, 1].copy(), out["pos"][:k, 2].copy(),
                                 out["std"][:k], out["sensors"][:k], out["standstill"][:k].astype(bool),
                                 log_arr[:int(log.count)].copy(), cfg,
                                 epochs.trimmed() if epochs else None,
                                 transfer=out["transfer"][:k] if transfer else None,
                                 state_std=out["state_std"][:k] if state_std else None)
        if status != lib.GF_OK:
            hints = {
                lib.GF_ERR_BAD_TIME: (f"IMU sample {bad} at t = {float(t[bad])!r} s: the interval from the "
                                      f"previous sample ({self.t_s!r} s) is not in (0, "
                                      f"{cfg.max_imu_gap_s}] s (time going backwards or an IMU gap; "
                                      "raise max_imu_gap_s to bridge gaps by dead reckoning)"),
                lib.GF_ERR_NONFINITE_INPUT: (
                    f"IMU sample {bad} holds NaN or Inf" if not (
                        np.isfinite(t[bad]) and np.all(np.isfinite(g[bad])) and np.all(np.isfinite(a[bad])))
                    else f"IMU sample {bad} (t = {float(t[bad])!r} s) is finite, but an update in its "
                         "interval was not (a measurement's value, or its variance, overflows)"),
                lib.GF_ERR_OUT_OF_RANGE: (f"IMU sample {bad} exceeds |w| <= {cfg.max_rate_rad_s} rad/s or "
                                          f"|f| <= {cfg.max_specific_force_m_s2} m/s^2 (input = "
                                          f"{cfg.input!r}: check the units)"),
                lib.GF_ERR_DIVERGED: (f"IMU sample {bad}: the filter diverged (navigation state left "
                                      "its domain or the covariance lost positive definiteness)"),
            }
            msg = hints.get(status, f"IMU sample {bad}: {status_text(status)}")
            raise FilterError(msg + "; the solution before it is in .partial", int(status), bad, sol)
        return sol


    # ---- reverse-time filtering and forward-backward processing (seed 003) ----------------

    @property
    def reversed(self) -> bool:
        """True after an odd number of :meth:`reverse` calls (time runs backward)."""
        return float(self._f.nav.earth_rate_sign) < 0

    def reverse(self) -> None:
        """Turn the filter around in time (``gf_ins_reverse``: velocity and gyro-bias
        errors change sign, the Earth rate too; see csrc/est/gf_ins_gnss.h). Twice = identity."""
        check_status(lib.gf_ins_reverse(self._f), "gf_ins_reverse")

    def _record(self, imu):
        cfg = self.config
        t = np.ascontiguousarray(np.asarray(imu.t_s, dtype=float))
        g = np.ascontiguousarray(np.asarray(imu.gyro, dtype=float))
        a = np.ascontiguousarray(np.asarray(imu.accel, dtype=float))
        n = t.shape[0]
        if t.ndim != 1 or g.shape != (n, 3) or a.shape != (n, 3):
            raise ValueError(f"imu.t_s must be (n,) and imu.gyro, imu.accel (n, 3); got "
                             f"{t.shape}, {g.shape}, {a.shape}")
        kind = getattr(imu, "kind", cfg.input)
        if kind != cfg.input:
            raise ValueError(f"the IMU record holds {kind!r} but the filter is configured for "
                             f"input={cfg.input!r}: convert the record (to_increments()/to_rates()) "
                             "or change FilterConfig.input")
        return t, g, a

    def _specific_force(self, t, a, most: int = 100_000):
        """|f| (m/s^2) of at most ``most`` samples spread over the record (rates: the
        accelerometer; increments: dv over its interval)."""
        step = max(1, len(t) // most)
        if self.config.input == "rates":
            return np.linalg.norm(a[::step], axis=1)
        dt = np.diff(np.r_[self.t_s, t])[::step]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.linalg.norm(a[::step], axis=1) / dt

    def _log(self, n_entries: int):
        arr = np.zeros(n_entries + 16, INNOVATION_DTYPE)
        log = ffi.new("gf_ins_log *")
        log.capacity = len(arr)
        log.entries = ptr(arr, len(arr), "gf_ins_innovation")
        return arr, log

    def run_backward(self, imu, t_start_s: float, gnss=None, baro=None, odometer=None, *, speed=None,
                     gnss_velocity: bool = True) -> IntegratedSolution:
        """Walk a reversed filter (:meth:`reverse`) backward over a record stored in
        increasing time, from its last sample (the filter's time) to ``t_start_s`` (where
        the first increment interval starts). Measurements as recorded (true time). Row k
        is the state after processing sample k (true-time velocity and gyro bias); one C
        call (``gf_ins_run_backward``)."""
        if not self.reversed:
            raise ValueError("run_backward needs a reversed filter: call reverse() first")
        t, g, a = self._record(imu)
        n = len(t)
        meas = gather_measurements(gnss, baro, odometer, gnss_velocity, speed)
        internal = (int(self.config.nhc) + 2 * int(self.config.zupt)) * \
            (int((t[-1] - t_start_s) / max(self.config.propagation_interval_s, 1e-3)) + n + 2 if n else 0)
        log_arr, log = self._log(len(meas) + internal)
        out = {"t_s": np.empty(n), "q_bn": np.empty((n, 4)), "v_n_m_s": np.empty((n, 3)),
               "pos": np.empty((n, 3)), "std": np.empty((n, 9)), "sensors": np.empty((n, N_SENSORS)),
               "standstill": np.zeros(n, np.int8)}
        c_out = ffi.new("gf_ins_output *")
        for k, w in (("t_s", 1), ("q_bn", 4), ("v_n_m_s", 3), ("pos", 3), ("std", 9), ("sensors", N_SENSORS)):
            setattr(c_out, k, ptr(out[k], w * n))
        c_out.standstill = ptr(out["standstill"], n, "int8_t")
        n_done, m_done = ffi.new("size_t *"), ffi.new("size_t *")
        mptr = ptr(meas, len(meas), "gf_ins_meas") if len(meas) else ffi.NULL
        st = lib.gf_ins_run_backward(self._f, n, ptr(t, n), ptr(g, 3 * n), ptr(a, 3 * n), float(t_start_s),
                                     len(meas), mptr, c_out, log, n_done, m_done)
        if st != lib.GF_OK:
            k = int(n_done[0])
            raise FilterError(f"backward walk stopped after {k} samples (from the last): {status_text(st)} "
                              f"(the filter's time must be the record's last sample, {float(t[-1]) if n else None!r} s, "
                              f"and t_start_s = {t_start_s!r} before its first)", int(st), n - 1 - k)
        return IntegratedSolution(out["t_s"], out["q_bn"], out["v_n_m_s"], out["pos"][:, 0].copy(),
                                  out["pos"][:, 1].copy(), out["pos"][:, 2].copy(), out["std"], out["sensors"],
                                  out["standstill"].astype(bool), log_arr[:int(log.count)].copy(), self.config)

    def forward_backward(self, imu, passes: int, gnss=None, baro=None, odometer=None, *, speed=None,
                         gnss_velocity: bool = True):
        """Seed 003's forward-backward processing of a stored record in one C call
        (``gf_ins_forward_backward``): forward over the record, then ``passes`` times
        backward to its start and forward to its end, x and P carried across each
        reversal. The filter must be at the start of the record's first interval; it ends
        forward at the record's last sample. Returns (pass table, innovation log): the
        table holds, per pass (1 + 2 passes rows), direction (+1/-1), t_s, q_bn, v_n_m_s,
        std9 (9, as IntegratedSolution.std), sensors, n_updates, n_rejected."""
        if self.reversed:
            raise ValueError("forward_backward starts from a forward filter: reverse() it back")
        if isinstance(passes, bool) or not isinstance(passes, (int, np.integer)) or not 0 <= passes <= 10000:
            raise ValueError(f"passes must be an integer in [0, 10000]; got {passes!r}")
        t, g, a = self._record(imu)
        n = len(t)
        if n < 2:
            raise ValueError(f"forward-backward processing needs a record of at least 2 IMU samples; got {n}")
        meas = gather_measurements(gnss, baro, odometer, gnss_velocity, speed)
        np_total = 1 + 2 * int(passes)
        n_prop = int((t[-1] - self.t_s) / max(self.config.propagation_interval_s, 1e-3)) + n + 2
        internal = (int(self.config.nhc) + 2 * int(self.config.zupt)) * n_prop
        log_arr, log = self._log(np_total * (len(meas) + internal))
        table = np.zeros(np_total, PASS_DTYPE)
        done = ffi.new("int32_t *")
        mptr = ptr(meas, len(meas), "gf_ins_meas") if len(meas) else ffi.NULL
        st = lib.gf_ins_forward_backward(self._f, n, ptr(t, n), ptr(g, 3 * n), ptr(a, 3 * n), len(meas), mptr,
                                         int(passes), ptr(table, np_total, "gf_ins_pass"), log, done)
        if log.n_dropped:
            raise RuntimeError(f"innovation log overflow ({log.n_dropped} entries): please report")
        if st != lib.GF_OK:
            raise FilterError(f"forward-backward processing stopped in pass {int(done[0])} of {np_total}: "
                              f"{status_text(st)} (the filter must start at the record's start, before "
                              f"its first sample at {float(t[0])!r} s)", int(st), -1)
        return table, log_arr[:int(log.count)].copy()


def integrate(imu, gnss=None, baro=None, odometer=None, *, config: FilterConfig,
              initial: InitialState, smooth: bool = False, **kwargs):
    """One call: run the filter over a record (and smooth it with ``smooth=True``).
    Returns the :class:`IntegratedSolution` (or the :class:`SmoothedSolution`)."""
    nav = IntegratedNavigator(config, initial)
    sol = nav.run(imu, gnss, baro, odometer, smoother=smooth, **kwargs)
    return sol.smooth() if smooth else sol
