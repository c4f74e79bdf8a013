"""The rotating pendulum of Kim & Yoo (2007), Figs. 2-4, from Python.

A uniform rod (L = 1 m ± 3, 6, 12 %) hangs from a shaft spinning at Ω; hinge damping makes
its mode overdamped for 3.530 < Ω < 3.984 rad/s, and it swings out at Ω = 3.835 rad/s.

* Fig. 2: mean of the damped natural frequency ω_d against Ω, analytic and Monte Carlo.
* Fig. 3: σ of ω_d for the 3 % case: the exact answer (modaltol's quadrature, method
  ``analytic``), the paper's first-order method and Monte Carlo.
* Fig. 4: σ of ω_d for the three cases, first order and Monte Carlo.

Run from the repository root (a few seconds; with ``--samples 3000`` as in the paper, about a
minute on 2 cores)::

    python python/examples/paper_figures.py --out figures

It writes ``fig2.png``, ``fig3.png``, ``fig4.png`` and the table they are drawn from
(``tolerance.csv``) into ``--out``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt  # noqa: E402

import modaltol  # noqa: E402

HERE = Path(__file__).resolve().parent
MODEL = HERE.parent.parent / "examples" / "rotating_pendulum.toml"
COLOURS = {"L3": "tab:blue", "L6": "tab:orange", "L12": "tab:green"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("figures"), help="output directory")
    ap.add_argument("--samples", type=int, default=1000, help="Monte Carlo samples")
    ap.add_argument("--speeds", default="0:6:0.02", help="FROM:TO:STEP in rad/s")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    model = modaltol.load(MODEL)
    res = model.analyze(args.speeds, samples=args.samples, seed=1)
    t = res.tolerance
    t.to_csv(args.out / "tolerance.csv", index=False)
    wd = t[(t["quantity"] == "damped_frequency") & (t["mode"] == 1)]

    def rows(case: str, method: str):
        r = wd[(wd["case"] == case) & (wd["method"] == method)]
        return r["speed"], r

    # Fig. 2: mean of ω_d.
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for case, colour in COLOURS.items():
        s, r = rows(case, "analytic")
        ax.plot(s, r["mean"], color=colour, label=f"{case}: analytic")
        s, r = rows(case, "monte_carlo")
        ax.plot(s, r["mean"], ".", color=colour, ms=3, label=f"{case}: Monte Carlo")
    ax.set(xlabel="spin speed Ω (rad/s)", ylabel="mean of ω_d (rad/s)",
           title="Fig. 2: mean damped natural frequency")
    ax.set_ylim(0, 1.35 * ax.get_ylim()[1])  # room for the legend above the curves
    ax.legend(fontsize=8, loc="upper center", ncol=3)
    fig.tight_layout()
    fig.savefig(args.out / "fig2.png", dpi=120)

    # Fig. 3: σ of ω_d, 3 % on L, three methods.
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for method, style, label in [
        ("analytic", "-", "exact (quadrature)"),
        ("first_order", "--", "first order (the paper's method)"),
        ("monte_carlo", ".", f"Monte Carlo ({args.samples} samples)"),
    ]:
        s, r = rows("L3", method)
        ax.plot(s, r["std"], style, ms=3, label=label)
    ax.set(xlabel="spin speed Ω (rad/s)", ylabel="σ of ω_d (rad/s)",
           title="Fig. 3: σ of ω_d, L ± 3 %")
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(args.out / "fig3.png", dpi=120)

    # Fig. 4: σ of ω_d for 3, 6, 12 %.
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for case, colour in COLOURS.items():
        s, r = rows(case, "first_order")
        ax.plot(s, r["std"], color=colour, label=f"{case}: first order")
        s, r = rows(case, "monte_carlo")
        ax.plot(s, r["std"], ".", color=colour, ms=3, label=f"{case}: Monte Carlo")
    ax.set(xlabel="spin speed Ω (rad/s)", ylabel="σ of ω_d (rad/s)",
           title="Fig. 4: σ of ω_d for 3, 6 and 12 % on L")
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(args.out / "fig4.png", dpi=120)
    print(f"wrote {args.out}/fig2.png, fig3.png, fig4.png and tolerance.csv")


if __name__ == "__main__":
    main()
