"""The text parser alone (issue 20): ns per value of gf_text_parse (C, through
TableReader and bare) against polars' CSV reader (the reader before it), on the same
text held in memory, one core. CPU time (time.process_time) of the best of --repeat. "C parser alone": one
call over the whole text into an array allocated beforehand; "TableReader": the reader
as the commands use it (4 MiB blocks read from the file, chunks of 2^18 rows allocated
as it goes); polars: read_csv of the text in memory.

    taskset -c 0 python bench/bench_text_parse.py [--rows 1000000] [--file imu.txt --mb 200]

Texts: KF-GINS IMU lines (7 values, "%.15f", one space: the Clinger path), the same
as CSV with the shortest round-trip digits (repr: 17 significant digits often, the
strtod path for some), and, with --file, the first --mb MiB of a real file
(whitespace-separated). polars gets the text as the old reader gave it (spaces turned
into commas, which this timing leaves out) with one thread (POLARS_MAX_THREADS=1).
"""
from __future__ import annotations

import argparse
import os
import pathlib
import platform
import sys
import tempfile
import time

os.environ.setdefault("POLARS_MAX_THREADS", "1")

import numpy as np  # noqa: E402

from gfins_fmi._lib import ffi, lib, ptr  # noqa: E402
from gfins_fmi.io.tables import TableReader  # noqa: E402


def cpu(fn, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best


def bare(text: bytes, k: int, whitespace: bool):
    """One C call over the whole text (the parser alone): the output allocated and
    touched beforehand, outside the timing."""
    buf = np.frombuffer(text, np.uint8)
    n = text.count(b"\n") + 1
    out = np.zeros((n, k))
    r, u, l = ffi.new("size_t *"), ffi.new("size_t *"), ffi.new("size_t *")

    def run() -> np.ndarray:
        st = lib.gf_text_parse(ptr(buf, buf.size, "uint8_t"), buf.size, 1, k, int(whitespace), ptr(out, out.size),
                               n, r, u, l)
        assert st == lib.GF_OK, st
        return out[:r[0]]
    return run


def via_polars(csv: bytes, k: int):
    import polars as pl   # lazy: only the comparison needs it
    return pl.read_csv(csv, has_header=False, schema={f"c{j}": pl.Float64 for j in range(k)}, quote_char=None)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rows", type=int, default=1_000_000)
    ap.add_argument("--file", type=pathlib.Path)
    ap.add_argument("--mb", type=float, default=200.0)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    import polars
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, load {os.getloadavg()}, "
          f"Python {platform.python_version()}, numpy {np.__version__}, polars {polars.__version__}")
    rng = np.random.default_rng(1)
    t = np.arange(a.rows) * 0.005
    x = rng.normal(0, 1e-4, (a.rows, 6))
    texts = {"KF-GINS %.15f, spaces": ("\n".join(" ".join("%.15f" % v for v in row) for row in
                                                 np.column_stack([t, x]).tolist()).encode() + b"\n", True),
             "repr, commas": ("\n".join(",".join(repr(v) for v in row) for row in
                                        np.column_stack([t, x]).tolist()).encode() + b"\n", False)}
    if a.file:
        with open(a.file, "rb") as f:
            head = f.read(int(a.mb * 2**20))
        texts[f"{a.file.name}, first {a.mb:g} MiB"] = (head[:head.rfind(b"\n") + 1], True)
    print("| text | values | C parser alone | TableReader (C) | polars | MiB |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, (text, ws) in texts.items():
            k = 7
            csv = text.replace(b" ", b",") if ws else text
            parse = bare(text, k, ws)
            n = parse().size
            ref = via_polars(csv, k).to_numpy()
            assert np.array_equal(parse(), ref), "the parsers disagree"
            p = pathlib.Path(tmp) / "t.txt"
            p.write_bytes(text)
            c_bare = cpu(parse, a.repeat)
            c_reader = cpu(lambda: [b for _, b in TableReader(p, whitespace=ws)], a.repeat)
            c_pl = cpu(lambda: via_polars(csv, k), a.repeat)
            print(f"| {name} | {n:.3g} | {c_bare / n * 1e9:.1f} ns | {c_reader / n * 1e9:.1f} ns | "
                  f"{c_pl / n * 1e9:.1f} ns | {len(text) / 2**20:.0f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
