"""The C smoother's raw outputs for the tests: gf_ins_smooth over the epochs a run kept
(the smoothed error states and covariances that SmoothedSolution only reports as stds)."""
from __future__ import annotations

import numpy as np

from gfins_fmi._lib import ffi, lib, ptr


def unpack(tri: np.ndarray, n: int) -> np.ndarray:
    """(E, n(n+1)/2) packed upper triangles, row by row -> (E, n, n)."""
    P = np.zeros((len(tri), n, n))
    iu = np.triu_indices(n)
    P[:, iu[0], iu[1]] = tri
    P[:, iu[1], iu[0]] = tri
    return P


def c_smoother(ep: dict) -> tuple[np.ndarray, np.ndarray]:
    """gf_ins_smooth over a solution's ``epochs``: the smoothed error of each epoch's
    posterior nominal (E, n) and its covariance (E, n, n)."""
    n, E = ep["n_states"], len(ep["t_s"])
    arrays = ep["_keepalive"].arrays
    c = ffi.new("gf_ins_epochs *")
    c.capacity = c.count = E
    for k in ("t_s", "nav", "sensors", "dx", "P_prior", "P_post", "Phi"):
        setattr(c, k, ptr(arrays[k], arrays[k].size))
    xs = np.empty((E, n))
    Ps = np.empty_like(ep["P_post"])
    assert lib.gf_ins_smooth(n, c, ptr(xs, xs.size), ptr(Ps, Ps.size)) == lib.GF_OK
    return xs, unpack(Ps, n)
