/* turn_drive.h — the vehicle truth the navigator FMU tests run on (test_fmu_navigator.c,
 * test_fmu_ins_gnss.c): gf_vehicle from lat 30 deg, h 100 m: 2 s at rest, to 15 m/s in
 * 3 s, 1 s straight, a 180 deg turn in 6 s; n samples h_s apart from t = 0. */
#ifndef TURN_DRIVE_H
#define TURN_DRIVE_H

#include <string.h>

#include "base/gf_math.h"
#include "gf_test.h"
#include "sim/gf_vehicle.h"

static void turn_drive(gf_vehicle_sample *truth, int n, double h_s)
{
    gf_vehicle_profile p;
    memset(&p, 0, sizeof p);
    p.lat0_rad = 0.5235987755982988;
    p.lon0_rad = 1.9896753472735356;
    p.h0_m = 100.0;
    p.n_segments = 4;
    const double seg[4][4] = {{2, 0, 0, 0}, {3, 15, 0, 0}, {1, 0, 0, 0}, {6, 0, 0, GF_PI}};
    for (int i = 0; i < 4; ++i) {
        p.segment[i].duration_s = seg[i][0];
        p.segment[i].dspeed_m_s = seg[i][1];
        p.segment[i].dheading_rad = seg[i][3];
    }
    gf_vehicle_state s;
    CHECK(gf_vehicle_init(&s, &p, 0.0, &truth[0], NULL) == GF_OK, "vehicle");
    CHECK(gf_vehicle_run(&s, (size_t)(n - 1), h_s, &truth[1], NULL) == GF_OK, "vehicle run");
}

#endif /* TURN_DRIVE_H */
