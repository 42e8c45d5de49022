"""``gfins noise``: noise identification of a static IMU record (usage: ``gfins noise
--help``; the method: docs/characterise_imu.md).

    gfins noise RECORD [--format record|kfgins|rtk_walk] [--output NOISE.toml] [--table ADEV.csv]
                [--plot DIR] [--per-decade N] [--tau-max S] [--progress]

Streams the record (ImuRecord CSV, npz or Parquet, rates or increments) through the
overlapping Allan deviation, fits the IEEE Std 952 terms per axis, prints them with their
1-sigma and writes the filter's noise block (``gfins integrate --noise-file``), the
deviation table and the figure.
"""
from __future__ import annotations

import numpy as np

from gfins_fmi.analysis.allan import AllanAccumulator, averaging_factors
from gfins_fmi.analysis.noise_id import fit_noise_terms
from gfins_fmi.analysis.noise_report import identified_toml, imu_noise_of, plot_allan, terms_table
from gfins_fmi.cli.files import read_imu, run_writing
from gfins_fmi.estimation.noise_file import write_noise_file
from gfins_fmi.io.tables import TableReader
from gfins_fmi.nav.imu_errors import ImuNoise

__all__ = ["run"]

AXES = ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
_KINDS = {("gyro_x_rad", "increments"), ("gyro_x_rad_s", "rates")}


class _Stream:
    """The record's rows as rates, chunk by chunk, with its sampling checked."""

    def __init__(self, args):
        self.args = args
        self.dt = None
        self.t_prev = None
        self.gaps = 0
        self.n_rows_est = None
        self.first = None

    def chunks(self):
        a = self.args
        if a.format != "record":
            rec = read_imu(a.record, a.format).to_rates()
            self.n_rows_est = len(rec)
            yield np.column_stack([rec.t_s, rec.gyro, rec.accel]), "rates"
            return
        reader = TableReader(a.record, header=True, what="IMU record",
                             header_hint="an ImuRecord CSV starts with t_s,gyro_x_...")
        with reader:
            names = reader.names
            if not names or len(names) != 7 or names[0] != "t_s" or names[1] not in ("gyro_x_rad", "gyro_x_rad_s"):
                raise ValueError(f"{a.record}: columns {names} are not an ImuRecord's (t_s, gyro_x_rad[_s], "
                                 "..., accel_z_m_s[2]); use --format kfgins or rtk_walk for those files")
            kind = "increments" if names[1] == "gyro_x_rad" else "rates"
            bar = None
            if a.progress:
                from tqdm import tqdm   # lazy: only with --progress
                bar = tqdm(total=reader.size, unit=reader.unit, unit_scale=True, desc="reading")
            for start, block in reader:
                if self.n_rows_est is None:
                    self.n_rows_est = reader.n_rows or int(len(block) * reader.size /
                                                           max(reader.position, 1) * 1.02) + 1
                if bar is not None:
                    bar.update(reader.position - bar.n)
                yield block, kind
            if bar is not None:
                bar.close()

    def rates(self, block, kind):
        t = block[:, 0]
        if self.dt is None:
            if len(t) < 3:
                raise ValueError(f"{self.args.record}: fewer than 3 samples")
            self.dt = float(np.median(np.diff(t)))
            if not self.dt > 0:
                raise ValueError(f"{self.args.record}: times do not increase")
        d = np.diff(np.r_[self.t_prev, t] if self.t_prev is not None else t)
        bad = np.abs(d - self.dt) > 0.5 * self.dt
        self.gaps += int(np.count_nonzero(bad))
        self.t_prev = t[-1]
        y = block[:, 1:7]
        return y / self.dt if kind == "increments" else y


def run(args) -> int:
    return run_writing(_run, args, [args.record], [args.output, args.table], args.plot)


def _run(args, outs) -> int:
    st = _Stream(args)
    acc = None
    for block, kind in st.chunks():
        y = st.rates(block, kind)
        if acc is None:
            n = max(st.n_rows_est, 4)
            frac = 0.25 if args.tau_max is None else min(0.49, args.tau_max / (st.dt * n))
            m = averaging_factors(n, args.per_decade, max(frac, 1.0 / n))
            acc = AllanAccumulator(st.dt, m, 6, AXES)
        acc.add(y)
    if acc is None:
        raise ValueError(f"{args.record}: no samples")
    if st.gaps:
        raise ValueError(f"{args.record}: {st.gaps} sampling intervals differ from the median "
                         f"{st.dt:g} s by more than half of it (gaps or repeated times); the "
                         "Allan deviation needs uniform sampling: split the record at its gaps")
    ad = acc.result()
    keep = ad.tau_s <= (0.25 * ad.n_samples * ad.dt_s if args.tau_max is None else args.tau_max) * 1.0001
    for f in ("tau_s", "adev", "n_terms", "m"):
        setattr(ad, f, getattr(ad, f)[keep])
    T = ad.n_samples * ad.dt_s
    print(f"{args.record}: {ad.n_samples} samples at {1 / ad.dt_s:g} Hz ({T / 3600:.3g} h); "
          f"{ad.tau_s.size} taus from {ad.tau_s[0]:g} to {ad.tau_s[-1]:g} s")
    terms = [fit_noise_terms(ad, c) for c in range(6)]
    print(terms_table(terms))
    model: ImuNoise = imu_noise_of(terms)
    print("noise block (largest axis of each sensor): " + ", ".join(
        f"{k} {getattr(model, k):.4g}" for k in ("gyro_arw_deg_sqrt_h", "gyro_bias_instability_deg_h",
                                                 "gyro_correlation_time_s", "gyro_rrw_deg_h_sqrt_h",
                                                 "accel_vrw_ug_sqrt_hz", "accel_bias_instability_ug",
                                                 "accel_correlation_time_s", "accel_rrw_ug_sqrt_s")))
    if args.output:
        header = (f"identified by `gfins noise` from {args.record.name}: {ad.n_samples} samples at "
                  f"{1 / ad.dt_s:g} Hz ({T / 3600:.3g} h), overlapping Allan deviation, IEEE Std 952 "
                  "terms;\nthe largest axis of each sensor; quantisation and rate ramp are not in the "
                  "filter's model (see [identified])")
        write_noise_file(outs.file(args.output), model, header, identified_toml(terms))
        print(f"noise block -> {args.output}")
    if args.table:
        lo, hi = ad.confidence()
        cols = [ad.tau_s, ad.n_terms] + [ad.adev[:, c] for c in range(6)] + \
               [lo[:, c] for c in range(6)] + [hi[:, c] for c in range(6)]
        unit = ["rad_s"] * 3 + ["m_s2"] * 3
        names = (["tau_s", "n_terms"] + [f"adev_{a}_{u}" for a, u in zip(AXES, unit)]
                 + [f"low_{a}_{u}" for a, u in zip(AXES, unit)] + [f"high_{a}_{u}" for a, u in zip(AXES, unit)])
        outs.write_table(args.table, names, cols, [np.float64, np.int64] + [np.float64] * 18)
        print(f"Allan deviation with its 68% interval -> {args.table}")
    if args.plot:
        figure = args.plot / "allan.png"
        plot_allan(ad, terms, outs.file(figure), title=args.record.name)
        print("figure:", figure)
    return 0
