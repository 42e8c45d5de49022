/* gf_layout.h — accelerometer-array layouts of the literature beyond seed 000's nine
 * (gf9_geometry, gf9.h), as geometries for the any-array solver (gf_array_solver.h).
 */
#ifndef GF_LAYOUT_H
#define GF_LAYOUT_H

#include "base/gf_status.h"
#include "gyrofree/gf_array.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
/* The layouts of the literature (positions in m, unit directions):
 * cube6: Tan & Park's 6-accelerometer cube as tabled in the mission digest (face
 * centres, face diagonals); layout12: Qin's nine plus three tangential sensors
 * (l e_x along e_y, l e_y along e_z, l e_z along e_x), which makes all of w w^T linear. */
gf_status gf_layout_cube6(double lever_arm_m, gf_array_geometry *geometry);
gf_status gf_layout_12(double lever_arm_m, gf_array_geometry *geometry);
/* CDEF END */

#ifdef __cplusplus
}
#endif

#endif /* GF_LAYOUT_H */
