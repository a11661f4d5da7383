#!/usr/bin/python3
"""plot.py CSV PNG - error (relative to the radius) against CPU time, one curve per
integrator, one panel per scene; prints the markdown table."""
import sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

rows = [l.strip().split(",") for l in open(sys.argv[1]) if l.startswith("csv,")]
scenes = {"dem_chain": "DEM: 25 Hertz chains (325 spheres, e 0.8, friction)", "pd_bar": "PD: PMB bar pulse (480 points)"}
marks = {"velocity_verlet": "o-", "leapfrog": "x--", "rk2": "s-", "adaptive_verlet": "D", "adaptive_rk2": "^"}
fig, axes = plt.subplots(1, 2, figsize=(12, 5))
print("| scene | integrator | dt / critical | steps | CPU [ms] | max position error / R |")
print("| --- | --- | --- | --- | --- | --- |")
for ax, (sc, title) in zip(axes, scenes.items()):
    for name, style in marks.items():
        pts = [r for r in rows if r[1] == sc and r[2] == name]
        if not pts:
            continue
        xs = [1e3 * float(r[5]) for r in pts]
        ys = [float(r[6]) for r in pts]
        ax.loglog(xs, ys, style, label=name.replace("_", " "), ms=6)
        for r in pts:
            print("| %s | %s | %s | %s | %.2f | %.2e |" % (sc, name, "adaptive" if name.startswith("adaptive") else r[3],
                  r[4], 1e3 * float(r[5]), float(r[6])))
    ax.set_xlabel("CPU time [ms]")
    ax.set_ylabel("max position error / radius (vs 0.001 x critical)")
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
fig.suptitle("floe integrators: accuracy against cost (dt factors 0.025 ... 1 of the critical estimate)")
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
print("wrote", sys.argv[2], file=sys.stderr)
