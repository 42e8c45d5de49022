/* gf_quad.h — the 8-node Gauss-Legendre rule on [-1, 1] (exact for polynomials of degree
 * 15), shared by the simulators that integrate exact sensor outputs into increments
 * (gf_vehicle, gf_rot). Include it only where both arrays are used (an unused
 * static const array is a warning, and warnings are errors). */
#ifndef GF_QUAD_H
#define GF_QUAD_H

static const double GF_GL8_X[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290,
                                   -0.1834346424956498, 0.1834346424956498, 0.5255324099163290,
                                   0.7966664774136267, 0.9602898564975363};
static const double GF_GL8_W[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873,
                                   0.3626837833783620, 0.3626837833783620, 0.3137066458778873,
                                   0.2223810344533745, 0.1012285362903763};

#endif /* GF_QUAD_H */
