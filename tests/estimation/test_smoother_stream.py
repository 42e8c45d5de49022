"""The smoother with flat memory (gfins_fmi.estimation.smoother_stream.StreamingSmoother:
epochs and rows on disk, the backward pass in blocks, gf_ins_smooth_block) against the
whole-record smoother (IntegratedSolution.smooth: gf_ins_smooth in one call, itself checked
against an independent RTS in test_smoother.py): every column equal, bit for bit, with
tiny pieces, blocks and row chunks so that every kind of boundary is crossed — a piece
that ends on a GNSS epoch (which is also a propagation epoch), blocks of one epoch (a block
boundary on every measurement epoch), row chunks that start between epochs and on them.
Equality is exact because the computation is the same: one recursion in C, and a row reads
only the two epochs around it."""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi import io
from gfins_fmi.cli.integrate_stream import time_slice
from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
from gfins_fmi.estimation.smoother_stream import StreamingSmoother, epoch_bytes, ROW_BYTES
from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive, town_drive
from gfins_fmi.sim.vehicle import GnssReceiver

T_S = 30.0
COLUMNS = ("t_s", "q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m", "std", "sensors", "standstill")


@pytest.fixture(scope="module")
def drive():
    """A seeded 30 s town drive at 100 Hz, GNSS at 1 Hz on whole seconds (on the 0.1 s
    propagation grid and on the pieces' ends) with a 10 s outage; the fix at the start
    time is left out (a streamed run takes the fixes after the filter's time)."""
    prof = town_drive(T_S)
    rx = GnssReceiver(rate_hz=1.0, offset_s=0.0, pos_std_m=(1.0, 1.2, 2.0), vel_std_m_s=(0.05, 0.06, 0.1),
                      outages_s=((12.0, 22.0),))
    d = simulate_drive(prof, T_S, 0.01, imu=TACTICAL, gnss=rx, seed=11)
    init = InitialState(d.initial, position_std_m=(1.0, 1.5, 2.0), velocity_std_m_s=0.1,
                        attitude_std_rad=(0.005, 0.006, 0.02), gyro_scale_std=5e-4, accel_scale_std=3e-4)
    gnss = time_slice(d.gnss, float(d.initial.t_s), np.inf)
    return d.imu, gnss, init


def _whole(drive, filter_, **settings):
    imu, gnss, init = drive
    cfg = FilterConfig(imu=TACTICAL, filter=filter_, scale_factors=True, **settings)
    return IntegratedNavigator(cfg, init).run(imu, gnss, smoother=True).smooth(), cfg


def _streamed(drive, cfg, piece, block, rows):
    imu, gnss, init = drive
    sm = StreamingSmoother(IntegratedNavigator(cfg, init), block_epochs=block)
    ends = []
    with sm:
        lo = sm.navigator.t_s
        for a in range(0, len(imu.t_s), piece):
            rec = io.ImuRecord(imu.t_s[a:a + piece], imu.gyro[a:a + piece], imu.accel[a:a + piece], imu.kind, "")
            hi = float(rec.t_s[-1]) + 1e-9
            sm.run(rec, time_slice(gnss, lo, hi), checks="off")
            ends.append(float(rec.t_s[-1]))
            lo = hi
        sm.smooth()
        parts = list(sm.solutions(rows))
        folder = sm.folder
        assert folder.is_dir()
    assert not folder.exists(), f"{folder} left behind by close()"
    return parts, np.array(ends), sm


@pytest.mark.parametrize("filter_, piece, block, rows, settings", [
    ("ekf", 100, 1, 37, {}),      # pieces end on every GNSS epoch; every epoch a block boundary
    ("ekf", 333, 7, 250, {}),     # pieces end between epochs; row chunks start on epochs (250 = 2.5 s)
    ("ukf", 97, 64, 1000, {}),
    # non-holonomic and zero-velocity updates on the 0.1 s grid (at every piece's end), and
    # two samples per navigation update (coning/sculling over pairs)
    ("ekf", 100, 3, 101, {"nhc": True, "zupt": True, "subsamples": 2}),
])
def test_streamed_smoother_equals_the_whole_record_one_bit_for_bit(drive, filter_, piece, block, rows, settings):
    ref, cfg = _whole(drive, filter_, **settings)
    parts, ends, sm = _streamed(drive, cfg, piece, block, rows)
    imu, gnss, _ = drive
    if piece == 100:
        # the premise: pieces ending on GNSS epochs (updates at a piece's last sample)
        assert np.sum(np.isin(np.round(ends, 9), np.round(gnss.t_s, 9))) >= 15
    assert sm.n_epochs == len(ref.epoch_t_s), "the streamed forward pass stored another number of epochs"
    assert [len(p) for p in parts[:-1]] == [rows] * (len(parts) - 1)
    for k in COLUMNS:
        got = np.concatenate([getattr(p, k) for p in parts])
        want = getattr(ref, k)
        assert got.shape == want.shape, f"{k}: shape {got.shape}, whole record {want.shape}"
        bad = np.flatnonzero(np.any((got != want).reshape(len(got), -1), axis=1))
        assert len(bad) == 0, (f"{k}: {len(bad)} rows differ from the whole-record smoother, the first at "
                               f"t = {float(ref.t_s[bad[0]])} s")
    # the smoother did something: the outage's rows move by more than a metre
    fwd_h = IntegratedNavigator(cfg, drive[2]).run(imu, gnss).lat_rad
    assert np.max(np.abs(ref.lat_rad - fwd_h)) * 6.37e6 > 1.0


def test_disk_use_is_what_the_documentation_says(drive):
    """epoch_bytes and ROW_BYTES (docs, --help) against the files' sizes, counted here from
    the widths: 1 + 10 + n + 2 n(n+1)/2 + n^2 numbers per forward epoch, n + 9 smoothed,
    28 per row."""
    imu, gnss, init = drive
    cfg = FilterConfig(imu=TACTICAL, scale_factors=True)
    n = 21
    assert epoch_bytes(n) == 8 * (1 + 10 + n + n * (n + 1) + n * n + n + 9)
    assert ROW_BYTES == 8 * 28
    with StreamingSmoother(IntegratedNavigator(cfg, init)) as sm:
        sm.run(imu, gnss, checks="off")
        sm.smooth()
        assert sm.bytes_on_disk == sm.n_epochs * epoch_bytes(n) + sm.n_rows * ROW_BYTES


def test_refusals_say_what_to_do(drive, tmp_path):
    imu, gnss, init = drive
    cfg = FilterConfig(imu=TACTICAL)
    nav = IntegratedNavigator(cfg, init)
    with pytest.raises(ValueError, match="block_epochs must be an integer >= 1"):
        StreamingSmoother(nav, block_epochs=0)
    with pytest.raises(ValueError, match="is not a folder"):
        StreamingSmoother(nav, tmp_path / "missing")
    with StreamingSmoother(nav, tmp_path) as sm:
        assert sm.folder.parent == tmp_path
        with pytest.raises(ValueError, match="call smooth"):
            next(sm.solutions())
        with pytest.raises(ValueError, match="run\\(\\) the record before smooth"):
            StreamingSmoother(IntegratedNavigator(cfg, init)).smooth()
        with pytest.raises(ValueError, match="holds the epochs in memory"):
            sm.run(imu, gnss, smoother=True)
    ran = IntegratedNavigator(cfg, init)
    ran.run(io.ImuRecord(imu.t_s[:10], imu.gyro[:10], imu.accel[:10], imu.kind, ""), checks="off")
    with StreamingSmoother(ran) as sm, pytest.raises(ValueError, match="has not run yet"):
        sm.run(io.ImuRecord(imu.t_s[10:20], imu.gyro[10:20], imu.accel[10:20], imu.kind, ""))
    assert list(tmp_path.iterdir()) == [], "a temporary folder was left behind"


def test_nothing_is_left_behind_on_an_error(drive, tmp_path):
    """An exception inside the with block (a Ctrl-C is the same path) removes the folder."""
    imu, gnss, init = drive
    with pytest.raises(RuntimeError, match="stop"):
        with StreamingSmoother(IntegratedNavigator(FilterConfig(imu=TACTICAL), init), tmp_path) as sm:
            sm.run(imu, gnss, checks="off")
            raise RuntimeError("stop")
    assert list(tmp_path.iterdir()) == []
