#!/usr/bin/env python3
"""Compare two crack patterns written by bench_beam_newmark (bonds_*.csv): broken bonds of
both runs at the same times, their overlap (Jaccard index) and where they are.
    compare.py A.csv B.csv [t1 t2 ...]"""
import csv
import sys


def load(path):
    rows = []
    with open(path) as f:
        for r in csv.DictReader(f):
            rows.append((float(r["x [m]"]), float(r["y [m]"]), int(r["broken"]), float(r["t_broken [s]"])))
    return rows


def main():
    a, b = load(sys.argv[1]), load(sys.argv[2])
    if len(a) != len(b):
        sys.exit("the two runs have different bonds")
    times = [float(t) for t in sys.argv[3:]] or [0.005, 0.01, 0.025, 0.5]
    for t in times:
        sa = {k for k, r in enumerate(a) if r[2] and r[3] <= t}
        sb = {k for k, r in enumerate(b) if r[2] and r[3] <= t}
        u = sa | sb
        def where(s, rows):
            if not s:
                return "none"
            xs = sorted(rows[k][0] for k in s)
            return "x %.3f..%.3f, median %.3f" % (xs[0], xs[-1], xs[len(xs) // 2])
        print("t = %-6g A %4d broken (%s) | B %4d broken (%s) | common %4d, Jaccard %.3f"
              % (t, len(sa), where(sa, a), len(sb), where(sb, b), len(sa & sb), len(sa & sb) / len(u) if u else 1.0))
    fa = sorted((r[3], k) for k, r in enumerate(a) if r[2])[:10]
    fb = sorted((r[3], k) for k, r in enumerate(b) if r[2])[:10]
    print("first 10 broken: A x = %s" % " ".join("%.3f" % a[k][0] for _, k in fa))
    print("                 B x = %s" % " ".join("%.3f" % b[k][0] for _, k in fb))
    print("common among the first 10: %d" % len({k for _, k in fa} & {k for _, k in fb}))


if __name__ == "__main__":
    main()
