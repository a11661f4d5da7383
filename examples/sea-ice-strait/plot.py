#!/usr/bin/env python3
"""plot.py - the figures of examples/sea-ice-strait/README.md (jam scene), as SVG, from two
runs' outputs: the cumulative floes through the constriction (gate.csv) against time, with
and without friction, and the floe outlines (floes_NNNNNN.vtu) at one time side by side.

usage: python3 plot.py WITH_DIR WITHOUT_DIR HOUR OUT_PREFIX
       e.g. python3 examples/sea-ice-strait/plot.py out/jam out/jam-0 72 examples/sea-ice-strait/jam
writes OUT_PREFIX-flux.svg and OUT_PREFIX-floes.svg. Python 3 standard library only.
"""
import csv
import glob
import os
import re
import struct
import sys


def read_gate(d):
    """(hours, cumulative floes) rows of DIR/gate.csv."""
    rows = list(csv.reader(open(os.path.join(d, "gate.csv"))))[1:]
    return [(float(r[0]) / 3600, int(float(r[1]))) for r in rows]


def read_outlines(path):
    """Polygons [(body, [(x, y), ...]), ...] of one outlines .vtu (raw appended data)."""
    data = open(path, "rb").read()
    cut = data.index(b"<AppendedData")
    head = data[:cut].decode("latin-1")
    raw = data[data.index(b"_", cut) + 1:]
    fmt = {"Float64": ("d", 8), "Int32": ("i", 4), "Int64": ("q", 8), "UInt8": ("B", 1)}
    arrays = {}
    for m in re.finditer(r'<DataArray([^>]*?)/>', head):
        attrs = dict(re.findall(r'(\w+)="([^"]*)"', m.group(1)))
        if attrs.get("format") != "appended":
            continue
        off = int(attrs["offset"])
        nbytes = struct.unpack("<Q", raw[off:off + 8])[0]
        code, size = fmt[attrs["type"]]
        nc = int(attrs.get("NumberOfComponents", "1"))
        vals = struct.unpack("<" + code * (nbytes // size), raw[off + 8:off + 8 + nbytes])
        arrays[attrs["Name"]] = [vals[i:i + nc] for i in range(0, len(vals), nc)] if nc > 1 else list(vals)
    pts, conn, offs, body = arrays["Points"], arrays["connectivity"], arrays["offsets"], arrays["body"]
    polys, start = [], 0
    for c, end in enumerate(offs):
        polys.append((body[c], [(pts[k][0], pts[k][1]) for k in conn[start:end]]))
        start = end
    return polys


def frame_at(d, hour):
    """The outlines frame of DIR whose time is nearest HOUR (frames every hour from 0)."""
    frames = sorted(glob.glob(os.path.join(d, "floes_*.vtu")))
    return frames[min(len(frames) - 1, int(round(hour)))]


def flux_svg(runs, path):
    """Cumulative floes through the gate against time, one polyline per (label, colour, rows)."""
    W, H, L, B = 640, 360, 60, 40
    tmax = max(r[-1][0] for _, _, r in runs)
    nmax = max(5, max(n for _, _, r in runs for _, n in r))
    nmax = 5 * ((nmax + 4) // 5)
    sx = lambda t: L + (W - L - 20) * t / tmax
    sy = lambda n: H - B - (H - B - 20) * n / nmax
    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="sans-serif" '
           'font-size="12">' % (W, H), '<rect width="100%" height="100%" fill="white"/>']
    for t in range(0, int(tmax) + 1, 12):
        out.append('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="#ddd"/>' % (sx(t), 20, sx(t), H - B))
        out.append('<text x="%.1f" y="%d" text-anchor="middle">%d</text>' % (sx(t), H - B + 16, t))
    for n in range(0, nmax + 1, max(1, nmax // 5)):
        out.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#ddd"/>' % (L, sy(n), W - 20, sy(n)))
        out.append('<text x="%d" y="%.1f" text-anchor="end">%d</text>' % (L - 6, sy(n) + 4, n))
    out.append('<text x="%d" y="%d" text-anchor="middle">time (h)</text>' % ((W + L) // 2, H - 6))
    out.append('<text x="14" y="%d" text-anchor="middle" transform="rotate(-90 14 %d)">floes through '
               'the constriction</text>' % ((H - B) // 2, (H - B) // 2))
    for i, (label, colour, rows) in enumerate(runs):
        pts = " ".join("%.1f,%.1f" % (sx(t), sy(n)) for t, n in rows)
        out.append('<polyline points="%s" fill="none" stroke="%s" stroke-width="2"/>' % (pts, colour))
        out.append('<text x="%d" y="%d" fill="%s">%s</text>' % (L + 10, 36 + 16 * i, colour, label))
    out.append("</svg>")
    open(path, "w").write("\n".join(out) + "\n")


def floes_svg(panels, path, box=(-5000, 0, 65000, 125000), scale=0.004):
    """Floe outlines of each (title, polygons) panel side by side; coasts (body 0) grey."""
    x0, y0, x1, y1 = box
    pw, ph = (x1 - x0) * scale, (y1 - y0) * scale
    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%.0f" height="%.0f" font-family="sans-serif" '
           'font-size="12">' % (len(panels) * (pw + 20), ph + 30), '<rect width="100%" height="100%" fill="white"/>']
    for i, (title, polys) in enumerate(panels):
        ox = i * (pw + 20) + 10
        out.append('<text x="%.1f" y="16" text-anchor="middle">%s</text>' % (ox + pw / 2, title))
        for body, ring in polys:
            pts = " ".join("%.1f,%.1f" % (ox + (x - x0) * scale, 24 + (y1 - y) * scale) for x, y in ring
                           if x0 - 2e4 < x < x1 + 2e4 and y0 - 2e4 < y < y1 + 2e4)
            if not pts:
                continue
            fill, stroke = ("#bbb", "#bbb") if body == 0 else ("#cfe3f5", "#2a5d8a")
            out.append('<polygon points="%s" fill="%s" stroke="%s" stroke-width="0.6"/>' % (pts, fill, stroke))
        out.append('<rect x="%.1f" y="24" width="%.1f" height="%.1f" fill="none" stroke="black"/>' % (ox, pw, ph))
    out.append("</svg>")
    open(path, "w").write("\n".join(out) + "\n")


def main():
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    with_dir, without_dir, hour, prefix = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4]
    flux_svg([("with friction (mu = 0.7)", "#c0392b", read_gate(with_dir)),
              ("without friction (mu = 0)", "#2471a3", read_gate(without_dir))], prefix + "-flux.svg")
    floes_svg([("mu = 0.7, t = %g h" % hour, read_outlines(frame_at(with_dir, hour))),
               ("mu = 0, t = %g h" % hour, read_outlines(frame_at(without_dir, hour)))], prefix + "-floes.svg")
    print("wrote %s-flux.svg and %s-floes.svg" % (prefix, prefix))


if __name__ == "__main__":
    main()
