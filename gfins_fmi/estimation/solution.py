"""The filter's output: :class:`IntegratedSolution` (row k = the state after IMU sample
k, the innovation log, the smoother's epochs) and the Rauch–Tung–Striebel smoother that
turns it into a :class:`SmoothedSolution` (one backward C call, ``gf_ins_smooth``)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from gfins_fmi._lib import check_status, ffi, lib, ptr
from gfins_fmi.estimation.config import MEAS_TYPES, N_SENSORS, FilterConfig
from gfins_fmi.nav.earth import radii
from gfins_fmi.nav.strapdown import quat_to_euler

__all__ = ["IntegratedSolution", "SmoothedSolution", "smooth", "epoch_std", "smoothing_layout"]


@dataclass
class IntegratedSolution:
    """Filter output, row k = the state after IMU sample k.

    Attributes
    ----------
    t_s (n,), q_bn (n, 4), v_n_m_s (n, 3) ENU, lat_rad, lon_rad, h_m (n,);
    std (n, 9): 1-sigma of velocity E, N, U (m/s), position E, N, U (m), attitude
        E, N, U (rad);
    sensors (n, 16): sensor-error estimates (``SENSOR_NAMES``);
    standstill (n,) bool: the detector's output;
    innovations: structured array, one row per update (t_s, type, status, m, nis, r[3],
        s_std[3]; ``MEAS_TYPES``, ``UPDATE_STATUS``);
    epochs: what the smoother needs (None unless the run kept it);
    transfer (n, 13): transfer-alignment estimates (``TRANSFER_NAMES``: corrections to the
        configured mounting, lever arm and time offset, flexure), None without those states;
    state_std (n, n_states): 1-sigma of every error state (``state_names(config)``), None
        unless the run kept it;
    config, n_states.
    """

    t_s: np.ndarray
    q_bn: np.ndarray
    v_n_m_s: np.ndarray
    lat_rad: np.ndarray
    lon_rad: np.ndarray
    h_m: np.ndarray
    std: np.ndarray
    sensors: np.ndarray
    standstill: np.ndarray
    innovations: np.ndarray
    config: FilterConfig
    epochs: Optional[dict] = None
    transfer: Optional[np.ndarray] = None
    state_std: Optional[np.ndarray] = None
    _euler: Optional[np.ndarray] = field(default=None, repr=False)

    def __len__(self) -> int:
        return int(self.t_s.shape[0])

    @property
    def euler_rad(self) -> np.ndarray:
        """(heading, pitch, roll) per row, rad."""
        if self._euler is None:
            self._euler = quat_to_euler(self.q_bn) if len(self) else np.zeros((0, 3))
        return self._euler

    def rejected(self) -> np.ndarray:
        """The updates that were not applied (gate, singular, stale)."""
        st = self.innovations["status"]
        return self.innovations[(st != lib.GF_INS_ACCEPTED) & (st != lib.GF_INS_FORCED)]

    def innovations_of(self, kind: str) -> np.ndarray:
        """Rows of the innovation log of one measurement kind (``MEAS_TYPES`` values)."""
        code = {v: k for k, v in MEAS_TYPES.items()}
        if kind not in code:
            raise ValueError(f"kind must be one of {sorted(code)}; got {kind!r}")
        return self.innovations[self.innovations["type"] == code[kind]]

    def _rows(self, sl) -> "IntegratedSolution":
        return IntegratedSolution(self.t_s[sl].copy(), self.q_bn[sl].copy(), self.v_n_m_s[sl].copy(),
                                  self.lat_rad[sl].copy(), self.lon_rad[sl].copy(), self.h_m[sl].copy(),
                                  self.std[sl].copy(), self.sensors[sl].copy(), self.standstill[sl].copy(),
                                  self.innovations, self.config, self.epochs,
                                  None if self.transfer is None else self.transfer[sl].copy(),
                                  None if self.state_std is None else self.state_std[sl].copy())

    def smooth(self, progress: bool = False) -> "SmoothedSolution":
        """Rauch–Tung–Striebel smoothing (backward pass over the stored epochs, one C
        call), applied to every row (corrections interpolated between epochs)."""
        if self.epochs is None:
            raise ValueError("this solution kept no epochs: run with smoother=True")
        return smooth(self, progress)


@dataclass
class SmoothedSolution(IntegratedSolution):
    """The smoothed solution at the IMU rows (same fields; ``std`` smoothed, interpolated
    between epochs) and at the epochs themselves (``epoch_t_s``, ``epoch_std``)."""

    epoch_t_s: Optional[np.ndarray] = None
    epoch_std: Optional[np.ndarray] = None


def smooth(sol: IntegratedSolution, progress: bool = False) -> SmoothedSolution:
    """The smoother over a solution that kept its epochs (:meth:`IntegratedSolution.smooth`)."""
    ep = sol.epochs
    n = ep["n_states"]
    E = len(ep["t_s"])
    keep = ep["_keepalive"]
    c = ffi.new("gf_ins_epochs *")
    c.capacity = c.count = E
    for k in ("t_s", "nav", "sensors", "dx", "P_prior", "P_post", "Phi"):
        setattr(c, k, ptr(keep.arrays[k], keep.arrays[k].size))
    xs = np.empty((E, n))
    Ps = np.empty_like(ep["P_post"])
    check_status(lib.gf_ins_smooth(n, c, ptr(xs, xs.size), ptr(Ps, Ps.size)), "gf_ins_smooth (a prior covariance "
                 "is not positive definite)")
    # apply to the rows
    q, v = sol.q_bn.copy(), sol.v_n_m_s.copy()
    pos = np.c_[sol.lat_rad, sol.lon_rad, sol.h_m]
    sens = sol.sensors.copy()
    f = smoothing_layout(sol.config, n)
    cfg = sol.config
    et = np.ascontiguousarray(ep["t_s"])
    dx = np.ascontiguousarray(ep["dx"])
    t_rows = np.ascontiguousarray(sol.t_s)
    nr = len(sol)
    check_status(lib.gf_ins_smooth_apply(f, E, ptr(et, E), ptr(xs, E * n), ptr(dx, E * n), nr,
                                         ptr(t_rows, nr), ptr(q, 4 * nr), ptr(v, 3 * nr),
                                         ptr(pos, 3 * nr), ptr(sens, N_SENSORS * nr)),
                 "gf_ins_smooth_apply")
    # smoothed std at the epochs, interpolated to the rows
    estd = epoch_std(Ps, ep["nav"], n)
    std = np.column_stack([np.interp(sol.t_s, et, estd[:, i]) for i in range(9)])
    return SmoothedSolution(sol.t_s.copy(), q, v, pos[:, 0].copy(), pos[:, 1].copy(), pos[:, 2].copy(),
                            std, sens, sol.standstill.copy(), sol.innovations, cfg, ep,
                            epoch_t_s=et.copy(), epoch_std=estd)


def smoothing_layout(cfg: FilterConfig, n_states: int):
    """The filter struct ``gf_ins_smooth_apply`` reads (the state layout of ``cfg``), refused
    when the epochs hold another number of states."""
    lay = cfg.layout()
    if lay.n_states != n_states:
        raise ValueError(f"the solution's epochs hold {n_states} states, its configuration {lay.n_states}")
    f = ffi.new("gf_ins_filter *")
    f.n_states = lay.n_states
    f.idx_sg, f.idx_sa, f.idx_baro = lay.idx_sg, lay.idx_sa, lay.idx_baro
    f.idx_odo, f.idx_mount = lay.idx_odo, lay.idx_mount
    return f


def epoch_std(Ps: np.ndarray, nav: np.ndarray, n_states: int) -> np.ndarray:
    """The smoothed 1-sigma at epochs (E, 9: velocity E, N, U m/s, position E, N, U m,
    attitude E, N, U rad) from their packed smoothed covariances (E, n(n+1)/2) and
    nominal states (E, 10: q, v, lat, lon, h): row by row, so a block of epochs gives the
    rows of the whole record's result."""
    tri_idx = np.triu_indices(n_states)
    diag_pos = np.flatnonzero(tri_idx[0] == tri_idx[1])
    var = Ps[:, diag_pos]
    RM, RN, _, _ = radii(nav[:, 7])
    estd = np.empty((len(Ps), 9))
    estd[:, 0:3] = np.sqrt(var[:, 0:3])
    estd[:, 3] = np.sqrt(var[:, 4]) * (RN + nav[:, 9]) * np.cos(nav[:, 7])
    estd[:, 4] = np.sqrt(var[:, 3]) * (RM + nav[:, 9])
    estd[:, 5] = np.sqrt(var[:, 5])
    estd[:, 6:9] = np.sqrt(var[:, 6:9])
    return estd
