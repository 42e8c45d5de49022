"""atheris target: the record readers of gfins_fmi.io on any file contents.

The first byte picks the reader (our CSV records' ``from_csv``, KF-GINS IMU text and
binary, GNSS and navigation files, RTKLIB .pos, rtk_walk IMU CSV); the rest is the file.
A reader may only refuse a file with the errors it documents — FileFormatError (naming
the file and line) or RecordError — or return a record; any other exception (IndexError,
UnicodeDecodeError, a bare numpy ValueError, ...) is a finding.

    python fuzz/python/fuzz_io_readers.py [libFuzzer options] CORPUS_DIR
"""
from __future__ import annotations

import os
import sys
import tempfile

import atheris

with atheris.instrument_imports():
    from gfins_fmi.io import (BaroRecord, GnssRecord, ImuRecord, OdometerRecord, TruthRecord,
                              read_kfgins_gnss, read_kfgins_imu, read_kfgins_nav, read_rtk_walk_imu,
                              read_rtklib_pos, rtk_walk_mounting)
    from gfins_fmi.io.errors import FileFormatError, RecordError

# files live in memory where there is a tmpfs
_DIR = tempfile.mkdtemp(prefix="fuzz_io_", dir="/dev/shm" if os.path.isdir("/dev/shm") else None)
_MOUNTING = rtk_walk_mounting()

READERS = [
    (".csv", ImuRecord.from_csv), (".csv", GnssRecord.from_csv), (".csv", BaroRecord.from_csv),
    (".csv", OdometerRecord.from_csv), (".csv", TruthRecord.from_csv),
    (".txt", read_kfgins_imu), (".bin", read_kfgins_imu),
    (".txt", lambda p: read_kfgins_imu(p, n_columns=8, gps_week=2100)),
    (".txt", read_kfgins_gnss), (".txt", lambda p: read_kfgins_gnss(p, angles="rad")),
    (".txt", read_kfgins_nav), (".pos", read_rtklib_pos),
    (".pos", lambda p: read_rtklib_pos(p, velocity=True)),
    (".csv", lambda p: read_rtk_walk_imu(p, _MOUNTING)),
]


def test_one_input(data: bytes) -> None:
    if not data:
        return
    suffix, reader = READERS[data[0] % len(READERS)]
    path = os.path.join(_DIR, "record" + suffix)
    with open(path, "wb") as f:
        f.write(data[1:])
    try:
        reader(path)
    except (FileFormatError, RecordError):
        pass


def main(argv: list[str]) -> None:
    atheris.Setup(argv, test_one_input)
    atheris.Fuzz()


if __name__ == "__main__":
    main(sys.argv)
