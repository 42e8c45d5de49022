"""gather_measurements (estimation/measurements.py): the records become one time-sorted
array of gf_ins_meas; a NaN or Inf anywhere (time, value, std) and a std <= 0 on any axis a
kind uses are refused, naming the kind and the time; the std columns a kind does not use
are not checked. The records are plain namespaces here, so that values a record class
would already refuse reach the function's own checks."""
from __future__ import annotations

from types import SimpleNamespace as NS

import numpy as np
import pytest

from gfins_fmi._lib import lib
from gfins_fmi.estimation.measurements import gather_measurements


def gnss(**change):
    rec = dict(t_s=np.array([1.0, 2.0]), lat_rad=np.array([0.5, 0.5]),
               lon_rad=np.array([2.0, 2.0]), h_m=np.array([10.0, 11.0]),
               pos_std_m=np.array([[1.0, 2.0, 3.0]] * 2),
               vel_enu_m_s=np.array([[4.0, 5.0, 6.0]] * 2),
               vel_std_m_s=np.array([[0.1, 0.2, 0.3]] * 2))
    rec.update(change)
    return NS(**rec)


def scalar(t, value, std):
    return NS(t_s=np.asarray(t, float), h_m=np.asarray(value, float),
              speed_m_s=np.asarray(value, float), std_m=np.asarray(std, float),
              std_m_s=np.asarray(std, float))


def test_every_kind_in_time_order_with_its_columns():
    baro = scalar([1.5], [12.0], [0.7])
    odo = scalar([0.5], [3.0], [0.05])
    speed = scalar([2.5], [3.5], [0.04])
    m = gather_measurements(gnss(), baro, odo, True, speed=speed)
    assert m["t_s"].tolist() == [0.5, 1.0, 1.0, 1.5, 2.0, 2.0, 2.5]
    assert m["type"].tolist() == [lib.GF_INS_MEAS_ODO, lib.GF_INS_MEAS_GNSS_POS,
                                  lib.GF_INS_MEAS_GNSS_VEL, lib.GF_INS_MEAS_BARO,
                                  lib.GF_INS_MEAS_GNSS_POS, lib.GF_INS_MEAS_GNSS_VEL,
                                  lib.GF_INS_MEAS_SPEED]
    np.testing.assert_array_equal(m["std"][1], [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(m["z"][2], [4.0, 5.0, 6.0])
    # one-row kinds: the value and std in column 0, the unused columns 0 and not checked
    np.testing.assert_array_equal(m["std"][6], [0.04, 0.0, 0.0])
    np.testing.assert_array_equal(m["z"][3], [12.0, 0.0, 0.0])


@pytest.mark.parametrize("where", ["t_s", "z", "std"])
def test_a_nonfinite_time_value_or_std_alone_is_refused(where):
    g = gnss()
    if where == "t_s":
        g.t_s = np.array([1.0, np.nan])
    elif where == "z":
        g.h_m = np.array([10.0, np.inf])
    else:
        g.pos_std_m = np.array([[1.0, 2.0, 3.0], [1.0, np.nan, 3.0]])
    with pytest.raises(ValueError, match="measurement gnss_pos at t = .* holds NaN or Inf"):
        gather_measurements(g, None, None, False)


@pytest.mark.parametrize("value", [0.0, -2.0])
@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("kind", ["pos", "vel"])
def test_a_std_of_zero_or_below_on_any_axis_is_refused(kind, axis, value):
    std = np.array([[1.0, 2.0, 3.0], [1.0, 2.0, 3.0]])
    std[1, axis] = value
    g = gnss(**{f"{kind}_std_m": std} if kind == "pos" else {"vel_std_m_s": std})
    with pytest.raises(ValueError, match=rf"gnss_{kind} at t = 2.0 s has a standard deviation <= 0"):
        gather_measurements(g, None, None, True)


@pytest.mark.parametrize("value", [0.0, -0.5])
@pytest.mark.parametrize("which", ["baro", "odometer", "speed"])
def test_a_one_row_kind_with_std_zero_or_below_is_refused(which, value):
    bad, good = scalar([1.0, 2.0], [1.0, 1.0], [0.5, value]), None
    args = dict(baro=good, odometer=good, speed=good)
    args[which] = bad
    with pytest.raises(ValueError, match=r"at t = 2.0 s has a standard deviation <= 0"):
        gather_measurements(None, args["baro"], args["odometer"], False, speed=args["speed"])


def test_the_first_bad_std_is_named_and_the_largest_std_taken():
    """Of several epochs with a std <= 0 the first is named; a std of exactly MAX_STD
    (1e100) is taken, one above it refused (its square would near the double's range)."""
    from gfins_fmi.estimation.measurements import MAX_STD
    g = gnss(pos_std_m=np.array([[1.0, 0.0, 3.0], [1.0, 2.0, -1.0]]))
    with pytest.raises(ValueError, match=r"gnss_pos at t = 1.0 s has a standard deviation <= 0"):
        gather_measurements(g, None, None, False)
    ok = gather_measurements(gnss(pos_std_m=np.array([[1.0, 2.0, MAX_STD]] * 2)), None, None, False)
    assert ok["std"][0, 2] == 1e100
    with pytest.raises(ValueError, match="gnss_pos"):
        gather_measurements(gnss(pos_std_m=np.array([[1.0, 2.0, 1e101]] * 2)), None, None, False)
