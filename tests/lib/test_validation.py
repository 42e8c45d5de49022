"""The one boundary check between Python and the C core (gfins_fmi._lib): every array a
caller hands in is checked for dtype, shape and finiteness before C gets a pointer, and
every pointer C gets covers exactly the elements it reads or writes.

Issue 15, item 2: GyroFreeNavigator read beyond a 2-element initial velocity (the C core
reads 3); these tests run every entry point that takes an initial state, a rate or a
record with arrays one element short, and check the source for pointers handed to C
outside the helper.
"""
from __future__ import annotations

import ast
import pathlib

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi import _lib
from gfins_fmi.sim import trajectory as tj

PACKAGE = pathlib.Path(gf.__file__).resolve().parent


@pytest.fixture(scope="module")
def circle():
    return tj.sample(tj.Circle(), 0.05, 0.01)


def _state(tr, **change):
    x0 = gf.NavState.from_trajectory(tr, 0)
    for k, v in change.items():
        setattr(x0, k, v)
    return x0


def _strapdown(x0, tr):
    gf.Strapdown(x0).run(tr.dtheta_rad, tr.dv_m_s, dt_s=0.01)


def _strapdown_flat(x0, tr):
    gf.Strapdown(x0, gf.SinsConfig(earth="flat")).run(tr.dtheta_rad, tr.dv_m_s, dt_s=0.01)


def _gfnav(x0, tr):
    g = gf.layout("qin9", 0.1)
    gf.GyroFreeNavigator(g, x0, "sqrt", tr.gyro_rad_s[0]).run(tr.array_outputs(g), 0.01)


def _gfnav_flat(x0, tr):
    g = gf.layout("qin9", 0.1)
    gf.GyroFreeNavigator(g, x0, "sqrt", tr.gyro_rad_s[0], sins=gf.SinsConfig(earth="flat")).run(
        tr.array_outputs(g), 0.01)


def _sins_fmu(x0, tr):
    from gfins_fmi.fmi.models import run_sins_fmu
    run_sins_fmu(tr.dtheta_rad, tr.dv_m_s, 0.01, x0)


def _gfnav_fmu(x0, tr):
    from gfins_fmi.fmi.models import run_gfnav_fmu
    run_gfnav_fmu("qin9", tr.array_outputs(gf.layout("qin9", 0.1)), 0.01, x0, strategy="sqrt",
                  omega_init_rad_s=tr.gyro_rad_s[0])


NAVIGATORS = {"Strapdown": _strapdown, "GyroFreeNavigator": _gfnav, "run_sins_fmu": _sins_fmu,
              "run_gfnav_fmu": _gfnav_fmu}
BAD_STATES = {
    "v_short": (dict(v_n_m_s=np.array([1.0, 2.0])), r"initial\.v_n_m_s .*3"),
    "v_long": (dict(v_n_m_s=np.zeros(4)), r"initial\.v_n_m_s .*3"),
    "v_nan": (dict(v_n_m_s=np.array([0.0, np.nan, 0.0])), r"initial\.v_n_m_s .*finite"),
    "q_short": (dict(q_bn=np.array([1.0, 0.0, 0.0])), r"initial\.q_bn .*4"),
    "q_2d": (dict(q_bn=np.array([[1.0, 0.0, 0.0, 0.0]])), r"initial\.q_bn .*4"),
    "q_text": (dict(q_bn=np.array(["1", "0", "0", "0"])), r"initial\.q_bn .*real numbers"),
    "q_zero": (dict(q_bn=np.zeros(4)), r"initial\.q_bn .*normalised"),
    "lat_pole": (dict(lat_rad=np.pi / 2), r"initial\.lat_rad .*\(-89\.9, 89\.9\) deg"),
    "lat_nan": (dict(lat_rad=np.nan), r"initial\.lat_rad .*finite"),
    "lon_inf": (dict(lon_rad=np.inf), r"initial\.lon_rad .*finite"),
    "h_absurd": (dict(h_m=-4e6), r"initial\.h_m .*-a/2"),
    "t_nan": (dict(t_s=np.nan), r"initial\.t_s .*finite"),
    "t_vector": (dict(t_s=np.zeros(2)), r"initial\.t_s .*a real number"),
}


@pytest.mark.parametrize("bad", sorted(BAD_STATES))
@pytest.mark.parametrize("entry", sorted(NAVIGATORS))
def test_every_navigator_checks_the_initial_state(circle, entry, bad):
    """The same initial-state check, with the same message, in every navigator (before:
    GyroFreeNavigator handed a 2-element velocity to C, which read a third value from
    beyond the array)."""
    change, match = BAD_STATES[bad]
    with pytest.raises((ValueError, TypeError), match=match):   # TypeError: not numbers
        NAVIGATORS[entry](_state(circle, **change), circle)


@pytest.mark.parametrize("entry", [_strapdown_flat, _gfnav_flat], ids=["Strapdown", "GyroFreeNavigator"])
def test_flat_position_is_checked(circle, entry):
    with pytest.raises(ValueError, match=r"initial\.pos_m .*3"):
        entry(_state(circle, pos_m=np.zeros(2)), circle)
    entry(_state(circle, pos_m=None), circle)     # none given: the origin


@pytest.mark.parametrize("call", [
    lambda: gf.RateSolver(gf.layout("qin9", 0.1), "sqrt", [1.0, 2.0]),
    lambda: gf.Accel9Solver(0.1, [1.0, 2.0]),
    lambda: gf.solve_accel9(np.zeros((2, 9)), 0.01, 0.1, [1.0, 2.0]),
    lambda: gf.GyroFreeNavigator(gf.layout("qin9", 0.1),
                                 gf.NavState.from_euler([0, 0, 0], [0, 0, 0], 0.5, 1.0, 0.0),
                                 "sqrt", [1.0, 2.0]),
], ids=["RateSolver", "Accel9Solver", "solve_accel9", "GyroFreeNavigator"])
def test_initial_rate_must_have_three_elements(call):
    with pytest.raises(ValueError, match=r"omega_init_rad_s must have shape \(3,\)"):
        call()


def test_euler_to_quat_checks_its_argument():
    with pytest.raises(ValueError, match=r"euler_rad .*shape \(3,\)"):
        gf.euler_to_quat([0.1, 0.2])
    with pytest.raises(ValueError, match="euler_rad .*finite"):
        gf.euler_to_quat([0.1, np.nan, 0.0])


def test_external_height_and_times_are_checked():
    x0 = gf.NavState.from_euler([0, 0, 0], [0, 0, 0], 0.5, 1.0, 0.0)
    z = np.zeros((5, 3))
    with pytest.raises(ValueError, match=r"h_ext_m must have shape \(5,\)"):
        gf.Strapdown(x0, gf.SinsConfig(vertical="baro")).run(z, z, dt_s=0.01, h_ext_m=np.zeros(4))
    with pytest.raises(ValueError, match=r"t_s must have shape \(5,\)"):
        gf.Strapdown(x0).run(z, z, t_s=np.arange(4.0))
    g = gf.layout("qin9", 0.1)
    with pytest.raises(ValueError, match=r"h_ext_m must have shape \(5,\)"):
        gf.GyroFreeNavigator(g, x0, sins=gf.SinsConfig(vertical="baro")).run(
            np.zeros((5, 9)), 0.01, h_ext_m=np.zeros(6))


def test_the_helper_names_argument_shape_unit_and_the_fault():
    a = _lib.as_array("gyro", np.zeros((4, 3), dtype=np.int16)[:, ::-1], (None, 3), "rad")
    assert a.dtype == np.float64 and a.flags.c_contiguous and a.shape == (4, 3)
    with pytest.raises(ValueError, match=r"gyro must have shape \(n, 3\) in rad; got shape \(4, 2\)"):
        _lib.as_array("gyro", np.zeros((4, 2)), (None, 3), "rad")
    with pytest.raises(TypeError, match="gyro must hold real numbers in rad; got dtype bool"):
        _lib.as_array("gyro", np.zeros((4, 3), dtype=bool), (None, 3), "rad")
    with pytest.raises(ValueError, match=r"v must be finite; got \[0.0, nan, 0.0\]"):
        _lib.as_array("v", [0.0, np.nan, 0.0], (3,), "m/s")
    # records keep their NaN: the C core stops at the sample and returns what came before
    assert np.isnan(_lib.as_array("A", [[np.nan]], (None, 1), "m/s^2", finite=False)).any()
    assert _lib.as_scalar("dt", np.float32(0.5), "s", above=0.0) == 0.5
    for bad in (0.0, -1.0, np.nan, np.inf):
        with pytest.raises(ValueError, match="dt must be finite and > 0 s"):
            _lib.as_scalar("dt", bad, "s", above=0.0)
    for bad in (True, "1", None, [1.0]):
        with pytest.raises(TypeError, match="dt must be a real number"):
            _lib.as_scalar("dt", bad, "s", above=0.0)
    with pytest.raises(ValueError, match=r"lat must be finite and in \(-90, 90\) deg"):
        _lib.as_scalar("lat", 90.0, "deg", above=-90.0, below=90.0)


def test_pointers_cover_exactly_what_c_accesses():
    """``ptr`` is the only way a buffer reaches C: it refuses a buffer whose size, dtype
    or layout differs from what the C function will read or write."""
    assert len(_lib.ptr(np.zeros(3), 3)) == 3
    with pytest.raises(ValueError, match="2 elements where C accesses 3"):
        _lib.ptr(np.zeros(2), 3)
    with pytest.raises(ValueError, match="4 elements where C accesses 3"):   # larger too
        _lib.ptr(np.zeros(4), 3)
    with pytest.raises(TypeError, match="float64"):
        _lib.ptr(np.zeros(3, dtype=np.float32), 3)
    with pytest.raises(ValueError, match="C-contiguous"):
        _lib.ptr(np.zeros((3, 2))[:, 0], 3)
    with pytest.raises(TypeError, match="uint8"):
        _lib.ptr(np.zeros(3), 3, "uint8_t")


def test_array_shape_check_and_the_single_sample_hint():
    """Every way a shape can be wrong is refused; the reshape hint appears only where it
    is the fix (a single sample handed in for a record of rows)."""
    with pytest.raises(ValueError, match=r"use gyro\.reshape\(1, 3\)"):
        _lib.as_array("gyro", np.zeros(3), (None, 3), "rad")
    cases = [(np.zeros(4), (None, 3)),            # a vector of another length: no hint
             (np.zeros((2, 3, 1)), (None, 3)),    # more dimensions
             (np.zeros(3), (3, 3)),               # fixed shape, not a record
             (np.zeros((2, 2)), (None,)),         # a 1-D record given rows
             (np.zeros((3, 1)), (3,)),            # fewer dimensions expected
             (np.zeros(3), (None, 3, 3))]         # a record of matrices: no row hint
    for value, shape in cases:
        with pytest.raises(ValueError, match="must have shape") as info:
            _lib.as_array("x", value, shape, "m")
        assert "reshape" not in str(info.value), (value.shape, shape)
    assert _lib.as_array("x", np.zeros((0, 3)), (None, 3), "m").shape == (0, 3)
    # records keep NaN and Inf for the C core to locate (as_rows is as_array(finite=False))
    rows = _lib.as_rows("A", [[np.nan, 1.0], [np.inf, 2.0]], 2, "m/s^2")
    assert rows.shape == (2, 2) and np.isnan(rows[0, 0]) and np.isinf(rows[1, 0])


def test_helper_options_are_keyword_only_and_annotations_resolve():
    """``finite`` and the bounds are keyword-only: a positional ``0.0`` at a call would be a
    bound nobody can see. The annotations resolve (documentation tools evaluate them)."""
    with pytest.raises(TypeError):
        _lib.as_array("x", np.zeros(3), (3,), "m", False)
    with pytest.raises(TypeError):
        _lib.as_scalar("dt", 1.0, "s", 0.0)
    import typing
    for f in (_lib.as_array, _lib.as_scalar, _lib.as_rows, _lib.as_positive_scalar,
              _lib.as_vector3, _lib.ptr, _lib.done_before, _lib.as_start_index,
              _lib.first_nonfinite):
        typing.get_type_hints(f)


def test_scalars_zero_d_arrays_positive_and_start_index():
    assert _lib.as_scalar("dt", np.array(0.25), "s") == 0.25        # a 0-d array is a scalar
    with pytest.raises(TypeError, match="real number"):
        _lib.as_scalar("dt", np.array([0.25]), "s")
    assert _lib.as_positive_scalar("l", 1e-9, "m") == 1e-9
    for bad in (0.0, -1e-300, -0.5):
        with pytest.raises(ValueError, match="l must be finite and > 0 m"):
            _lib.as_positive_scalar("l", bad, "m")
    assert _lib.as_start_index(0) == 0 and _lib.as_start_index(np.int64(12)) == 12
    for bad in (-1, True, 2.0, "3"):
        with pytest.raises(ValueError, match="start_index must be an integer >= 0"):
            _lib.as_start_index(bad)


def test_partial_result_messages_count_the_samples_done():
    """``done_before`` tells how much of a record was solved before a bad sample: the
    sample numbers are the record's (``start`` onwards), the last one ``start + k - 1``."""
    assert _lib.done_before(0) == "no sample was solved before it (.partial is empty)"
    assert _lib.done_before(1, 7) == "sample 7 was solved (see .partial)"
    assert _lib.done_before(2, 7) == "samples 7..8 were solved (see .partial)"
    assert _lib.done_before(5, 0, "filtered") == "samples 0..4 were filtered (see .partial)"
    assert _lib.done_before(3, 1) == "samples 1..3 were solved (see .partial)"
    assert _lib.done_before(2) == "samples 0..1 were solved (see .partial)"   # record start 0


def test_first_nonfinite_names_the_first_bad_column():
    a = np.array([[1.0, 2.0, 3.0, 4.0], [0.0, np.nan, np.inf, np.nan]])
    assert _lib.first_nonfinite(a, 1) == 1          # the first, not the last
    assert _lib.first_nonfinite(a, 0) == -1         # none: exactly -1
    assert _lib.first_nonfinite(np.array([[-np.inf, 0.0]]), 0) == 0


def test_struct_buffers_must_be_records_of_the_struct_size():
    """``ptr`` with a C struct type: only a C-contiguous numpy structured array whose
    records have the struct's size, with exactly the number of records C accesses."""
    ctype = "gf_vehicle_sample"
    size = _lib.ffi.sizeof(ctype)
    rec = np.dtype([("d", np.float64, (size // 8,))])
    assert rec.itemsize == size
    buf = np.zeros(4, dtype=rec)
    p = _lib.ptr(buf, 4, ctype)
    assert _lib.ffi.typeof(p) is _lib.ffi.typeof(f"{ctype} *")
    assert int(_lib.ffi.cast("uintptr_t", p)) == buf.ctypes.data
    for n in (3, 5):
        with pytest.raises(ValueError, match=f"4 records where C accesses {n}"):
            _lib.ptr(buf, n, ctype)
    with pytest.raises(ValueError, match="C-contiguous"):
        _lib.ptr(np.zeros(8, dtype=rec)[::2], 4, ctype)
    bad = (np.zeros(4, dtype=np.dtype(f"V{size}")),                           # unstructured bytes
           np.zeros(4, dtype=np.dtype([("d", np.float64, (size // 8 + 1,))])),  # longer records
           np.zeros(4, dtype=np.dtype([("d", np.float64, (size // 8 - 1,))])),  # shorter records
           np.zeros((4, size // 8)),                                           # plain doubles
           [0.0] * size)                                                        # not an array
    for b in bad:
        with pytest.raises(TypeError, match=f"structured array of {size}-byte records"):
            _lib.ptr(b, 4, ctype)


def _calls(tree):
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            yield node


def test_no_module_hands_c_a_buffer_outside_the_helper():
    """Source audit of every module: buffers reach C only through ``_lib.ptr`` (no
    ``ffi.from_buffer`` elsewhere), and every ``ptr`` call outside the signal-conditioning
    module states the number of elements C accesses."""
    offenders = []
    for path in sorted(PACKAGE.glob("**/*.py")):
        if path.name == "_lib.py":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for call in _calls(tree):
            f = call.func
            if isinstance(f, ast.Attribute) and f.attr == "from_buffer":
                offenders.append(f"{path.name}:{call.lineno}: ffi.from_buffer")
            if isinstance(f, ast.Name) and f.id == "ptr" and len(call.args) + len(call.keywords) < 2:
                offenders.append(f"{path.name}:{call.lineno}: ptr() without a size")
    assert not offenders, "\n".join(offenders)


def test_misspelled_keywords_are_refused():
    g = gf.layout("qin9", 0.1)
    x0 = gf.NavState.from_euler([0, 0, 0], [0, 0, 0], 0.5, 1.0, 0.0)
    with pytest.raises(TypeError, match="init_std"):
        gf.GyroFreeNavigator(g, x0, "fused", init_std=1.0)
    nav = gf.GyroFreeNavigator(g, x0, "fused", init_std_rad_s=0.5, bias_walk_rad_s2_sqrt_s=0.0,
                               init_bias_std_rad_s2=0.0)
    assert nav is not None
    with pytest.raises(ValueError, match=r"init_bias_std_rad_s2 must be finite and in \[0, 1000\]"):
        gf.GyroFreeNavigator(g, x0, "fused", init_bias_std_rad_s2=-1.0)
    with pytest.raises(ValueError, match=r"bias_walk_rad_s2_sqrt_s must be finite and in \[0, 1000\]"):
        gf.RateSolver(g, "fused", bias_walk_rad_s2_sqrt_s=np.nan)


def test_commands_python_entry_points_check_their_parameters_first(tmp_path):
    """The functions behind ``gfins demo / reproduce / cosim`` refuse bad parameters
    before doing any work (before: tracebacks after part of the run, NaN tables)."""
    from gfins_fmi.fmi.reference import compare_runners
    from gfins_fmi.experiments import demo
    from gfins_fmi.experiments import qin as reproduce
    from gfins_fmi.sim.vehicle import VehicleProfile
    out = tmp_path / "out"
    for kwargs, match in ((dict(duration_s=0.0), "duration_s must be finite and > 0 s"),
                          (dict(dt_s=-0.01), "dt_s must be finite and > 0 s"),
                          (dict(noise_m_s2=-1.0), "noise_m_s2 must be finite and >= 0"),
                          (dict(duration_s=0.01, dt_s=0.01), "fewer than 2 samples")):
        with pytest.raises(ValueError, match=match):
            demo.run(out_dir=out, **kwargs)
    with pytest.raises(ValueError, match="runs must be an integer >= 1"):
        reproduce.run_qin(runs=0, progress=False)
    with pytest.raises(ValueError, match="stop_s must be finite and >= 0.01 s"):
        compare_runners("gfnav_qin9", VehicleProfile.seed001(align_s=1.0), 0.0, out)
    assert not out.exists()
