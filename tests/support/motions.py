"""Closed-form motions of the tests beyond gfins_fmi.sim.trajectory's."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gfins_fmi.sim import trajectory as tj

DEG = np.pi / 180.0


@dataclass
class Mooring(tj._Local, tj._EulerAttitude, tj.Motion):
    """A moored ship (closed forms, independent of the alignment code): surge, sway and
    heave of 0.2-0.5 m, yaw 2 deg, pitch 3 deg, roll 5 deg at 0.05-0.12 Hz."""
    heading: float = 40 * DEG

    def position(self, t):
        w1, w2, w3 = 2 * np.pi * 0.08, 2 * np.pi * 0.06, 2 * np.pi * 0.12
        E, N, U = 0.3 * np.sin(w1 * t), 0.2 * np.sin(w2 * t + 1), 0.5 * np.sin(w3 * t)
        return self._geo(E, N, U, 0.3 * w1 * np.cos(w1 * t), 0.2 * w2 * np.cos(w2 * t + 1),
                         0.5 * w3 * np.cos(w3 * t), -w1 * w1 * E, -w2 * w2 * N, -w3 * w3 * U)

    def euler(self, t):
        a, b, c = 2 * np.pi * 0.05, 2 * np.pi * 0.07, 2 * np.pi * 0.1
        return ((self.heading + 2 * DEG * np.sin(a * t), 3 * DEG * np.sin(b * t), 5 * DEG * np.sin(c * t + 0.5)),
                (2 * DEG * a * np.cos(a * t), 3 * DEG * b * np.cos(b * t), 5 * DEG * c * np.cos(c * t + 0.5)))
