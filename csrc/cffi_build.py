"""Generate the C source of the cffi extension ``gfins_fmi._core`` (API mode).

Usage: ``python cffi_build.py OUTPUT.c``  (run by CMake at build time)

The declarations handed to cffi are cut out of the public headers, between the
``/* CDEF BEGIN */`` and ``/* CDEF END */`` markers, so each C declaration is written
once. The generated source is compiled and linked against the static core library by
CMake; nothing here compiles.
"""
from __future__ import annotations

import pathlib
import re
import sys

import cffi

HERE = pathlib.Path(__file__).resolve().parent
# Public headers (paths under csrc/, the one include root), in dependency order.
HEADERS = [
    "base/gf_status.h",
    "base/gf_allan.h",
    "base/gf_text.h",
    "gyrofree/gf_array.h",
    "gyrofree/gf9.h",
    "nav/gf_earth.h",
    "nav/gf_sins.h",
    "est/gf_kalman.h",
    "gyrofree/gf_array_solver.h",
    "gyrofree/gf_layout.h",
    "gyrofree/gf_gfins.h",
    "gyrofree/gf_gfnav.h",
    "nav/gf_biquad.h",
    "nav/gf_imu_error.h",
    "sim/gf_vehicle.h",
    "sim/gf_noise.h",
    "sim/gf_aiding.h",
    "est/gf_ins_gnss.h",
    "sim/gf_rot.h",
    "est/gf_ins_model.h",
    "est/gf_syscal.h",
]
_BLOCK = re.compile(r"/\* CDEF BEGIN \*/(.*?)/\* CDEF END \*/", re.S)
_COMMENT = re.compile(r"/\*.*?\*/", re.S)


def cdef_text() -> str:
    parts = []
    for name in HEADERS:
        text = (HERE / name).read_text(encoding="utf-8")
        blocks = _BLOCK.findall(text)
        if not blocks:
            raise SystemExit(f"{name}: no CDEF BEGIN/END block")
        parts += [_COMMENT.sub("", b) for b in blocks]
    return "\n".join(parts)


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    ffi = cffi.FFI()
    ffi.cdef(cdef_text())
    ffi.set_source("gfins_fmi._core", "\n".join(f'#include "{h}"' for h in HEADERS))
    ffi.emit_c_code(argv[1])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
