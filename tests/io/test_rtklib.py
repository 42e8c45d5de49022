"""RTKLIB .pos files (gfins_fmi.io.rtklib): calendar and GPS-week time forms, velocities,
files without a header, bad files named.
"""
from __future__ import annotations

import datetime
import pathlib

import numpy as np
import pytest

from gfins_fmi.io import FileFormatError, read_rtklib_pos

EPS = np.finfo(float).eps
GPS_EPOCH = datetime.datetime(1980, 1, 6)


def write(path: pathlib.Path, text: str) -> pathlib.Path:
    path.write_text(text, encoding="utf-8")
    return path


POS_HEADER = ("%  GPST            latitude(deg) longitude(deg) height(m) Q ns sdn(m) sde(m) sdu(m) "
              "sdne(m) sdeu(m) sdun(m) age(s) ratio vn(m/s) ve(m/s) vu(m/s) sdvn sdve sdvu sdvne "
              "sdveu sdvun\n")
POS_LINES = ("2025/08/28 17:30:39.749 40.0966916 -105.1471665 1601.4350 1 25 0.0099 0.0098 0.0100 "
             "0.0 0.0 0.0 0.0 0.0 0.0010 -0.0020 0.0270 0.0494 0.0495 0.0496 0 0 0\n"
             "2025/08/28 17:30:39.999 40.0966917 -105.1471664 1601.4310 2 25 0.0199 0.0198 0.0200 "
             "0.0 0.0 0.0 0.0 0.0 0.0050 0.0000 -0.0220 0.0594 0.0595 0.0596 0 0 0\n")


def gps_seconds(dt: datetime.datetime) -> float:
    return (dt - GPS_EPOCH).total_seconds()


def test_rtklib_calendar_form_with_velocity(tmp_path):
    r = read_rtklib_pos(write(tmp_path / "a.pos", "% program   : RTKLIB\n" + POS_HEADER + POS_LINES))
    t0 = gps_seconds(datetime.datetime(2025, 8, 28, 17, 30, 39, 749000))
    # two roundings (calendar seconds, then the fraction) against datetime's one: 1 ulp
    np.testing.assert_allclose(r.t_s, [t0, t0 + 0.25], rtol=0, atol=2.5e-7)
    np.testing.assert_allclose(r.lat_rad, np.radians([40.0966916, 40.0966917]), rtol=2 * EPS)
    np.testing.assert_array_equal(r.h_m, [1601.435, 1601.431])
    np.testing.assert_array_equal(r.pos_std_m[0], [0.0098, 0.0099, 0.0100])      # sde, sdn, sdu
    np.testing.assert_array_equal(r.vel_enu_m_s, [[-0.002, 0.001, 0.027], [0.0, 0.005, -0.022]])
    np.testing.assert_array_equal(r.vel_std_m_s[0], [0.0495, 0.0494, 0.0496])    # sdve, sdvn, sdvu
    np.testing.assert_array_equal(r.quality, [1, 2])
    assert not read_rtklib_pos(tmp_path / "a.pos", velocity=False).has_velocity


def test_rtklib_week_form_and_no_header(tmp_path):
    """The same epoch written as GPS week and seconds, and without a header (RTKLIB's
    standard column order), gives the calendar form's time."""
    t0 = gps_seconds(datetime.datetime(2025, 8, 28, 17, 30, 39, 749000))
    week, sow = divmod(round(t0 * 1000), 604800 * 1000)
    line = f"{week} {sow / 1000:.3f} 40.0966916 -105.1471665 1601.4350 5 9 1.2 1.3 2.5 0 0 0 0.0 0.0\n"
    r = read_rtklib_pos(write(tmp_path / "w.pos", POS_HEADER.split(" vn(m/s)")[0] + "\n" + line))
    np.testing.assert_allclose(r.t_s, [t0], rtol=0, atol=2.5e-7)
    assert not r.has_velocity and r.quality_counts() == {"single": 1}
    bare = read_rtklib_pos(write(tmp_path / "bare.pos", POS_LINES))
    full = read_rtklib_pos(write(tmp_path / "full.pos", POS_HEADER + POS_LINES))
    assert bare.has_velocity and len(bare) == 2
    for name in ("t_s", "lat_rad", "lon_rad", "h_m", "pos_std_m", "vel_enu_m_s", "vel_std_m_s",
                 "quality"):    # every field as with the header (test_reader_conventions.py)
        assert np.array_equal(getattr(bare, name), getattr(full, name)), name
    with pytest.raises(FileFormatError, match="velocity=True but the file has no velocity columns"):
        read_rtklib_pos(tmp_path / "w.pos", velocity=True)
    # the record says which time form the file had
    assert "GPST week/seconds" in r.source and "GPST calendar" in full.source


def test_rtklib_header_lines_that_are_not_the_column_line(tmp_path):
    """A '% GPST' line with nothing after it is not the column line (the next one is);
    a column line written without a space after the '%' is one."""
    alone = read_rtklib_pos(write(tmp_path / "a.pos", "%  GPST\n" + POS_HEADER + POS_LINES))
    tight = read_rtklib_pos(write(tmp_path / "t.pos", POS_HEADER.replace("%  GPST", "%GPST") + POS_LINES))
    ref = read_rtklib_pos(write(tmp_path / "r.pos", POS_HEADER + POS_LINES))
    for rec in (alone, tight):
        assert np.array_equal(rec.vel_enu_m_s, ref.vel_enu_m_s) and np.array_equal(rec.t_s, ref.t_s)
    # and a velocity column order of the header's own, not RTKLIB's standard one, is followed
    swapped = POS_HEADER.replace("vn(m/s) ve(m/s)", "ve(m/s) vn(m/s)")
    sw = read_rtklib_pos(write(tmp_path / "s.pos", swapped + POS_LINES))
    assert np.array_equal(sw.vel_enu_m_s[:, :2], ref.vel_enu_m_s[:, 1::-1])
    # a tight column line is read as a header, not skipped (its own order followed too)
    tight_sw = read_rtklib_pos(write(tmp_path / "ts.pos", swapped.replace("%  GPST", "%GPST")
                                     + POS_LINES))
    assert np.array_equal(tight_sw.vel_enu_m_s, sw.vel_enu_m_s)


@pytest.mark.parametrize("text, match", [
    (POS_HEADER.replace("GPST", "UTC "), "times are in UTC: .* export the solution with the time system GPST"),
    (POS_HEADER.replace("GPST", "BJT "), "times are in BJT: .* export the solution with the time system GPST"),
    # a blank line before the header: the header is still read (and its time system refused)
    ("\n" + POS_HEADER.replace("GPST", "JST "), "times are in JST"),
    ("%  GPST  x-ecef(m) y-ecef(m) z-ecef(m) Q ns sdx(m)\n", r"a.pos:1: .*ECEF x/y/z: export latitude/longitude/height"),
    ("% program : RTKLIB\n%  GPST  x-ecef(m)\n", r"a.pos:2: .*ECEF x/y/z"),   # two words suffice
    ("% (lat/lon/height=WGS84/geodetic,Q=1:fix)\n" + POS_HEADER,
     r"a.pos:1: .*WGS84/geodetic: export WGS84 with ellipsoidal"),
    ("% x\n% y\n% (lat/lon/height=Tokyo,Q=1:fix)\n", r"a.pos:3: .*Tokyo: export WGS84"),
    (POS_HEADER, "no epoch lines"),
    (POS_HEADER + POS_LINES.replace("1601.4310", "nan"), r"a.pos:3: h_m\[1\] = nan is not finite"),
    (POS_HEADER + POS_LINES.replace("0.0199", "0.0"), r"a.pos:3: pos_std_m\[1, 1\] = 0.0 m"),
    (POS_HEADER + POS_LINES.replace(" 0.0594", ""), r"a.pos:3: 27 columns where a RTKLIB .pos "
     r"\(date and time counted as 6 fields\) line has 28"),
    (POS_HEADER + POS_LINES[::-1][::-1].replace("39.999", "39.749"), r"a.pos:3: t_s must be strictly increasing"),
])
def test_rtklib_bad_files(tmp_path, text, match):
    with pytest.raises(FileFormatError, match=match):
        read_rtklib_pos(write(tmp_path / "a.pos", text))
