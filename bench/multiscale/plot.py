#!/usr/bin/python3
"""plot.py OUTDIR PNG - wall force against the displacement of the spheres for the schemes
of bench/multiscale/run.sh (000 Fig. 8)."""
import csv, os, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

out, png = sys.argv[1], sys.argv[2]
runs = [("monolithic.csv", "monolithic, dt 5e-5 s", "k-"),
        ("staggered_m1.csv", "staggered, equal steps 5e-5 s", "C0--"),
        ("staggered_m2.csv", "staggered MS m = 2 (DEM 1e-4, PD 5e-5 s)", "C1-"),
        ("staggered_m3.csv", "staggered MS m = 3 (DEM 1.5e-4, PD 5e-5 s)", "C2-"),
        ("staggered_dem1e-4_pd2e-5.csv", "staggered MS m = 5 (DEM 1e-4, PD 2e-5 s)", "C3:"),
        ("staggered_m4.csv", "staggered MS m = 4 (DEM 2e-4 s): unstable", "C4-")]
fig, ax = plt.subplots(figsize=(8, 5))
for name, label, style in runs:
    path = os.path.join(out, name)
    if not os.path.exists(path):
        continue
    u, f = [], []
    with open(path) as fh:
        r = csv.reader(fh)
        next(r)
        for row in r:
            u.append(1e3 * float(row[1]))
            f.append(1e-3 * float(row[2]))
    ax.plot(u, f, style, label=label, lw=1)
ax.set_xlabel("displacement of the spheres u [mm]")
ax.set_ylabel("normal force on the wall [kN]")
ax.set_title("000 §4.2: PD body (2,000 points) under 81 DEM spheres, floe")
ax.set_ylim(bottom=0)
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(png, dpi=110)
print("wrote", png)
