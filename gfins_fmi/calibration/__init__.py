"""IMU calibration, in two kinds: the laboratory calibration of seed 004 (``laboratory``:
multi-position static tests and rate-table runs, least squares) and the system-level
calibration of a rotating INS (``system``: calibrate a raw record with the filter of
``syscal_filter`` — the full inner lever-arm model or seed 001's 36 states — after
``segmentation`` cut it into rests and turns, with the defaults of ``grades``, the checks
of ``diagnostics`` and the report of ``report``; ``compensation`` converts a result to and
from the compensation form laboratory tools write). The two ``calibrate`` functions take
different inputs: import them from their modules."""
