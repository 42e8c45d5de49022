"""Record I/O: the records the integrated-navigation filters consume (body
right-front-up, navigation east-north-up, SI units, one time scale per record), our CSV
format, numeric tables read and written in chunks (CSV, npz, Parquet), and readers of
other tools' formats with their frames and units converted (docs/io.md)."""
from gfins_fmi.io.errors import FileFormatError, RecordError
from gfins_fmi.io.kfgins import read_kfgins_gnss, read_kfgins_imu, read_kfgins_nav
from gfins_fmi.io.raw_imu import read_raw_imu
from gfins_fmi.io.records import (IMU_KINDS, QUALITY_NAMES, BaroRecord, Gap, GnssRecord, ImuRecord,
                                  OdometerRecord, SamplingStats, TruthRecord)
from gfins_fmi.io.rtk_walk import (load_rtk_walk, mounting_from_rpy, read_rtk_walk_imu,
                                   rtk_walk_mounting)
from gfins_fmi.io.rtklib import read_rtklib_pos
from gfins_fmi.io.table_writer import TableWriter
from gfins_fmi.io.tables import TableReader, table_format

__all__ = [
    "ImuRecord", "GnssRecord", "BaroRecord", "OdometerRecord", "TruthRecord",
    "SamplingStats", "Gap", "IMU_KINDS", "QUALITY_NAMES", "RecordError", "FileFormatError",
    "read_kfgins_imu", "read_kfgins_gnss", "read_kfgins_nav", "read_rtklib_pos", "read_raw_imu",
    "read_rtk_walk_imu", "load_rtk_walk", "rtk_walk_mounting", "mounting_from_rpy",
    "TableReader", "TableWriter", "table_format",
]
