"""What a noise identification says, in datasheet units: the table of fitted terms, the
:class:`~gfins_fmi.nav.imu_errors.ImuNoise` the filter is given, the per-axis record of
the noise block, the log-log figure with the fitted asymptotes.

Axes 0-2 are gyros (rates in rad/s), 3-5 accelerometers (m/s^2).
"""
from __future__ import annotations

import numpy as np

from gfins_fmi.analysis.allan import AllanDeviation
from gfins_fmi.analysis.noise_id import NoiseTerms
from gfins_fmi.nav.imu_errors import DEG_H, UG, ImuNoise

__all__ = ["UNITS", "terms_table", "imu_noise_of", "identified_toml", "plot_allan", "in_units"]

_DEG = np.pi / 180.0
#: per sensor and term: (unit, factor from SI)
UNITS = {
    "gyro": {"quantisation": ("arcsec", 1 / (_DEG / 3600)), "white": ("deg/sqrt(h)", 60 / _DEG),
             "bias_instability": ("deg/h", 1 / DEG_H), "rate_random_walk": ("deg/h/sqrt(h)", 60 / DEG_H),
             "rate_ramp": ("deg/h^2", 3600 / DEG_H), "gm_sigma": ("deg/h", 1 / DEG_H), "gm_tau_s": ("s", 1.0)},
    "accel": {"quantisation": ("m/s", 1.0), "white": ("m/s/sqrt(h)", 60.0),
              "bias_instability": ("ug", 1 / UG), "rate_random_walk": ("ug/sqrt(s)", 1 / UG),
              "rate_ramp": ("ug/h", 3600 / UG), "gm_sigma": ("ug", 1 / UG), "gm_tau_s": ("s", 1.0)},
}
_LABEL = {"quantisation": "quantisation Q", "white": "random walk N (ARW / VRW)",
          "bias_instability": "bias instability B", "rate_random_walk": "rate random walk K",
          "rate_ramp": "rate ramp R", "gm_sigma": "Gauss-Markov sigma", "gm_tau_s": "Gauss-Markov T"}
_AXES = ("gyro x", "gyro y", "gyro z", "accel x", "accel y", "accel z")


def in_units(sensor: str, name: str, value: float) -> float:
    """A term's SI value in its datasheet unit (:data:`UNITS`)."""
    return value * UNITS[sensor][name][1]


def terms_table(terms: list) -> str:
    """The fitted terms of the six axes with their 1-sigma, as a markdown table."""
    lines = ["| term | unit | " + " | ".join(_AXES[:3]) + " | unit | " + " | ".join(_AXES[3:]) + " |",
             "|---|---|" + "---|" * 3 + "---|" + "---|" * 3]

    def cell(t: NoiseTerms, sensor, name):
        v, s = in_units(sensor, name, t.values[name]), in_units(sensor, name, t.stds[name])
        if v == 0 and name in ("gm_sigma", "gm_tau_s"):
            return "—"
        return f"{v:.4g} ± {s:.2g}" if v > 0 else f"0 (< {s:.2g})"

    for name in ("quantisation", "white", "bias_instability", "gm_sigma", "gm_tau_s",
                 "rate_random_walk", "rate_ramp"):
        row = [_LABEL[name], UNITS["gyro"][name][0]] + [cell(terms[c], "gyro", name) for c in range(3)]
        row += [UNITS["accel"][name][0]] + [cell(terms[c], "accel", name) for c in range(3, 6)]
        lines.append("| " + " | ".join(row) + " |")
    lines.append("| floor model | | " + " | ".join(t.model for t in terms[:3]) + " | | "
                 + " | ".join(t.model for t in terms[3:]) + " |")
    extra = [t.values["white"] for t in terms[3:]]
    lines.append("")
    lines.append("accelerometer white noise as a one-sided density (ImuNoise.accel_vrw_ug_sqrt_hz = "
                 "sqrt(2) N / UG): " + ", ".join(f"{np.sqrt(2) * x / UG:.4g}" for x in extra) + " ug/sqrt(Hz)")
    return "\n".join(lines)


def imu_noise_of(terms: list) -> ImuNoise:
    """The filter's noise model: for each sensor the largest axis of each term (a filter
    told less noise than an axis has is inconsistent on that axis; one told the largest
    is at worst conservative on the others). The Gauss-Markov bias is the fitted bump,
    or the flicker floor converted (:meth:`NoiseTerms.filter_bias`)."""
    def worst(ts, name):
        return max(t.values[name] for t in ts)

    def bias(ts):
        pairs = [t.filter_bias() for t in ts]
        sigma, tau = max(pairs, key=lambda p: p[0])
        return sigma, (tau if tau > 0 else 100.0)

    g, a = terms[:3], terms[3:]
    gs, gt = bias(g)
    as_, at = bias(a)
    return ImuNoise(gyro_arw_deg_sqrt_h=worst(g, "white") * 60 / _DEG,
                    gyro_bias_instability_deg_h=gs / DEG_H, gyro_correlation_time_s=gt,
                    gyro_rrw_deg_h_sqrt_h=worst(g, "rate_random_walk") * 60 / DEG_H,
                    accel_vrw_ug_sqrt_hz=worst(a, "white") * np.sqrt(2.0) / UG,
                    accel_bias_instability_ug=as_ / UG, accel_correlation_time_s=at,
                    accel_rrw_ug_sqrt_s=worst(a, "rate_random_walk") / UG)


def identified_toml(terms: list) -> str:
    """The per-axis fit as a TOML table ``[identified]`` (values and 1-sigma in datasheet
    units, keys carrying them; kept for people, not read by the filter)."""
    lines = ["[identified]   # the per-axis fit (x, y, z): informative, not read by the filter",
             f'gyro_floor_model = {[t.model for t in terms[:3]]!r}'.replace("'", '"'),
             f'accel_floor_model = {[t.model for t in terms[3:]]!r}'.replace("'", '"')]
    for sensor, ts in (("gyro", terms[:3]), ("accel", terms[3:])):
        for name in ("quantisation", "white", "bias_instability", "gm_sigma", "gm_tau_s",
                     "rate_random_walk", "rate_ramp"):
            unit = UNITS[sensor][name][0].replace("/", "_").replace("(", "").replace(")", "").replace("^", "")
            key = f"{sensor}_{name}_{unit}"
            vals = [in_units(sensor, name, t.values[name]) for t in ts]
            stds = [in_units(sensor, name, t.stds[name]) for t in ts]
            lines.append(f"{key} = [{', '.join(repr(float(v)) for v in vals)}]")
            lines.append(f"{key}_std = [{', '.join(repr(float(v)) for v in stds)}]")
    return "\n".join(lines)


def plot_allan(ad: AllanDeviation, terms: list, path, title: str = ""):
    """Log-log figure: the deviation of every axis with its 68% interval, the fitted
    model and its asymptotes (gyros in deg/h, accelerometers in ug)."""
    import matplotlib   # lazy: matplotlib only when a figure is asked for
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    lo, hi = ad.confidence()
    fig, axes = plt.subplots(1, 2, figsize=(12, 5))
    tau_f = np.geomspace(ad.tau_s[0], ad.tau_s[-1], 200)
    for ax, cols, scale, unit in ((axes[0], range(3), 1 / DEG_H, "deg/h"), (axes[1], range(3, 6), 1 / UG, "ug")):
        for c, color in zip(cols, ("C0", "C1", "C2")):
            ax.errorbar(ad.tau_s, ad.adev[:, c] * scale,
                        yerr=[(ad.adev[:, c] - lo[:, c]) * scale, (hi[:, c] - ad.adev[:, c]) * scale],
                        fmt=".", ms=3, color=color, lw=0.6, label=f"{_AXES[c]} ({terms[c].model})")
            ax.plot(tau_f, np.sqrt(terms[c].avar(tau_f)) * scale, color=color, lw=1.0)
            for name, line in terms[c].asymptotes(tau_f).items():
                ax.plot(tau_f, line * scale, color=color, lw=0.6, ls="--", alpha=0.6)
        ax.set_xscale("log")
        ax.set_yscale("log")
        data = ad.adev[:, list(cols)] * scale
        ax.set_ylim(np.min(data[data > 0]) / 5, np.max(data) * 3)
        ax.set_xlabel("tau, s")
        ax.set_ylabel(f"Allan deviation, {unit}")
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=8)
    axes[0].set_title("gyros: dots with 68% intervals, fit (solid), its terms (dashed)", fontsize=9)
    axes[1].set_title("accelerometers", fontsize=9)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
