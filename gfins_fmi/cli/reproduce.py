"""``gfins reproduce``: the reproductions of published experiments
(:mod:`gfins_fmi.experiments`: ``qin``, seed 000's 6- vs 9-accelerometer comparison;
``seed001``, seed 001's vehicle test), with their tables and figures."""
from __future__ import annotations

from gfins_fmi.analysis.montecarlo import executor
from gfins_fmi.experiments import qin as R
from gfins_fmi.experiments import seed001 as S

__all__ = ["run"]


def run(args) -> int:
    args.out.mkdir(parents=True, exist_ok=True)
    if args.experiment == "seed001":
        runs = args.runs or 3
        print(f"Reproduction of seed 001's vehicle test: {runs} calibrations with and without K_a2 "
              "and lever arms, each driven (assumptions: gfins_fmi/reproduce_seed001.py, "
              "docs/reproductions/seed001_vehicle.md)")
        res = S.run_seed001(runs=runs, seed=args.seed, progress=True)
        table = S.seed001_table(res)
        print("\n" + table)
        png = S.seed001_plot(res, args.out / "seed001_vehicle.png")
        (args.out / "seed001_table.md").write_text(table + "\n", encoding="utf-8")
        print(f"\nfigure: {png}\ntable: {args.out / 'seed001_table.md'}")
        return 0
    args.runs = args.runs or 100
    print("Reproduction of Qin, Xu, Li (seed 000), section 2: Monte Carlo of "
          f"{args.runs} runs (assumptions: gfins_fmi/reproduce.py, docs/reproductions/qin.md)")
    with executor(args.scheduler, args.workers) as ex:
        res = R.run_qin(runs=args.runs, seed=args.seed, progress=True,
                        drift_signs=args.drift_signs,
                        scenario=R.QinScenario(gravity_m_s2=args.gravity), executor=ex)
    table = R.qin_table(res)
    print("\nErrors at t = 60 s\n" + table)
    mech = R.mechanization_table(R.mechanization_error(R.QinScenario(gravity_m_s2=args.gravity)))
    print("\nthe navigator's own part (exact outputs, no noise or drift), at 60 s:\n" + mech)
    imp = R.improvement(res)
    print(f"\nimprovement of 9 over 6 (median |error|): attitude "
          + ", ".join(f"{100 * v:.2f}%" for v in imp["att"]) + "; position "
          + ", ".join(f"{100 * v:.2f}%" for v in imp["pos"]))
    rates = R.rate_strategy_table(progress=False)
    print("\nangular-rate RMS error of the 9-accelerometer strategies (rad/s, median of 20 runs):")
    for case, row in rates.items():
        print(f"  {case:40s} " + "  ".join(f"{k} {v:.3g}" for k, v in row.items()))
    png = R.qin_plot(res, args.out / "qin_errors.png")
    (args.out / "qin_table.md").write_text(table + "\n\n" + mech + "\n", encoding="utf-8")
    print(f"\nfigure: {png}\ntable: {args.out / 'qin_table.md'}")
    return 0
