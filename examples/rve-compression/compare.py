"""Periodic vs walled sigma_zz for ParticLS §5.3 (README.md, "Periodic version").

Runs the walled scene through the Python API, measuring every 100 steps the packing strain
(the wall's travel since it touched the packing), the layer strain (mean centres of the
bottom and top layers), the interior Love-Weber -szz (contacts with their midpoint in a window
of 16 x 18 lattice columns, 3 columns from the side walls) and the top and bottom walls'
force over 0.85^2, then prints them at the strains 0.05, 0.1, 0.2, 0.3 beside the periodic
run's -szz (its stress.csv, strain 1 - V/V0).

    floe run examples/rve-compression/periodic.yaml -o out/rve-compression-periodic
    FLOE_LIBRARY=build/libfloe.so PYTHONPATH=python python3 \\
        examples/rve-compression/compare.py [SCENE [PERIODIC_STRESS_CSV]]

The walled run takes as long as `floe run` of the scene (minutes).
"""
import math
import os
import sys

import numpy as np

import floe

D = 0.038
ROW = D * math.sqrt(3) / 2
AREA = 0.85 * 0.85
TOP0 = 0.9689061022576076  # top of the packing: the wall touches it here
MARGIN = 3                 # lattice columns between the window and the side walls


def walled(scene):
    w = floe.World.from_scene(scene, outputs=False)
    w.record_contacts(True)
    x0 = np.array(w.particles().x)
    n = int(np.isfinite(np.array(w.particles().radius)).sum())  # walls come after the spheres
    z = x0[:n, 2]
    bot, top = np.abs(z - z.min()) < 1e-6, np.abs(z - z.max()) < 1e-6
    kx, ky = 22 - 2 * MARGIN, 25 - 2 * MARGIN
    ky -= ky % 2
    wx0 = x0[:n, 0].min() + (MARGIN + 0.1234) * D
    wy0 = x0[:n, 1].min() + (MARGIN + 0.0987) * ROW
    wx1, wy1 = wx0 + kx * D, wy0 + ky * ROW
    inw = (x0[:n, 0] > wx0) & (x0[:n, 0] < wx1) & (x0[:n, 1] > wy0) & (x0[:n, 1] < wy1)
    h0 = z[top].mean() - z[bot].mean()
    hi0 = z[top & inw].mean() - z[bot & inw].mean()
    top_wall, bottom_wall = len(x0) - 1, len(x0) - 2
    rows = []
    for _ in range(int(round(w.info["duration"] / w.dt / 100))):
        w.step(100)
        x = np.array(w.particles().x)
        c = w.contacts()
        i, j, f = c["i"], c["j"], c["force"]
        ss = (i < n) & (j < n)
        l = x[j[ss]] - x[i[ss]]
        mid = x[i[ss]] + 0.5 * l
        m = (mid[:, 0] > wx0) & (mid[:, 0] < wx1) & (mid[:, 1] > wy0) & (mid[:, 1] < wy1)
        hi = x[:n][top & inw, 2].mean() - x[:n][bot & inw, 2].mean()
        h = x[:n][top, 2].mean() - x[:n][bot, 2].mean()
        szz = -(l[m, 2] * f[ss][m, 2]).sum() / ((wx1 - wx0) * (wy1 - wy0) * hi)
        ftop = np.abs(f[(i == top_wall) | (j == top_wall), 2]).sum()
        fbot = np.abs(f[(i == bottom_wall) | (j == bottom_wall), 2]).sum()
        rows.append((w.time, (TOP0 - x[top_wall, 2]) / TOP0, 1 - h / h0, 1 - hi / hi0, szz,
                     ftop / AREA, fbot / AREA))
    return np.array(rows)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    scene = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "scene.yaml")
    per = sys.argv[2] if len(sys.argv) > 2 else "out/rve-compression-periodic/stress.csv"
    s = np.loadtxt(per, delimiter=",", skiprows=1)
    ep, sp = 1 - s[:, 10] / s[0, 10], -s[:, 3]
    r = walled(scene)
    print("strain  periodic  top wall  bottom wall  interior   (walled at the layer strain; Pa)")
    for e in (0.05, 0.1, 0.2, 0.3):
        p = np.interp(e, ep, sp)
        t, b = np.interp(e, r[:, 2], r[:, 5]), np.interp(e, r[:, 2], r[:, 6])
        it = np.interp(e, r[:, 3], r[:, 4])
        print("%.2f  %8.1f  %8.1f (%+.0f %%)  %8.1f (%+.0f %%)  %8.1f (%+.0f %%)"
              % (e, p, t, 100 * (t / p - 1), b, 100 * (b / p - 1), it, 100 * (it / p - 1)))


if __name__ == "__main__":
    main()
