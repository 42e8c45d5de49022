"""The noise block file (gfins_fmi.estimation.noise_file): written and read back to the
same ImuNoise bit for bit, the [noise] table equal to FilterConfig.noise_si(), either
table alone enough, the density conventions against their definitions, refusals that
name the key."""
from __future__ import annotations

import math

import numpy as np
import pytest

from gfins_fmi.estimation import noise_file
from gfins_fmi.estimation.config import FilterConfig
from gfins_fmi.estimation.noise_file import noise_text, read_noise_file, write_noise_file
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.sim.scenarios import CONSUMER, TACTICAL


@pytest.mark.parametrize("model", [CONSUMER, TACTICAL, ImuNoise(gyro_rrw_deg_h_sqrt_h=5.0, accel_rrw_ug_sqrt_s=2.0)])
def test_round_trip(tmp_path, model):
    """Every ImuNoise field back bit for bit (repr of a float reads back exactly)."""
    p = write_noise_file(tmp_path / "n.toml", model, header="a test")
    assert read_noise_file(p) == model
    assert p.read_text().startswith("# a test")


def test_noise_table_is_the_settings_table_in_si(tmp_path):
    """[noise] holds FilterConfig(imu=...).noise_si()'s IMU members under the settings
    table's names; alone it gives back a model with the same SI noise (1e-12)."""
    doc = noise_file.tomllib.loads(noise_text(CONSUMER))   # tomllib or, before 3.11, tomli
    si = FilterConfig(imu=CONSUMER).noise_si()
    for k, v in doc["noise"].items():
        assert v == si[k]
    only = tmp_path / "si.toml"
    only.write_text("[noise]\n" + "\n".join(f"{k} = {v!r}" for k, v in doc["noise"].items()))
    back = FilterConfig(imu=read_noise_file(only)).noise_si()
    for k in doc["noise"]:
        assert back[k] == pytest.approx(si[k], rel=1e-12)


def test_density_conventions():
    """White noise of per-sample std s at dt: the Allan (two-sided) density is s sqrt(dt);
    the gyro ARW field is that in deg/sqrt(h) (x 60 x 180/pi), the accelerometer field the
    ONE-sided density sqrt(2) s sqrt(dt) in ug/sqrt(Hz) -- what ImuNoise.sample draws."""
    dt = 0.01
    m = ImuNoise(gyro_arw_deg_sqrt_h=0.6, accel_vrw_ug_sqrt_hz=150.0)
    p = m.sample_parts(200000, dt, np.random.default_rng(4))
    s_g, s_a = p["gyro_white"].std(), p["accel_white"].std()
    # 200000 x 3 draws: std known to sqrt(1/(2 n)) = 0.09%; 0.5% bound
    assert s_g * math.sqrt(dt) * 60 * 180 / math.pi == pytest.approx(0.6, rel=5e-3)
    assert math.sqrt(2) * s_a * math.sqrt(dt) / 9.80665e-6 == pytest.approx(150.0, rel=5e-3)
    si = FilterConfig(imu=m).noise_si()
    assert si["accel_vrw_m_s_sqrt_s"] == pytest.approx(s_a * math.sqrt(dt), rel=5e-3)


def test_refusals_name_the_key(tmp_path):
    p = tmp_path / "n.toml"
    with pytest.raises(FileNotFoundError, match="gfins noise"):
        read_noise_file(p)
    p.write_text("[imu]\ngyro_arw = 0.3\n")
    with pytest.raises(ValueError, match=r"unknown keys \['gyro_arw'\].*gyro_arw_deg_sqrt_h"):
        read_noise_file(p)
    p.write_text("[imu]\ngyro_arw_deg_sqrt_h = -1.0\n")
    with pytest.raises(ValueError, match="gyro_arw_deg_sqrt_h must be finite and >= 0"):
        read_noise_file(p)
    p.write_text('[imu]\ngyro_arw_deg_sqrt_h = "0.3"\n')
    with pytest.raises(ValueError, match="must be a finite number"):
        read_noise_file(p)
    p.write_text("[imu\n")
    with pytest.raises(ValueError, match="not a TOML noise block"):
        read_noise_file(p)
    p.write_text("[other]\nx = 1\n")
    with pytest.raises(ValueError, match=r"no \[imu\] or \[noise\]"):
        read_noise_file(p)
    text = noise_text(CONSUMER).replace("gyro_arw_deg_sqrt_h = 0.3", "gyro_arw_deg_sqrt_h = 0.4")
    p.write_text(text)
    with pytest.raises(ValueError, match=r"\[noise\] gyro_arw_rad_sqrt_s = .* but \[imu\] gives"):
        read_noise_file(p)
    p.write_text("[noise]\ngyro_arw_rad_sqrt_s = 1e-4\n")
    with pytest.raises(ValueError, match="missing"):
        read_noise_file(p)
