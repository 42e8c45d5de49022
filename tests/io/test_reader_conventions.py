"""Frames, signs and column orders of every format we read and write, checked with
hand-made records whose axes are all different (north != east != up velocity, a
different std on every axis), so that a swapped column or a sign cannot hide behind
equal values; each format read with and without its header where it has one; and every
record written by our writers and read back with the same fields.

Truth: the values typed in here, and the column names of our CSV files read with the
standard library's csv module (not with our reader). The formats' own column
definitions: RTKLIB's solution format (rtklib.py; ``ve``/``vn``, ``sde``/``sdn`` are
east/north), KF-GINS's README (north-east-down, forward-right-down).
"""
from __future__ import annotations

import csv
import dataclasses
import datetime
import math
import pathlib

import numpy as np
import pytest

from gfins_fmi.cli.files import nav_columns, outputs
from gfins_fmi.io import (BaroRecord, GnssRecord, ImuRecord, OdometerRecord, TableReader,
                          TruthRecord, read_kfgins_gnss, read_kfgins_imu, read_kfgins_nav,
                          read_rtk_walk_imu, read_rtklib_pos)
from gfins_fmi.io.columns import NAV_COLUMNS
from gfins_fmi.nav import earth

EPS = np.finfo(float).eps
GPS_EPOCH = datetime.datetime(1980, 1, 6)


def write(path: pathlib.Path, text: str) -> pathlib.Path:
    path.write_text(text, encoding="utf-8")
    return path


def same_fields(a, b) -> None:
    """Every field of two records equal (arrays bit for bit, NaN and None included)."""
    assert type(a) is type(b)
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if f.name == "source":
            continue
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            assert x is not None and y is not None, f.name
            assert x.dtype == y.dtype and np.array_equal(x, y, equal_nan=True), (f.name, x, y)
        else:
            assert x == y, (f.name, x, y)


def csv_columns(path: pathlib.Path) -> dict:
    """Our CSV read with the csv module: column name -> float values."""
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    rows = list(csv.reader(lines))
    return {name: np.array([float(r[j]) for r in rows[1:]]) for j, name in enumerate(rows[0])}


def round_trip(rec, tmp_path: pathlib.Path, name: str):
    path = rec.to_csv(tmp_path / name)
    back = type(rec).from_csv(path)
    same_fields(rec, back)
    return csv_columns(path)


# ---- RTKLIB .pos: every column a different value --------------------------------------

# two epochs; per line: date time lat lon h Q ns sdn sde sdu sdne sdeu sdun age ratio
# vn ve vu sdvn sdve sdvu sdvne sdveu sdvun, no two values of an epoch alike
POS = [
    ("2025/08/28 17:30:39.750", 40.0966916, -105.1471665, 1601.4350, 1, 25, 0.011, 0.022, 0.033,
     0.0041, -0.0052, 0.0063, 1.5, 9.9, 1.25, -2.5, 0.375, 0.044, 0.055, 0.066, 0.001, 0.002, 0.003),
    ("2025/08/28 17:30:40.000", 40.0966919, -105.1471661, 1601.4210, 2, 24, 0.012, 0.023, 0.034,
     0.0042, -0.0053, 0.0064, 1.6, 8.8, 1.5, -2.25, -0.125, 0.045, 0.056, 0.067, 0.004, 0.005, 0.006),
]
HEADER = ("%  GPST            latitude(deg) longitude(deg) height(m) Q ns sdn(m) sde(m) sdu(m) "
          "sdne(m) sdeu(m) sdun(m) age(s) ratio vn(m/s) ve(m/s) vu(m/s) sdvn sdve sdvu sdvne "
          "sdveu sdvun\n")


def _pos_text(week_form: bool, velocity: bool) -> str:
    out = []
    for e in POS:
        vals = list(e[1:]) if velocity else list(e[1:14])
        if week_form:
            d = datetime.datetime.strptime(e[0], "%Y/%m/%d %H:%M:%S.%f")
            t = (d - GPS_EPOCH).total_seconds()
            week, sow = divmod(round(t * 1000), 604800 * 1000)
            stamp = f"{week} {sow / 1000:.3f}"
        else:
            stamp = e[0]
        out.append(stamp + " " + " ".join(repr(v) for v in vals))
    return "\n".join(out) + "\n"


@pytest.mark.parametrize("week_form", [False, True], ids=["calendar", "week"])
@pytest.mark.parametrize("velocity", [True, False], ids=["velocity", "position"])
def test_rtklib_with_and_without_header_and_its_axes(tmp_path, week_form, velocity):
    """The same epochs with the header line and without it (RTKLIB's standard order) give
    identical records; east, north, up taken from ve/vn/vu and sde/sdn/sdu."""
    header = HEADER if velocity else HEADER.split(" vn(m/s)")[0] + "\n"
    body = _pos_text(week_form, velocity)
    with_h = read_rtklib_pos(write(tmp_path / "h.pos", "% program : RTKLIB\n" + header + body))
    bare = read_rtklib_pos(write(tmp_path / "b.pos", body))
    same_fields(with_h, bare)
    P = np.array([e[1:] for e in POS], float)      # columns after the time, as in the file
    np.testing.assert_allclose(with_h.lat_rad, np.radians(P[:, 0]), rtol=2 * EPS)
    np.testing.assert_allclose(with_h.lon_rad, np.radians(P[:, 1]), rtol=2 * EPS)
    np.testing.assert_array_equal(with_h.h_m, P[:, 2])
    np.testing.assert_array_equal(with_h.quality, P[:, 3].astype(np.int8))
    np.testing.assert_array_equal(with_h.pos_std_m, P[:, [6, 5, 7]])           # sde, sdn, sdu
    if velocity:
        np.testing.assert_array_equal(with_h.vel_enu_m_s, P[:, [14, 13, 15]])  # ve, vn, vu
        np.testing.assert_array_equal(with_h.vel_std_m_s, P[:, [17, 16, 18]])  # sdve, sdvn, sdvu
    else:
        assert not with_h.has_velocity
    t0 = (datetime.datetime(2025, 8, 28, 17, 30, 39, 750000) - GPS_EPOCH).total_seconds()
    np.testing.assert_allclose(with_h.t_s, [t0, t0 + 0.25], rtol=0, atol=2.5e-7)
    # and through our CSV: the same record, each axis under its own name
    cols = round_trip(with_h, tmp_path, "g.csv")
    np.testing.assert_array_equal(cols["pos_std_e_m"], P[:, 6])
    np.testing.assert_array_equal(cols["pos_std_n_m"], P[:, 5])
    np.testing.assert_array_equal(cols["pos_std_u_m"], P[:, 7])
    if velocity:
        np.testing.assert_array_equal(cols["vel_e_m_s"], P[:, 14])
        np.testing.assert_array_equal(cols["vel_n_m_s"], P[:, 13])
        np.testing.assert_array_equal(cols["vel_u_m_s"], P[:, 15])
        np.testing.assert_array_equal(cols["vel_std_e_m_s"], P[:, 17])
        np.testing.assert_array_equal(cols["vel_std_n_m_s"], P[:, 16])


# ---- KF-GINS: north-east-down, forward-right-down -------------------------------------

def test_kfgins_gnss_axes_and_round_trip(tmp_path):
    """13 columns: time, lat, lon, h, std N E D, velocity N E D, its std N E D, all
    different: east/north swap, down -> up with its sign (velocity) or without (std)."""
    row = [456300.0, 30.4447858054, 114.4718661162, 21.095, 0.011, 0.022, 0.033,
           1.25, -2.5, 0.375, 0.044, 0.055, 0.066]
    r = read_kfgins_gnss(write(tmp_path / "g.txt", " ".join(map(repr, row)) + "\n"))
    np.testing.assert_array_equal(r.pos_std_m, [[0.022, 0.011, 0.033]])
    np.testing.assert_array_equal(r.vel_enu_m_s, [[-2.5, 1.25, -0.375]])
    np.testing.assert_array_equal(r.vel_std_m_s, [[0.055, 0.044, 0.066]])
    cols = round_trip(r, tmp_path, "g.csv")
    assert cols["vel_e_m_s"][0] == -2.5 and cols["vel_n_m_s"][0] == 1.25


def test_kfgins_imu_axes_and_round_trip(tmp_path):
    """Increments forward, right, down (x, y, z of KF-GINS) -> right, front, up."""
    r = read_kfgins_imu(write(tmp_path / "i.txt", "456300.005 0.0001 0.0002 0.0003 0.011 0.022 0.033\n"
                                                  "456300.010 0.0004 0.0005 0.0006 0.044 0.055 0.066\n"))
    np.testing.assert_array_equal(r.gyro, [[0.0002, 0.0001, -0.0003], [0.0005, 0.0004, -0.0006]])
    np.testing.assert_array_equal(r.accel, [[0.022, 0.011, -0.033], [0.055, 0.044, -0.066]])
    cols = round_trip(r, tmp_path, "i.csv")
    np.testing.assert_array_equal(cols["gyro_x_rad"], [0.0002, 0.0005])      # right
    np.testing.assert_array_equal(cols["accel_y_m_s"], [0.011, 0.044])       # front


def test_kfgins_nav_axes_and_round_trip(tmp_path):
    """Velocity N E D and roll, pitch, yaw all different -> E N U velocity and [heading,
    pitch, roll] in the right slots; through our CSV each under its name."""
    r = read_kfgins_nav(write(tmp_path / "t.nav", "2019 456300.0 30.5 114.25 20.75 1.25 -2.5 0.375 "
                                                  "10.0 -5.0 -30.0\n"))
    np.testing.assert_array_equal(r.v_enu_m_s, [[-2.5, 1.25, -0.375]])
    np.testing.assert_allclose(r.euler_rad, np.radians([[330.0, -5.0, 10.0]]), rtol=4 * EPS)
    cols = round_trip(r, tmp_path, "t.csv")
    assert (cols["v_e_m_s"][0], cols["v_n_m_s"][0], cols["v_u_m_s"][0]) == (-2.5, 1.25, -0.375)
    assert cols["heading_rad"][0] == r.euler_rad[0, 0] and cols["roll_rad"][0] == r.euler_rad[0, 2]


# ---- rtk_walk IMU (no header): sensor axes through the mounting ------------------------

def test_rtk_walk_imu_axes_through_a_mounting_with_all_axes_different(tmp_path):
    """Columns: time, accel x y z (g), gyro x y z (rad/s), 4 more. A mounting that turns
    every axis into another (a cyclic permutation with one sign) places each column:
    f_b = C_s^b f_s, w_b = C_s^b w_s."""
    C = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])    # det +1
    r = read_rtk_walk_imu(write(tmp_path / "imu.csv",
                                "1756402240.9610000,0.125,-0.25,1.0,0.01,0.02,0.03,0,0,0,0\n"),
                          C, g_m_s2=9.8)
    np.testing.assert_array_equal(r.accel, [[1.0 * 9.8, -0.125 * 9.8, 0.25 * 9.8]])
    np.testing.assert_array_equal(r.gyro, [[0.03, -0.01, -0.02]])
    round_trip(r, tmp_path, "i.csv")


# ---- our own records and solution tables ------------------------------------------------

def test_every_record_type_round_trips_with_its_columns_named(tmp_path):
    """A hand-made record of every type (every value different) written by to_csv: read
    with the csv module each named column holds its field's axis; read with from_csv the
    record is the same."""
    t = np.array([10.0, 10.5])
    imu = ImuRecord(t, [[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]], [[1.1, 1.2, 9.3], [1.4, 1.5, 9.6]], "rates")
    cols = round_trip(imu, tmp_path, "imu.csv")
    for j, ax in enumerate("xyz"):
        np.testing.assert_array_equal(cols[f"gyro_{ax}_rad_s"], imu.gyro[:, j])
        np.testing.assert_array_equal(cols[f"accel_{ax}_m_s2"], imu.accel[:, j])
    g = GnssRecord(t, [0.5, 0.51], [2.0, 2.01], [30.0, 31.0], [[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]],
                   [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]], [[0.01, 0.02, 0.03], [0.04, 0.05, 0.06]], [1, 4])
    cols = round_trip(g, tmp_path, "g.csv")
    for j, ax in enumerate("enu"):
        np.testing.assert_array_equal(cols[f"pos_std_{ax}_m"], g.pos_std_m[:, j])
        np.testing.assert_array_equal(cols[f"vel_{ax}_m_s"], g.vel_enu_m_s[:, j])
        np.testing.assert_array_equal(cols[f"vel_std_{ax}_m_s"], g.vel_std_m_s[:, j])
    np.testing.assert_array_equal(cols["quality"], [1, 4])
    b = BaroRecord(t, [100.0, 101.0], [0.5, 0.25])
    cols = round_trip(b, tmp_path, "b.csv")
    assert cols["h_m"].tolist() == [100.0, 101.0] and cols["std_m"].tolist() == [0.5, 0.25]
    o = OdometerRecord(t, [5.0, 6.0], [0.05, 0.025])
    cols = round_trip(o, tmp_path, "o.csv")
    assert cols["speed_m_s"].tolist() == [5.0, 6.0] and cols["std_m_s"].tolist() == [0.05, 0.025]
    tr = TruthRecord(t, [0.5, 0.51], [2.0, 2.01], [30.0, 31.0], [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]],
                     [[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]])
    cols = round_trip(tr, tmp_path, "t.csv")
    for j, ax in enumerate("enu"):
        np.testing.assert_array_equal(cols[f"v_{ax}_m_s"], tr.v_enu_m_s[:, j])
    for j, ang in enumerate(("heading", "pitch", "roll")):
        np.testing.assert_array_equal(cols[f"{ang}_rad"], tr.euler_rad[:, j])


def test_navigation_solution_table_names_each_axis(tmp_path):
    """The commands' navigation table (cli/files.py nav_columns, written through the
    commands' output set io/output_set.py; the vocabulary of io/columns.py): a solution
    with every axis different, written and read back with TableReader, has each quantity
    under its own name and unit (deg)."""
    eul = np.array([[0.5, 0.1, -0.2], [1.5, -0.3, 0.4]])                # heading, pitch, roll
    q = np.array([earth.euler_to_quat(*e) for e in eul])
    sol = _Sized(t_s=np.array([1.0, 2.0]), lat_rad=np.array([0.5, 0.6]),
                 lon_rad=np.array([2.0, 2.1]), h_m=np.array([30.0, 40.0]),
                 v_n_m_s=np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]), euler_rad=eul, q_bn=q)
    cols = nav_columns(sol)
    path = tmp_path / "nav.csv"
    outs = outputs()
    outs.write_table(path, list(NAV_COLUMNS), cols)
    outs.commit()
    with TableReader(path, header=True) as r:
        names = r.names
        table = np.concatenate([b for _, b in r])
    got = dict(zip(names, table.T))
    deg = 180 / math.pi
    np.testing.assert_array_equal(got["lat_deg"], sol.lat_rad * deg)
    np.testing.assert_array_equal(got["lon_deg"], sol.lon_rad * deg)
    for j, ax in enumerate("enu"):
        np.testing.assert_array_equal(got[f"v_{ax}_m_s"], sol.v_n_m_s[:, j])
    for j, ang in enumerate(("heading", "pitch", "roll")):
        np.testing.assert_array_equal(got[f"{ang}_deg"], eul[:, j] * deg)
    for j in range(4):
        np.testing.assert_array_equal(got[f"q{j}"], q[:, j])


class _Sized:
    """A solution-like object with len() (nav_columns asks len(sol))."""

    def __init__(self, **fields):
        self.__dict__.update(fields)

    def __len__(self) -> int:
        return len(self.t_s)
