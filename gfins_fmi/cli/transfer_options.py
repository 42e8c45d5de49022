"""The options of ``gfins align transfer`` (issue 24): transfer alignment of a slave IMU
against a master INS — the matching, the nominal installation and which of it to
estimate, the priors, the master's errors, the truth to score against, the figure, the
simulated scenario and the convergence tolerance (units and bounds in every help, checked
at parse time by the option types of :mod:`gfins_fmi.cli.options`). Kept apart from
:mod:`gfins_fmi.cli.parser`, which adds them to ``gfins align``'s parser."""
from __future__ import annotations

import argparse
import pathlib

from gfins_fmi.cli.options import real, vector

__all__ = ["transfer_arguments"]


def transfer_arguments(p: argparse.ArgumentParser) -> None:
    """Add the transfer-alignment option group to ``gfins align``'s parser ``p``."""
    t = p.add_argument_group("transfer alignment (mode transfer; docs/alignment.md)")
    t.add_argument("--matching", choices=("velocity", "velocity+attitude"), default="velocity+attitude",
                   help="what the slave matches of the master (default velocity+attitude)")
    t.add_argument("--master-position", action="store_true", help="the master's position too")
    t.add_argument("--mount", type=vector(3, "HEADING,PITCH,ROLL in deg"), default=[0.0, 0.0, 0.0],
                   metavar="H,P,R", help="nominal mounting of the slave's axes in the master's, deg "
                   "(default 0,0,0)")
    t.add_argument("--lever", type=vector(3, "X,Y,Z in m"), default=[0.0, 0.0, 0.0], metavar="X,Y,Z",
                   help="nominal lever arm: the slave IMU from the master's, master axes, m (write "
                        "--lever=-0.1,0,0 when it starts with -)")
    t.add_argument("--time-offset", type=real("s"), default=0.0,
                   help="nominal time offset: slave stamp - master stamp, s (default 0)")
    t.add_argument("--fix", choices=("lever", "offset"), action="append", default=[],
                   help="do not estimate the lever arm or the time offset (repeatable)")
    t.add_argument("--flexure", type=vector(2, "STD_DEG,TAU_S"), default=None, metavar="STD_DEG,TAU_S",
                   help="estimate a structural flexure of this std (deg) and correlation time (s)")
    t.add_argument("--mount-std", type=real("deg", above=0.0), default=1.0,
                   help="1-sigma of the nominal mounting, deg (default 1); the slave starts from the "
                        "master's attitude turned by it, its attitude error the mounting's (+1 mrad)")
    t.add_argument("--lever-std", type=real("m", above=0.0), default=0.1,
                   help="1-sigma of the nominal lever arm, m (default 0.1)")
    t.add_argument("--offset-std", type=real("s", above=0.0), default=0.02,
                   help="1-sigma of the nominal time offset, s (default 0.02)")
    t.add_argument("--master-vel-std", type=real("m/s", above=0.0), default=0.02,
                   help="the master's velocity error as measurement noise, m/s (default 0.02)")
    t.add_argument("--master-att-std", type=vector(2, "TILT,HEADING in deg"), default=[0.0057, 0.0172],
                   metavar="TILT,HEADING", help="the master's attitude error as measurement noise, deg "
                   "(default 0.0057,0.0172: 0.1, 0.3 mrad)")
    t.add_argument("--master-att-bias", type=vector(2, "TILT,HEADING in deg"), default=[0.0, 0.0],
                   metavar="TILT,HEADING", help="the master's constant attitude error (its absolute "
                   "accuracy), deg: added to the slave's attitude 1-sigma (default 0,0)")
    t.add_argument("--truth", type=pathlib.Path, default=None,
                   help="the slave's true navigation record (TruthRecord CSV): attitude errors and 3-sigma")
    t.add_argument("--truth-json", type=pathlib.Path, default=None,
                   help="the true mounting, lever arm, offset and biases (JSON: mount_deg, lever_arm_m, "
                        "time_offset_s, gyro_bias_deg_h, accel_bias_mg; any of them)")
    t.add_argument("--plot", type=pathlib.Path, default=None, help="the convergence figure (PNG)")
    t.add_argument("--simulate", type=real("s", above=1.0), default=None, metavar="SECONDS",
                   help="first write a simulated scenario of this length to SLAVE_IMU and MASTER_NAV "
                        "(a MEMS slave mounted 20, -15, 25 arcmin off, 0.1 m away, 15 ms late, beside a "
                        "navigation-grade INS on a car rolling its platform +-30 deg), its truth beside "
                        "them (SLAVE_IMU.truth.csv, .truth.json)")
    t.add_argument("--sim-seed", type=int, default=0, help="seed of --simulate (default 0)")
    t.add_argument("--tolerance", type=real("arcmin", above=0.0), default=1.0,
                   help="the mounting's heading and roll 1-sigma at the end below which it is aligned, "
                        "arcmin (default 1)")
