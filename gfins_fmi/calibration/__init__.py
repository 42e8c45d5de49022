"""IMU calibration, in two kinds: the laboratory calibration of seed 004 (``laboratory``:
multi-position static tests and rate-table runs, least squares) and the system-level
calibration of a rotating INS of seed 001 (``system``: calibrate a raw record with the
36/37-state filter of ``syscal_filter``, after ``segmentation`` cut it into rests and
turns). The two ``calibrate`` functions take different inputs: import them from their
modules."""
