"""The shared navigation blocks of the INS error model (C gf_ins_model) against the
definition, gfins_fmi.estimation.error_model.ins_error_matrices (written in numpy from Titterton &
Weston ch. 12.3), at random moving states. Tolerance: 1e-12 relative to the largest
entry of each block (the two evaluate the same closed forms in different orders)."""
from __future__ import annotations

import numpy as np

from gfins_fmi._lib import ffi, lib, ptr
from gfins_fmi.estimation.error_model import ins_error_matrices


def test_nav_blocks_equal_the_definition():
    rng = np.random.default_rng(11)
    for _ in range(25):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        v = rng.uniform(-250, 250, 3)
        lat, h = rng.uniform(-1.3, 1.3), rng.uniform(-100, 10000)
        fb = rng.uniform(-30, 30, 3)
        F_def, _ = ins_error_matrices(lat, h, v, q, fb, np.zeros(3))
        # definition order: dv 0-2, dp 3-5, phi 6-8; ours here: phi 0, dv 3, dp 6 in a 9 x 9
        F = np.full(81, np.nan)
        st = lib.gf_ins_nav_error_model(ptr(q, 4), ptr(v, 3), lat, h, ptr(fb, 3), 9, 0, 3, 6,
                                        ptr(F, 81))
        assert st == lib.GF_OK
        F = F.reshape(9, 9)
        perm = [6, 7, 8, 0, 1, 2, 3, 4, 5]
        want = F_def[np.ix_(perm, perm)]
        for r in range(3):
            for c in range(3):
                blk, ref = F[3 * r:3 * r + 3, 3 * c:3 * c + 3], want[3 * r:3 * r + 3, 3 * c:3 * c + 3]
                scale = max(np.abs(ref).max(), 1e-300)
                np.testing.assert_allclose(blk, ref, rtol=0, atol=1e-12 * scale,
                                           err_msg=f"block ({r}, {c})")


def test_bad_arguments():
    q, v, f = np.array([1.0, 0, 0, 0]), np.zeros(3), np.array([0, 0, 9.8])
    F = np.zeros(81)
    assert lib.gf_ins_nav_error_model(ptr(q, 4), ptr(v, 3), 2.0, 0.0, ptr(f, 3), 9, 0, 3, 6,
                                      ptr(F, 81)) == lib.GF_ERR_BAD_PARAMETER
    assert lib.gf_ins_nav_error_model(ptr(q, 4), ptr(v, 3), 0.2, 0.0, ptr(f, 3), 9, 0, 1, 6,
                                      ptr(F, 81)) == lib.GF_ERR_BAD_SIZE
    assert lib.gf_ins_nav_error_model(ptr(q, 4), ptr(v, 3), 0.2, 0.0, ffi.NULL, 9, 0, 3, 6,
                                      ptr(F, 81)) == lib.GF_ERR_NULL_POINTER
