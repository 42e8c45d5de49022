"""Navigation of a rotating IMU (seed 001's rotation modulation): the IMU frame navigated
by the one mechanization (gf_sins) from its increments, optionally compensated with a
calibrated error model (seed 001 S6), and the vehicle's attitude from the navigated
C_m^n and the gimbal angles read by the encoders (``gf_rot_vehicle_attitude``). The
records come from :mod:`gfins_fmi.sim.rotation` or from a real mechanism
(docs/rotating_ins.md)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gfins_fmi._lib import GfinsError, as_array, ffi, lib, ptr
from gfins_fmi.nav.strapdown import SinsConfig, Strapdown

__all__ = ["RotatingNavSolution", "navigate", "vehicle_attitude"]


@dataclass(frozen=True)
class RotatingNavSolution:
    """Navigation of a rotating IMU: ``imu`` is the strapdown solution of the IMU frame
    (its ``q_bn`` holds C_m^n), ``q_bn_vehicle`` the vehicle's attitude from it and the
    gimbal angles (None when the schedule drives no mechanism)."""
    imu: object
    q_bn_vehicle: np.ndarray | None

    @property
    def t_s(self):
        return self.imu.t_s


def navigate(record, dtheta_rad=None, dv_m_s=None, *, initial=None,
             compensation=None, config=None) -> RotatingNavSolution:
    """Rotation-modulated navigation of ``record`` (a
    :class:`gfins_fmi.sim.rotation.RotatingImuRecord`, or anything with its ``t_s``,
    ``dt_s``, ``dtheta_rad``, ``dv_m_s``, ``gimbal_rad``, ``initial`` and ``schedule``):
    the IMU's increments (``record``'s, or the given
    ones, e.g. with sensor errors) compensated with ``compensation`` (an ImuErrors: the
    calibrated model; seed 001 S6), navigated in the IMU frame by the one mechanization
    (gf_sins), and the vehicle attitude from the navigated C_m^n and the gimbal angles
    (the encoders). ``initial``: the IMU's initial state (default: the record's truth);
    ``config``: a SinsConfig (default increments with coning, height held)."""
    th = record.dtheta_rad if dtheta_rad is None else dtheta_rad
    dv = record.dv_m_s if dv_m_s is None else dv_m_s
    if compensation is not None:
        th, dv = compensation.compensate_increments(th, dv, record.dt_s)
    x0 = initial if initial is not None else record.initial
    cfg = config or SinsConfig(vertical="hold")
    sol = Strapdown(x0, cfg).run(th, dv, t_s=record.t_s)
    qv = vehicle_attitude(sol.q_bn, record.gimbal_rad) if record.schedule.is_mechanism else None
    return RotatingNavSolution(sol, qv)


def vehicle_attitude(q_mn, gimbal_rad) -> np.ndarray:
    """C_b^n of the vehicle (n, 4) from the navigated IMU attitude C_m^n (n, 4) and the
    gimbal angles (n, 2: middle, inner) read by the encoders: C_b^n = C_m^n (C_m^b)^T."""
    q = as_array("q_mn", q_mn, (None, 4), "1")
    n = q.shape[0]
    g = as_array("gimbal_rad", gimbal_rad, (n, 2), "rad")
    out = np.empty((n, 4))
    done = ffi.new("size_t *")
    status = lib.gf_rot_vehicle_attitude(n, ptr(q, 4 * n), ptr(g, 2 * n), ptr(out, 4 * n), done)
    if status != lib.GF_OK:
        raise GfinsError(f"vehicle attitude: q_mn[{done[0]}] is not a rotation", int(status))
    return out
