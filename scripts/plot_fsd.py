#!/usr/bin/env python3
"""plot_fsd.py - a PNG of the floe size distribution from the floe_sizes output
(observers/floe_sizes.c, docs/sea-ice.md "Outputs"): for each chosen frame, the number of
floes of diameter at least D, N(>=D), against D = 2 sqrt(area / pi), on log-log axes (the
complementary cumulative distribution of sea-ice studies, Rothrock & Thorndike 1984; a
power law N(>D) ~ D^-alpha is a straight line of slope -alpha).

usage: plot_fsd.py FLOE_SIZES.csv [-o fsd.png] [--times T ...] [--fit] [--title TEXT]

  --times T ...  the frames nearest to these times (s); default: the first and the last
  --fit          per frame, the maximum-likelihood exponent alpha of a power law
                 truncated to the frame's smallest and largest diameters (a truncated
                 Pareto law, Aban, Meerschaert & Panorska 2006), drawn dashed (its
                 N(>=D) = n (D^-a - U^-a) / (L^-a - U^-a)) and given in the legend
  -o PATH        the PNG (default fsd.png)

Needs matplotlib (Debian: python3-matplotlib, installed by scripts/install-deps.sh).
Exit status 0; 1 with a message for a missing or malformed file, no frames, or no
matplotlib."""
import argparse
import csv
import math
import sys


def read_frames(path):
    """{t: [areas]} from a floe_sizes CSV (columns t [s], floe, particles, area [m^2], ...)"""
    frames = {}
    with open(path, newline="") as f:
        rows = csv.reader(f)
        head = next(rows, None)
        if not head or len(head) < 4 or not head[0].startswith("t") or not head[3].startswith("area"):
            raise ValueError("%s: not a floe_sizes CSV (header %r)" % (path, head))
        for k, r in enumerate(rows, start=2):
            if not r:
                continue
            try:
                t, a = float(r[0]), float(r[3])
            except (IndexError, ValueError):
                raise ValueError("%s:%d: malformed row %r" % (path, k, r))
            if not (a >= 0 and math.isfinite(a) and math.isfinite(t)):
                raise ValueError("%s:%d: area %r at t = %r" % (path, k, r[3], r[0]))
            frames.setdefault(t, []).append(a)
    if not frames:
        raise ValueError("%s: no rows" % path)
    return frames


def choose(times, wanted):
    """the frames' times nearest to each wanted time (first and last by default), in order"""
    ts = sorted(times)
    if not wanted:
        return sorted({ts[0], ts[-1]})
    return sorted({min(ts, key=lambda t: abs(t - w)) for w in wanted})


def ccdf(areas):
    """diameters in decreasing order and N(>=D) = 1, 2, ... n"""
    d = sorted((2 * math.sqrt(a / math.pi) for a in areas if a > 0), reverse=True)
    return d, list(range(1, len(d) + 1))


def fit_alpha(d):
    """the maximum-likelihood exponent of a Pareto law truncated to [L, U] = [min d, max d]:
    the root of 1/a + r^a ln r / (1 - r^a) = mean ln(D / L), r = L / U, by bisection (the left
    side falls with a); None for fewer than 3 floes or a single diameter"""
    lo, hi = min(d), max(d)
    if len(d) < 3 or not hi > lo:
        return None
    r, lr = lo / hi, math.log(lo / hi)
    s = sum(math.log(x / lo) for x in d) / len(d)
    a0, a1 = 1e-3, 20.0
    for _ in range(200):
        am = 0.5 * (a0 + a1)
        ra = r ** am
        if 1 / am + ra * lr / (1 - ra) > s:
            a0 = am
        else:
            a1 = am
    return 0.5 * (a0 + a1)


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("csv")
    ap.add_argument("-o", "--output", default="fsd.png")
    ap.add_argument("--times", type=float, nargs="+")
    ap.add_argument("--fit", action="store_true")
    ap.add_argument("--title", default="floe size distribution")
    a = ap.parse_args(argv)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("plot_fsd: needs matplotlib (Debian: apt install python3-matplotlib, or scripts/install-deps.sh)",
              file=sys.stderr)
        return 1
    try:
        frames = read_frames(a.csv)
    except (OSError, ValueError) as e:
        print("plot_fsd: %s" % e, file=sys.stderr)
        return 1
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    for t in choose(frames, a.times):
        d, n = ccdf(frames[t])
        if not d:
            continue
        line, = ax.step(d, n, where="post", label="t = %g s, %d floes" % (t, len(d)))
        alpha = fit_alpha(d) if a.fit else None
        if alpha:
            lo, hi = min(d), max(d)
            xs = [lo * (hi / lo) ** (k / 50) for k in range(50)]
            ys = [len(d) * (x ** -alpha - hi ** -alpha) / (lo ** -alpha - hi ** -alpha) for x in xs]
            ax.plot(xs, ys, "--", color=line.get_color(), label="  fit: alpha = %.2f" % alpha)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("floe diameter D = 2 sqrt(A / pi) [m]")
    ax.set_ylabel("number of floes N(>= D)")
    ax.set_title(a.title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small")
    fig.tight_layout()
    try:
        fig.savefig(a.output, dpi=100)
    except OSError as e:
        print("plot_fsd: cannot write %s: %s" % (a.output, e), file=sys.stderr)
        return 1
    print("plot_fsd: wrote %s" % a.output)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
