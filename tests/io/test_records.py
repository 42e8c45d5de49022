"""The records (gfins_fmi.io.records): their contract (frozen, read-only float64 copies,
refused with the fix), slices, sampling statistics and gaps, outages, the conversions
between rates and increments, and our CSV format (bit-exact round trip, units in the
header, errors named). The other formats' readers: test_kfgins.py, test_rtklib.py,
test_rtk_walk.py.

Truth: files written here by hand with values typed in and closed-form rates for the
increment conversions.
"""
from __future__ import annotations

import copy
import dataclasses
import pathlib
import pickle

import numpy as np
import pytest

from gfins_fmi.io import BaroRecord, FileFormatError, GnssRecord, ImuRecord, OdometerRecord, RecordError, TruthRecord


def write(path: pathlib.Path, text: str) -> pathlib.Path:
    path.write_text(text, encoding="utf-8")
    return path


def imu_rates(n=5, t0=100.0, dt=0.01):
    t = t0 + dt * np.arange(n)
    return ImuRecord(t, np.tile([0.01, -0.02, 0.03], (n, 1)), np.tile([0.1, 0.2, 9.8], (n, 1)),
                     "rates", "test")


def gnss(n=6, dt=1.0, vel=True):
    t = 1000.0 + dt * np.arange(n)
    v = np.tile([1.0, 2.0, 0.1], (n, 1)) if vel else None
    return GnssRecord(t, np.full(n, 0.5), np.full(n, 2.0), np.full(n, 30.0),
                      np.tile([0.02, 0.03, 0.05], (n, 1)), v,
                      np.tile([0.1, 0.1, 0.2], (n, 1)) if vel else None,
                      np.array([1, 1, 2, 2, 5, 1][:n]), "test")


def test_records_are_frozen_read_only_float64_copies():
    g = np.array([[1, 2, 3], [4, 5, 6]])                       # integers: converted
    t = np.array([0.0, 1.0])
    r = ImuRecord(t, g, np.zeros((2, 3)), "increments")
    assert r.gyro.dtype == np.float64 and r.gyro.flags.c_contiguous and not r.gyro.flags.writeable
    t[1] = 5.0
    g[0, 0] = 99                                               # the caller's arrays stay theirs
    assert r.t_s[1] == 1.0 and r.gyro[0, 0] == 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.kind = "rates"
    with pytest.raises(ValueError, match="read-only"):
        r.gyro[0, 0] = 0.0
    assert len(r) == 2 and r.duration_s == 1.0 and r.units == ("rad", "m/s")
    assert "ImuRecord(kind='increments', n=2" in repr(r)
    for twin in (pickle.loads(pickle.dumps(r)), copy.deepcopy(r)):   # process pools, copies
        assert np.array_equal(twin.gyro, r.gyro) and not twin.gyro.flags.writeable


@pytest.mark.parametrize("make, match", [
    (lambda: ImuRecord([0, 1, 1], np.zeros((3, 3)), np.zeros((3, 3)), "rates"),
     r"strictly increasing: t_s\[2\] = 1.0 s repeats t_s\[1\]"),
    (lambda: ImuRecord([0, 2, 1], np.zeros((3, 3)), np.zeros((3, 3)), "rates"),
     r"t_s\[2\] = 1.0 s goes back from"),
    (lambda: ImuRecord([0, 1], [[0, 0, 0], [0, np.nan, 0]], np.zeros((2, 3)), "rates"),
     r"gyro\[1, 1\] = nan is not finite"),
    (lambda: ImuRecord([0, 1], np.zeros((2, 3)), np.zeros((3, 3)), "rates"),
     "accel has 3 rows but t_s has 2"),
    (lambda: ImuRecord([0, 1], np.zeros((2, 2)), np.zeros((2, 3)), "rates"),
     r"gyro must have shape \(n, 3\) in rad/s"),
    (lambda: ImuRecord([0, 1], np.zeros((2, 3)), np.zeros((2, 3)), "rate"),
     "kind must be 'increments'"),
    (lambda: ImuRecord([], np.zeros((0, 3)), np.zeros((0, 3)), "rates"), "the record is empty"),
    (lambda: GnssRecord([0], [0.5], [1.0], [3.0], [[0.1, 0.0, 0.2]]),
     r"pos_std_m\[0, 1\] = 0.0 m: a standard deviation must be > 0"),
    (lambda: GnssRecord([0], [30.5], [114.4], [3.0], [[0.1, 0.1, 0.2]]),
     r"lat_rad\[0\] = 30.5 rad is outside .*from degrees: np.radians"),
    (lambda: GnssRecord([0], [0.5], [1.0], [3.0], [[0.1, 0.1, 0.2]], [[1, 2, 3]]),
     "give both vel_enu_m_s and vel_std_m_s"),
    (lambda: GnssRecord([0], [0.5], [1.0], [3.0], [[0.1, 0.1, 0.2]], quality=[7]),
     r"quality\[0\] = 7 is not one of RTKLIB's Q"),
    (lambda: TruthRecord([0], [0.5], [1.0], [3.0], [[0, 0, 0]], [[-0.1, 0, 0]]),
     r"heading.* wrap it with np.mod"),
    (lambda: TruthRecord([0], [0.5], [1.0], [3.0], [[0, 0, 0]], [[0.1, 2.0, 0]]),
     r"pitch.*outside \[-1.5708, 1.5708\]"),
    (lambda: BaroRecord([0, 1], [10, 11], [0.5, -0.5]), r"std_m\[1\] = -0.5 m"),
    (lambda: OdometerRecord([0, 1], [1, np.inf], [0.1, 0.1]), r"speed_m_s\[1\] = inf"),
])
def test_bad_records_are_refused_with_the_fix(make, match):
    with pytest.raises(RecordError, match=match):
        make()


def test_record_errors_carry_field_and_index():
    with pytest.raises(RecordError) as info:
        BaroRecord([0, 1, 2], [1, 2, np.nan], [1, 1, 1])
    assert (info.value.field, info.value.index) == ("h_m", 2)
    with pytest.raises(TypeError, match="real numbers"):
        BaroRecord([0, 1], ["a", "b"], [1, 1])


def test_slice_dt_stats_and_gaps():
    t = np.r_[np.arange(10.0), 13.0 + np.arange(5.0)]          # a 4 s gap after t = 9
    r = BaroRecord(t, np.arange(15.0), np.ones(15), "b")
    s = r.slice(2.0, 13.0)
    np.testing.assert_array_equal(s.t_s, [2, 3, 4, 5, 6, 7, 8, 9, 13])   # both ends kept
    assert isinstance(s, BaroRecord) and s.source == "b"
    st = r.dt_stats()
    assert (st.median_s, st.min_s, st.max_s, st.gap_threshold_s) == (1.0, 1.0, 4.0, 2.0)
    assert len(st.gaps) == 1 and st.gaps[0] == (10, 9.0, 13.0) and st.gaps[0].length_s == 4.0
    assert r.dt_stats(gap_threshold_s=5.0).gaps == ()
    assert "1 gap(s) over 2 s" in str(st)
    with pytest.raises(RecordError, match=r"no sample in \[10, 12\] s: the record spans \[0, 17\] s"):
        r.slice(10.0, 12.0)
    with pytest.raises(ValueError, match="t0_s <= t1_s"):
        r.slice(5.0, 1.0)


def test_with_outages_removes_the_epochs_inside():
    g = gnss(n=6)
    out = g.with_outages([(1001.0, 1002.0), (1004.5, 1010.0)])
    np.testing.assert_array_equal(out.t_s, [1000.0, 1003.0, 1004.0])
    np.testing.assert_array_equal(out.quality, [1, 2, 5])       # rows stay together
    np.testing.assert_array_equal(out.vel_enu_m_s, g.vel_enu_m_s[[0, 3, 4]])
    assert "outages [1001, 1002], [1004.5, 1010] s removed" in out.source
    assert len(g) == 6                                           # the original is unchanged
    with pytest.raises(ValueError, match="lies outside the record.*add t_s\\[0\\]"):
        g.with_outages([(10.0, 20.0)])                           # seconds from the start
    with pytest.raises(ValueError, match="finite t0_s < t1_s"):
        g.with_outages([(1003.0, 1001.0)])
    with pytest.raises(ValueError, match="must be a pair"):
        g.with_outages([1001.0])
    with pytest.raises(RecordError, match="remove every epoch"):
        g.with_outages([(999.0, 1006.0)])
    assert g.quality_counts() == {"fix": 3, "float": 2, "single": 1}


def test_trapezoid_increments_are_exact_for_linear_rates(rng):
    """Rates linear in time: the trapezoid is the exact integral (to round-off; the
    values are O(1) over intervals of O(0.01): 1e-15 absolute)."""
    t = np.cumsum(rng.uniform(0.005, 0.01, 200))
    a, b = rng.normal(size=3), rng.normal(size=3)
    rec = ImuRecord(t, a + b * t[:, None], 2 * a + b * t[:, None], "rates")
    inc = rec.to_increments()
    dt = np.diff(t)[:, None]
    exact = (a + b * (t[:-1, None] + t[1:, None]) / 2) * dt     # integral of a + b t
    assert inc.kind == "increments" and len(inc) == 199
    np.testing.assert_array_equal(inc.t_s, t[1:])
    assert np.abs(inc.gyro - exact).max() < 1e-15
    assert inc.to_increments() is inc


def test_conversion_orders_of_accuracy():
    """w = sin(t): the trapezoid's error per interval falls 8x when T halves (third
    order); increments / T as the rate at the interval's end falls 2x (first order), as
    the rate at its middle 4x (second order). Ratios within 10% of 8, 2, 4: the next
    terms of the Taylor series are a factor T = 0.01-0.02 smaller."""
    def errors(T):
        t = np.arange(1.0, 3.0, T)
        w = np.sin(t)[:, None] * [1.0, 1.0, 1.0]
        inc = ImuRecord(t, w, w, "rates").to_increments()
        exact = (np.cos(t[:-1]) - np.cos(t[1:]))[:, None] * [1.0, 1.0, 1.0]   # integral of sin
        trap = np.abs(inc.gyro - exact).max()
        mean_rate = ImuRecord(t[1:], exact, exact, "increments").to_rates(first_interval_s=T)
        end = np.abs(mean_rate.gyro[:, 0] - np.sin(t[1:])).max()
        mid = np.abs(mean_rate.gyro[:, 0] - np.sin(t[1:] - T / 2)).max()
        return np.array([trap, end, mid])
    ratio = errors(0.02) / errors(0.01)
    np.testing.assert_allclose(ratio, [8, 2, 4], rtol=0.1)


def test_to_rates_first_interval():
    t = np.array([1.0, 1.5, 2.5])
    inc = ImuRecord(t, np.ones((3, 3)), np.ones((3, 3)), "increments")
    np.testing.assert_array_equal(inc.to_rates().gyro[:, 0], [2.0, 2.0, 1.0])   # T0 = T1
    np.testing.assert_array_equal(inc.to_rates(first_interval_s=0.25).gyro[:, 0], [4.0, 2.0, 1.0])
    with pytest.raises(RecordError, match="needs first_interval_s"):
        ImuRecord([1.0], np.ones((1, 3)), np.ones((1, 3)), "increments").to_rates()
    with pytest.raises(RecordError, match="at least two rate samples"):
        ImuRecord([1.0], np.ones((1, 3)), np.ones((1, 3)), "rates").to_increments()


def random_records(rng):
    n = 7
    t = np.sort(rng.uniform(0, 1e9, n)) + np.arange(n)            # distinct, large, fractional
    v3 = lambda: rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-12, 3, (n, 1))  # noqa: E731
    std = lambda shape: rng.uniform(1e-9, 5, shape)               # noqa: E731
    return [
        ImuRecord(t, v3(), v3(), "increments", "line one\nline two"),
        ImuRecord(t, v3(), v3(), "rates", "rates"),
        GnssRecord(t, rng.uniform(-1.5, 1.5, n), rng.uniform(-3, 6, n), rng.normal(0, 1e3, n),
                   std((n, 3)), v3(), std((n, 3)), rng.integers(0, 7, n), "gnss"),
        GnssRecord(t, rng.uniform(-1.5, 1.5, n), rng.uniform(-3, 6, n), rng.normal(0, 1e3, n),
                   std((n, 3))),
        BaroRecord(t, rng.normal(0, 100, n), std(n), "baro"),
        OdometerRecord(t, rng.normal(0, 10, n), std(n), "odo"),
        TruthRecord(t, rng.uniform(-1.5, 1.5, n), rng.uniform(-3, 3, n), rng.normal(size=n), v3(),
                    np.c_[rng.uniform(0, 6.28, n), rng.uniform(-1.5, 1.5, n), rng.uniform(-3, 3, n)],
                    "truth"),
    ]


def test_csv_round_trip_is_bit_exact(rng, tmp_path):
    """Every float64 comes back bit for bit; kind, quality and source too (the source on
    one line)."""
    for i, rec in enumerate(random_records(rng)):
        path = rec.to_csv(tmp_path / f"r{i}.csv")
        back = type(rec).from_csv(path)
        assert back.source == " ".join(rec.source.split())
        for f in dataclasses.fields(rec):
            a, b = getattr(rec, f.name), getattr(back, f.name)
            if isinstance(a, np.ndarray):
                assert a.dtype == b.dtype and np.array_equal(a, b), (type(rec).__name__, f.name)
            elif f.name != "source":
                assert a == b
    assert not list(tmp_path.glob("*.partial"))


def test_csv_header_carries_units(tmp_path):
    text = imu_rates().to_csv(tmp_path / "imu.csv").read_text().splitlines()
    assert text[:3] == ["# gfins_fmi ImuRecord", "# source: test",
                        "t_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2"]
    # the shortest decimal of each float64 that reads back as the same float64
    assert text[3] == "100.0,0.01,-0.02,0.03,0.1,0.2,9.8"
    head = gnss(n=2).to_csv(tmp_path / "g.csv").read_text().splitlines()[2]
    assert head.endswith("vel_std_e_m_s,vel_std_n_m_s,vel_std_u_m_s,quality")


def test_csv_errors(tmp_path):
    path = imu_rates().to_csv(tmp_path / "imu.csv")
    with pytest.raises(FileFormatError, match="holds a ImuRecord: read it with ImuRecord.from_csv"):
        GnssRecord.from_csv(path)
    bad = write(tmp_path / "bad.csv", "t_s,gyro_x_deg_s\n1,2\n")
    with pytest.raises(FileFormatError, match=r"bad.csv:1: the column names 't_s,gyro_x_deg_s' are "
                       r"not a ImuRecord layout; expected one of\n  t_s,gyro_x_rad,"):
        ImuRecord.from_csv(bad)
    lines = path.read_text().splitlines()
    fields = lines[5].split(",")
    write(tmp_path / "nan.csv", "\n".join(lines[:5] + [",".join(fields[:1] + ["nan"] + fields[2:])] + lines[6:]))
    with pytest.raises(FileFormatError, match=r"nan.csv:6: gyro\[2, 0\] = nan is not finite"):
        ImuRecord.from_csv(tmp_path / "nan.csv")
    write(tmp_path / "short.csv", "\n".join(lines[:4] + ["100.01,1,2,3"]))
    with pytest.raises(FileFormatError, match="short.csv:5: 4 columns where a ImuRecord CSV line has 7"):
        ImuRecord.from_csv(tmp_path / "short.csv")
    with pytest.raises(FileFormatError, match="empty"):
        ImuRecord.from_csv(write(tmp_path / "empty.csv", ""))
    with pytest.raises(FileFormatError, match="no data lines"):
        ImuRecord.from_csv(write(tmp_path / "head.csv", "\n".join(lines[:3])))
    with pytest.raises(FileNotFoundError, match="an ImuRecord CSV was expected"):
        ImuRecord.from_csv(tmp_path / "missing.csv")
