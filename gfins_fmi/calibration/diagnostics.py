"""What a system-level calibration run says about itself, so that no prior, missing model
term or wrong noise figure biases the result silently (issue 22): each parameter's shift
against its prior, the per-block consistency of the prior with the data, the NIS of the
zero-velocity updates against its chi-square band (over the run, at rest and while
turning), the test of model terms the chosen model lacks, and the warnings that name the
parameters and the fix, the causes in order (model terms missing, priors too tight,
base motion, sensor noise).

The tests, for a linear-Gaussian filter (all the numbers are the filter's own):

* prior shift: d = estimate - prior mean, in prior sigmas d / s0 (reported); under a
  correct prior d ~ N(0, s0^2 - s^2) (the posterior mean moves by the data's share), so
  z = d / sqrt(s0^2 - s^2) is a standard normal; |z| > 4 names a parameter that fights
  its prior (0.006% per parameter, 0.2% for 31 of them when the prior is right);
* per block (one prior figure: gyro scale, gyro misalignment, ...): d^T (P0 - P)^+ d ~
  chi-square(rank), flagged beyond its 99.9% quantile;
* NIS: the mean over m accepted updates of a consistent filter lies in the 99% band of
  chi-square(3 m) / m;
* missing terms: a second pass with the full model and the delay; the combinations of
  its estimates the chosen model cannot represent (seed model: r_x.y, r_y.x and
  r_x.z - r_y.z, zero when every lever arm lies along its axis; the delay) are tested
  jointly (Wald: chi-square of their number of degrees, 99.9%) and named with their
  values and sigmas.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gfins_fmi.calibration.syscal_filter import prior_fields
from gfins_fmi.estimation.evaluation import chi2_band

__all__ = ["Diagnostics", "prior_checks", "nis_checks", "missing_terms", "diagnose",
           "FIGHT_Z", "BLOCK_PROB"]

#: |z| of a parameter against its prior above which it "fights its prior"
FIGHT_Z = 4.0
#: the one-sided probability of the block and missing-term chi-square tests
BLOCK_PROB = 0.999


def _chi2_upper(dof: int, prob: float = BLOCK_PROB) -> float:
    return chi2_band(dof, 1, 2 * prob - 1)[1]


@dataclass
class Diagnostics:
    """The checks of one run (see the module's docstring): ``shift`` (prior sigmas) and
    ``z_prior`` per parameter, ``fights`` (names with |z_prior| > FIGHT_Z), ``blocks``
    (dicts: field, names, nees, dof, bound, ok), ``nis`` (dict: mean, band, ok, rest,
    turning, n, refused), ``missing`` (dict: names, values, stds, units, chi2, bound,
    flagged) or None, and ``warnings`` (the sentences a user reads)."""
    shift: np.ndarray
    z_prior: np.ndarray
    fights: list
    blocks: list
    nis: dict
    missing: dict | None = None
    warnings: list = field(default_factory=list)


def prior_checks(names, model: str, delay: bool, estimate, prior_mean, prior_std, P_final):
    """(shift, z_prior, fights, blocks) of the estimates against the prior (SI, model order;
    P_final: the final covariance of the parameters)."""
    est, mu, s0 = (np.asarray(x, float) for x in (estimate, prior_mean, prior_std))
    P = np.asarray(P_final, float)
    d = est - mu
    shift = d / s0
    var_move = np.maximum(s0 ** 2 - np.diag(P), 1e-300)
    z = d / np.sqrt(var_move)
    fights = [n for n, zi in zip(names, z) if abs(zi) > FIGHT_Z]
    fields = np.array(prior_fields(model, delay))
    blocks = []
    for f in dict.fromkeys(fields):
        sel = np.flatnonzero(fields == f)
        C = np.diag(s0[sel] ** 2) - P[np.ix_(sel, sel)]
        w, V = np.linalg.eigh(0.5 * (C + C.T))
        keep = w > 1e-6 * max(w.max(), 1e-300)           # directions the data moved
        y = V[:, keep].T @ d[sel]
        nees = float(np.sum(y ** 2 / w[keep])) if keep.any() else 0.0
        dof = int(keep.sum())
        bound = _chi2_upper(dof) if dof else 0.0
        blocks.append({"field": str(f), "names": [names[k] for k in sel], "nees": nees, "dof": dof,
                       "bound": bound, "ok": dof == 0 or nees <= bound})
    return shift, z, fights, blocks


def nis_checks(epochs: dict, segments) -> dict:
    """Mean NIS of the accepted zero-velocity updates (3 dof each) with its 99% band, at
    rest and while turning, and the number of refused updates."""
    nis = np.asarray(epochs["nis"], float)
    refused = np.asarray(epochs.get("refused", np.zeros(nis.size, bool)), bool)
    t = np.asarray(epochs["t_s"], float)
    ok = ~refused
    rest = np.zeros(t.size, bool)
    for s in segments:
        if s.kind == "static":
            rest |= (t > s.t0_s) & (t <= s.t1_s)
    out = {"n": int(ok.sum()), "refused": int(refused.sum())}
    for key, sel in (("all", ok), ("rest", ok & rest), ("turning", ok & ~rest)):
        m = int(sel.sum())
        mean = float(np.mean(nis[sel])) if m else float("nan")
        band = chi2_band(3, m, 0.99) if m else (float("nan"), float("nan"))
        out[key] = {"mean": mean, "band": band, "n": m,
                    "ok": bool(m == 0 or band[0] <= mean <= band[1])}
    out["mean"], out["band"], out["ok"] = out["all"]["mean"], out["all"]["band"], out["all"]["ok"]
    return out


def missing_terms(model: str, delay: bool, full_names, full_estimate, full_cov, full_units) -> dict | None:
    """The terms a model lacks, from a pass of the full model with the delay (SI, model
    order of the full model): their values, sigmas and the joint chi-square. None when the
    chosen model has them all."""
    names = list(full_names)
    rows, labels, units = [], [], []
    def row(coef: dict):
        r = np.zeros(len(names))
        for n, c in coef.items():
            r[names.index(n)] = c
        return r
    if model == "seed":
        for lab, coef in (("lever_rx_y", {"lever_rx_y": 1.0}), ("lever_ry_x", {"lever_ry_x": 1.0}),
                          ("lever_rx_z - lever_ry_z", {"lever_rx_z": 1.0, "lever_ry_z": -1.0})):
            rows.append(row(coef))
            labels.append(lab)
            units.append(full_units[names.index("lever_rx_y")])
    if not delay:
        rows.append(row({"accel_delay": 1.0}))
        labels.append("accel_delay")
        units.append(full_units[names.index("accel_delay")])
    if not rows:
        return None
    A = np.array(rows)
    v = A @ np.asarray(full_estimate, float)
    S = A @ np.asarray(full_cov, float) @ A.T
    chi2 = float(v @ np.linalg.solve(S, v))
    bound = _chi2_upper(len(rows))
    return {"names": labels, "values": v, "stds": np.sqrt(np.diag(S)), "units": units,
            "chi2": chi2, "bound": bound, "flagged": chi2 > bound}


def _fmt(value_si: float, unit, digits: int = 4) -> str:
    return f"{value_si / unit[1]:.{digits}g} {unit[0]}"


def diagnose(report, segments, missing: dict | None, config) -> Diagnostics:
    """The checks and warnings of a :class:`gfins_fmi.calibration.system.CalibrationReport`."""
    model, delay = config.model, config.estimate_delay
    P = report.covariance[9:, 9:]
    shift, z, fights, blocks = prior_checks(report.names, model, delay, report.estimate,
                                            report.prior_mean, report.prior_std, P)
    nis = nis_checks(report.epochs, segments)
    warn = []
    if missing is not None and missing["flagged"]:
        parts = [f"{n} = {_fmt(v, u)} +- {_fmt(s, u, 2)} ({abs(v) / s:.0f} sigma)"
                 for n, v, s, u in zip(missing["names"], missing["values"], missing["stds"], missing["units"])]
        fix = ("use the full model (calibrate(config=...model='full'), gfins calibrate without "
               "--model seed)" if model == "seed" else "estimate the delay (estimate_delay=True, --delay)")
        warn.append(f"the record holds terms the {model} model lacks: {'; '.join(parts)} (joint "
                    f"chi-square {missing['chi2']:.3g} above its 99.9% bound {missing['bound']:.3g}); "
                    f"the other estimates absorb them and their sigmas are too small: {fix}")
    bad_blocks = [b for b in blocks if not b["ok"]]
    if fights or bad_blocks:
        named = list(dict.fromkeys(fights + [n for b in bad_blocks for n in b["names"]
                                             if abs(z[report.names.index(n)]) > 3.0]))
        if not named:
            named = [n for b in bad_blocks for n in b["names"]]
        flds = sorted({config_field for n in named
                       for config_field in [prior_fields(model, delay)[report.names.index(n)]]})
        shifts = ", ".join(f"{n} ({shift[report.names.index(n)]:+.1f} prior sigma)" for n in named)
        warn.append(f"estimates fight their prior: {shifts}. The prior is too tight for this IMU "
                    f"(or centred wrong): widen {', '.join(flds)} (--prior NAME=VALUE, or --grade), or "
                    "let the run widen and repeat (calibrate(widen_priors=True), --widen-priors)")
    if nis["refused"]:
        warn.append(f"{nis['refused']} zero-velocity updates were refused: their estimates would have "
                    "left the error model's range (a model term missing, a prior far off, or units)")
    above = [k for k in ("all", "rest", "turning") if nis[k]["n"] and nis[k]["mean"] > nis[k]["band"][1]]
    if (above or not nis["ok"]) and nis["n"]:
        lo, hi = nis["band"]
        where = ", ".join(f"{k} {nis[k]['mean']:.3g} (band [{nis[k]['band'][0]:.3g}, {nis[k]['band'][1]:.3g}])"
                          for k in ("rest", "turning") if nis[k]["n"])
        if above:
            causes = []
            if missing is not None and missing["flagged"]:
                causes.append("model terms missing (above)")
            elif model == "seed" or not delay:
                causes.append("model terms missing (try the full model with the delay)")
            if fights or bad_blocks:
                causes.append("priors too tight (above)")
            if model == "full" and _turning_excess(nis):
                causes.append("the z accelerometer (the full model's reference point) is off the turntable's "
                              "centre of rotation: while turning it moves at w x r_z, which the model "
                              "(r_z = 0) does not hold and the lever arms absorb; compare --model seed "
                              "(its r_zz) and mount the IMU with the z accelerometer at the centre "
                              "(docs/rotating_ins.md, 'The reference point')")
            causes.append("base motion: the turntable's base moves more than --vel-std "
                          f"{config.vel_std_m_s:g} m/s (give its RMS velocity)")
            causes.append(f"sensor noise above the assumed --arw {config.gyro_arw_deg_sqrt_h:g} deg/sqrt(h), "
                          f"--vrw {config.accel_vrw_ug_sqrt_hz:g} ug/sqrt(Hz) (measure it: Allan variance)")
            warn.append(f"the zero-velocity innovations are larger than the filter predicts ("
                        f"{' and '.join('over the run' if k == 'all' else 'at rest' if k == 'rest' else 'while turning' for k in above)}): "
                        f"mean NIS {nis['mean']:.3g}, 99% band [{lo:.3g}, {hi:.3g}]; {where}; causes, most "
                        "likely first: " + "; ".join(f"{k + 1}. {c}" for k, c in enumerate(causes)))
        else:
            warn.append(f"the zero-velocity innovations are smaller than the filter predicts: mean NIS "
                        f"{nis['mean']:.3g} below its 99% band [{lo:.3g}, {hi:.3g}] ({where}): the assumed "
                        "noise (--arw, --vrw) or base motion (--vel-std) exceeds the data's, so the "
                        "reported sigmas are upper bounds (on noise-free simulations this is expected)")
    return Diagnostics(shift, z, fights, blocks, nis, missing, warn)


def _turning_excess(nis: dict) -> bool:
    """True when the zero-velocity NIS is out of band while turning and its excess over the
    rest NIS is larger than the turning band's half-width: a rotation-borne cause (base
    motion and sensor noise would show at rest as well)."""
    t, r = nis["turning"], nis["rest"]
    if not (t["n"] and r["n"]) or t["mean"] <= t["band"][1]:
        return False
    return t["mean"] - r["mean"] > t["band"][1] - t["band"][0]
