/* gf_array_solver.h — the solver of any accelerometer array (seed 000 generalised to any
 * layout): each sample's specific force, angular acceleration and observed rate products.
 *
 * Every output is linear in x = [f (3), w_dot (3), W11, W22, W33, W12, W13, W23], the
 * specific force, the angular acceleration and the six products W = w w^T:
 *
 *   A_i = theta_i . f + (u_i x theta_i) . w_dot + sum_jk M_i,jk W_jk,
 *   M_i = sym(theta_i u_i^T) - (theta_i . u_i) I                (from seed 000 eq. 1-2)
 *
 * so an array is the N x 12 matrix H of these rows. The solver (gf_array_solver) splits
 * the six products into the combinations the outputs separate from f and w_dot
 * (observed), those that enter them only as f and w_dot do (confounded: taken from a
 * predicted rate) and those that do not enter them (absent), in coordinates a rotation
 * of the array acts on orthogonally, so that the same physical array gives the same
 * (rotated) solution in any mounting; it solves each sample by least squares with the
 * pseudo-inverse (SVD). Examples: the 12-accelerometer layout observes all of w w^T;
 * Qin's 9-accelerometer layout the squared rates along its axes (the cross products are
 * absent); the 6-accelerometer cube of Tan & Park none (its cross products are
 * confounded: it must integrate w_dot); a coplanar array three combinations.
 *
 * The angular rate comes from a strategy (gf_gfins.h), the navigation from gf_gfnav.h.
 */
#ifndef GF_ARRAY_SOLVER_H
#define GF_ARRAY_SOLVER_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_status.h"
#include "gyrofree/gf_array.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
#define GF_X_N 12                /* unknowns per sample */
#define GF_GROUP_F 1             /* f */
#define GF_GROUP_OMEGA_DOT 2     /* w_dot */
#define GF_GROUP_W_DIAG 4        /* W11, W22, W33 */
#define GF_GROUP_W_OFFDIAG 8     /* W12, W13, W23 */

/* What an array observes does not depend on how it is mounted in the body, so the
 * solver works in the space of products rather than on the body-axis groups. With
 * H = [H_l | H_p] (H_l: the 6 columns of f and w_dot; H_p: the products in the
 * orthonormal coordinates p = [W11, W22, W33, sqrt2 W12, sqrt2 W13, sqrt2 W23], in
 * which a rotation of the array acts orthogonally), and Q the projector on the
 * complement of the range of H_l:
 *   - H_l must have rank 6 (else the array is refused: f or w_dot unobservable even
 *     with the rate known);
 *   - the right singular vectors of Q H_p with singular values above the rank tolerance
 *     span the OBSERVED product combinations (n_obs, 0..6): the outputs separate them
 *     from f and w_dot;
 *   - of the rest, those with H_p v != 0 are CONFOUNDED (n_conf): they enter the
 *     outputs exactly as some f, w_dot do and must come from a predicted rate; the
 *     others are ABSENT (no effect on the outputs);
 *   - each sample is solved by least squares for f, w_dot and the observed
 *     combinations z (pinv of [H_l, H_p B_o], B_o the observed basis), after removing
 *     the confounded products of the predicted rate: x = pinv A - K_pred p(w_pred),
 *     K_pred = pinv H_p B_c B_c^T.
 * Everything here rotates with the array (a rotated array gives the rotated estimates,
 * the same condition number and the same principal noise gains). The body-axis group
 * masks are kept as a description: a group is "estimated" when every one of its
 * components lies in the observed subspace, "from_rate" when it is present, not
 * estimated, and touches the confounded subspace. */
typedef struct gf_array_solver {
    size_t n_sensors;
    uint32_t present;            /* groups whose columns are not zero (affect outputs) */
    uint32_t estimated;          /* groups solved from the outputs, every component */
    uint32_t from_rate;          /* present groups with components from the predicted rate */
    size_t n_obs;                /* observed product combinations, 0..6 */
    size_t n_conf;               /* confounded product combinations, 0..6 - n_obs */
    size_t n_est;                /* rows of pinv: f (3), w_dot (3), observed (n_obs) */
    size_t rank;                 /* rank of [H_l, H_p B_o] (= n_est when solvable) */
    double cond;                 /* its condition number s_max / s_min */
    double basis[36];            /* 6x6 orthonormal, row-major, column j = basis vector j
                                    in the orthonormal product coordinates: observed
                                    (0..n_obs-1), confounded, then absent */
    double noise_gain[GF_X_N];   /* std per unit output noise of f, w_dot and of every
                                    product W_jk wholly observed (0 otherwise), body axes */
    double pinv[GF_X_N * GF_ARRAY_MAX_SENSORS];   /* n_est rows, stride GF_ARRAY_MAX_SENSORS */
    double pinv_t[GF_ARRAY_MAX_SENSORS * GF_X_N]; /* its transpose, rows of 12 (zero beyond
                                                     n_est): the per-sample product as
                                                     axpys that vectorise */
    double K_pred[GF_X_N * 6];   /* n_est x 6: rows of x per orthonormal product of w_pred */
    double W_obs[36];            /* 6 x 6 (n_obs columns used): products W (as in x) per
                                    observed coordinate */
    double W_rate[36];           /* 6 x 6: products W (as in x) per orthonormal product of the
                                    rate, for the unobserved directions (B_n B_n^T) */
    double H[GF_ARRAY_MAX_SENSORS * GF_X_N];      /* n_sensors x 12 (products W_jk as in x) */
} gf_array_solver;

/* Builds the solver of an array. On GF_ERR_SINGULAR_GEOMETRY *unobservable (may be
 * NULL) has bit i set for every unknown i of x that the outputs cannot separate even
 * when the products come from a predicted rate (e.g. zero lever arms: w_dot). */
gf_status gf_array_solver_init(gf_array_solver *solver, const gf_array_geometry *geometry,
                               uint32_t *unobservable);

/* One sample: outputs A (n_sensors, m/s^2), predicted rate w_pred (3, rad/s; used for
 * the confounded products, may be NULL when there are none) -> x (12): f, w_dot and
 * the products W (observed combinations from the outputs, the rest from w_pred, or 0
 * without it). GF_ERR_BAD_SIZE for a solver whose sizes are out of range. */
gf_status gf_array_solve(const gf_array_solver *solver, const double *A_m_s2,
                         const double *w_pred_rad_s, double *x);

/* CDEF END */

#ifdef __cplusplus
}
#endif

#endif /* GF_ARRAY_SOLVER_H */
