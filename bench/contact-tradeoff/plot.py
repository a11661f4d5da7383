#!/usr/bin/python3
"""plot.py OUTPUT [PNG] - time per pair against depth error (p90, log-log), one curve per
method, from the csv lines of bench_contact_tradeoff (run.sh). Left: random polytopes,
error against the exact deepest-point depth (what floe computes; libccd computes the
minimum translation distance, a different quantity). Right: axis-aligned boxes, error
against the exact minimum translation distance (what libccd computes)."""
import sys, os
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

src = sys.argv[1]
png = sys.argv[2] if len(sys.argv) > 2 else os.path.join(os.path.dirname(__file__), "..", "..", "docs", "contact-tradeoff.png")
rows = {"P": {}, "B": {}}
for line in open(src):
    if not line.startswith("csv,"):
        continue
    f = line.strip().split(",")
    s, name, tol, us, p90 = f[1], f[2], f[3], float(f[4]), float(f[6])
    rows[s].setdefault(name, []).append((tol, us, max(p90, 1e-17)))
fig, ax = plt.subplots(1, 2, figsize=(12, 5))
titles = {"P": "random polytopes (20-40 vertices): error vs deepest-point depth",
          "B": "axis-aligned boxes: error vs minimum translation distance"}
marks = {"ADMM cold": "o-", "ADMM warm": "s-", "LP cold": "^", "LP warm": "v", "libccd MPR": "D--", "libccd GJK+EPA": "x--"}
for a, s in zip(ax, ["P", "B"]):
    for name, pts in rows[s].items():
        xs = [p[2] for p in pts]
        ys = [p[1] for p in pts]
        a.plot(xs, ys, marks.get(name, "o-"), label=name, ms=6)
        if name.startswith("ADMM"):
            for tol, y, x in pts:
                a.annotate(tol, (x, y), textcoords="offset points", xytext=(4, 2), fontsize=7)
    a.set_xscale("log")
    a.set_yscale("log")
    a.set_xlabel("depth error, 90th percentile (1e-17 = exact)")
    a.set_ylabel("time per pair (us, median of repetitions)")
    a.set_title(titles[s], fontsize=10)
    a.grid(True, which="both", alpha=0.3)
    a.legend(fontsize=8)
fig.suptitle("floe contact detection: accuracy vs time (2 vCPU VM, one thread)", fontsize=11)
fig.tight_layout()
fig.savefig(png, dpi=110)
print("wrote", png)
