"""Paths of the repository the tests read (sources, docs, data)."""
from __future__ import annotations

import os
import pathlib

#: the repository's root (tests/support/paths.py -> ..)
ROOT = pathlib.Path(__file__).resolve().parents[2]


def rtk_walk_dir() -> pathlib.Path | None:
    """The rtk_walk recording: ``$GFINS_RTK_WALK_DIR``, the repository's copy
    (tests/data/rtk_walk), or shared/data/rtk_walk beside the repository (CI, the lead's
    tree) or above a worktree; None when there is none."""
    env = os.environ.get("GFINS_RTK_WALK_DIR")
    candidates = ([pathlib.Path(env)] if env else []) + [ROOT / "tests" / "data" / "rtk_walk"] + \
        [p / "shared" / "data" / "rtk_walk" for p in ROOT.parents]
    return next((c for c in candidates if (c / "imu_1730_sf.csv").is_file()), None)
