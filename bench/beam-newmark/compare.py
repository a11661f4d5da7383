#!/usr/bin/env python3
"""Compare two crack patterns written by bench_beam_newmark (bonds_*.csv): broken bonds of
both runs at the same times, their overlap bond by bond and on a 5 cm grid (Jaccard
index: common / either), where they are, and an ASCII map of both (' ' none, '.' 1-2,
'o' 3-7, '#' 8 or more broken bonds per 5 cm cell; the beam is 3 m x 0.5 m).
    compare.py A.csv B.csv [t1 t2 ...]"""
import csv
import sys

CELL = 0.05


def load(path):
    rows = []
    with open(path) as f:
        for r in csv.DictReader(f):
            rows.append((float(r["x [m]"]), float(r["y [m]"]), int(r["broken"]), float(r["t_broken [s]"])))
    return rows


def cells(rows, s):
    c = {}
    for k in s:
        key = (int(rows[k][0] / CELL + 1e-9), int(rows[k][1] / CELL + 1e-9))
        c[key] = c.get(key, 0) + 1
    return c


def ascii_map(c):
    nx, ny = int(3.0 / CELL) + 1, int(0.5 / CELL)
    out = []
    for j in reversed(range(ny)):
        line = ""
        for i in range(nx):
            n = c.get((i, j), 0)
            line += " " if n == 0 else "." if n < 3 else "o" if n < 8 else "#"
        out.append("|" + line + "|")
    return out


def jac(a, b):
    u = a | b
    return len(a & b) / len(u) if u else 1.0


def main():
    a, b = load(sys.argv[1]), load(sys.argv[2])
    if len(a) != len(b):
        sys.exit("the two runs have different bonds")
    times = [float(t) for t in sys.argv[3:]] or [0.005, 0.01, 0.025, 0.5]
    for t in times:
        sa = {k for k, r in enumerate(a) if r[2] and r[3] <= t}
        sb = {k for k, r in enumerate(b) if r[2] and r[3] <= t}
        ca, cb = cells(a, sa), cells(b, sb)
        def where(s, rows):
            if not s:
                return "none"
            xs = sorted(rows[k][0] for k in s)
            return "x %.3f..%.3f, median %.3f" % (xs[0], xs[-1], xs[len(xs) // 2])
        print("t = %-6g A %4d broken (%s) | B %4d broken (%s) | bonds: common %d, Jaccard %.3f | 5 cm cells: "
              "%d / %d, Jaccard %.3f" % (t, len(sa), where(sa, a), len(sb), where(sb, b), len(sa & sb), jac(sa, sb),
                                         len(ca), len(cb), jac(set(ca), set(cb))))
    fa = sorted((r[3], k) for k, r in enumerate(a) if r[2])[:10]
    fb = sorted((r[3], k) for k, r in enumerate(b) if r[2])[:10]
    print("first 10 broken: A x = %s" % " ".join("%.3f" % a[k][0] for _, k in fa))
    print("                 B x = %s" % " ".join("%.3f" % b[k][0] for _, k in fb))
    print("common among the first 10: %d" % len({k for _, k in fa} & {k for _, k in fb}))
    t = times[-1]
    for name, rows in (("A " + sys.argv[1], a), ("B " + sys.argv[2], b)):
        print("%s at t = %g s:" % (name, t))
        print("\n".join(ascii_map(cells(rows, {k for k, r in enumerate(rows) if r[2] and r[3] <= t}))))


if __name__ == "__main__":
    main()
