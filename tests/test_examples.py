#!/usr/bin/env python3
"""test_examples.py - the example scenes stay valid and the small one reproduces its figure.

usage: python3 tests/test_examples.py <floe_cli_path> <tests_dir>

- `floe check` accepts every examples/*/scene.yaml (the RVE builds its 16,483 spheres).
- examples/dilating-sphere (ParticLS §5.2, Fig. 6) runs to t = 3 s: the middle sphere's six
  neighbours are pushed outward (each ends farther than R(t=3) = 3.1 m from the centre
  particle's position, while starting in contact at 0.2 m), the energy ledger closes
  (balance_error < 1e-3), and the cluster stays in the plane (z = 0).
- examples/polygons-2d and polyhedra-3d (ParticLS §5.1, Figs 4-5), copied with a shorter
  duration (the CLI has no duration override): the red particle hits the others (it slows
  down and they move), total linear momentum is conserved to 1e-9 of the initial one (no
  walls, no gravity; masses from the polygons' areas and prism heights read from the scene),
  the mechanical energy (kinetic + elastic) never rises above the initial energy (damped
  contacts only dissipate), states stay finite; 2D: the motion stays in the plane and the
  energy ledger closes (balance_error < 1e-3).
- examples/mesh-grains (needs floe built with assimp and CGAL; skipped with a note when
  `floe check` says the build lacks them), copied with a shorter duration: every grain stays
  inside the walled box and below its start height, no NaN, and the kinetic energy at the
  end is below its peak (the grains have landed and lose energy).
Prints "N passed, N failed".
"""
import csv
import glob
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

from pycheck import check, finish


def copy_example(root, tmp, name, duration):
    """Copy examples/NAME (scene and data files) into tmp/NAME with time.duration replaced."""
    src = os.path.join(root, "examples", name)
    dst = os.path.join(tmp, name)
    shutil.copytree(src, dst)
    path = os.path.join(dst, "scene.yaml")
    text = open(path).read()
    text, n = re.subn(r"(\btime: \{duration: )[0-9.eE+-]+", r"\g<1>%g" % duration, text)
    check(n == 1, "%s: time: {duration: ...} found once to shorten the run" % name)
    open(path, "w").write(text)
    return path


def run_example(cli, scene, out, name):
    p = subprocess.run([cli, "run", scene, "-o", out, "-q"], stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, universal_newlines=True, timeout=600)
    check(p.returncode == 0, "%s run: exit %d\n%s" % (name, p.returncode, p.stderr))
    return p.returncode == 0


def polygon_area(pts):
    a = 0.0
    for (x0, y0), (x1, y1) in zip(pts, pts[1:] + pts[:1]):
        a += x0 * y1 - x1 * y0
    return abs(a) / 2


def finite_rows(rows):
    return all(math.isfinite(float(v)) for r in rows for k, v in r.items() if k not in ("id", "body", "material"))


def check_polygons(cli, root, tmp, name, dim, duration):
    """ParticLS Figs 4-5: momentum conservation, no energy gain, the red particle hits."""
    scene = copy_example(root, tmp, name, duration)
    out = os.path.join(tmp, name + "-out")
    if not run_example(cli, scene, out, name):
        return
    # masses: density 1 (the scene's only material) x polygon area (x prism height in 3D)
    text = open(scene).read()
    check(re.search(r"\{name: poly, density: 1\}", text) is not None, "%s: density 1" % name)
    shapes = re.findall(r"(?:polygon|prism): \{(?:height: ([0-9.]+), )?vertices: (\[\[.*?\]\])\}", text)
    masses = [polygon_area(json.loads(v)) * (float(h) if h else 1.0) for h, v in shapes]
    check(len(masses) == 8, "%s: 8 polygon bodies read from the scene (%d)" % (name, len(masses)))
    rows = list(csv.DictReader(open(os.path.join(out, "particles.csv"))))
    check(len(rows) > 0 and finite_rows(rows), "%s: particles.csv rows finite" % name)
    frames = {}
    for r in rows:
        frames.setdefault(float(r["t [s]"]), {})[int(r["id"])] = r
    times = sorted(frames)
    check(times[-1] > 0.99 * duration, "%s: ran to t = %.3f s" % (name, times[-1]))
    P0 = None
    worst = 0.0
    for t in times:
        f = frames[t]
        P = [sum(masses[i] * float(f[i][c]) for i in range(len(masses))) for c in ("vx [m/s]", "vy [m/s]", "vz [m/s]")]
        if P0 is None:
            P0 = P
        worst = max(worst, math.sqrt(sum((P[c] - P0[c]) ** 2 for c in range(3))) / math.sqrt(sum(x * x for x in P0)))
    check(worst < 1e-9, "%s: linear momentum conserved to %.2e < 1e-9 (relative)" % (name, worst))
    red0, red1 = frames[times[0]][0], frames[times[-1]][0]
    sp0 = math.hypot(float(red0["vx [m/s]"]), float(red0["vy [m/s]"]))
    sp1 = math.hypot(float(red1["vx [m/s]"]), float(red1["vy [m/s]"]))
    check(sp1 < 0.9 * sp0, "%s: the red particle is slowed by the impact (%.3f -> %.3f m/s)" % (name, sp0, sp1))
    moved = sum(1 for i in range(1, 8) if abs(float(frames[times[-1]][i]["vx [m/s]"])) + abs(float(frames[times[-1]][i]["vy [m/s]"])) > 1e-3)
    check(moved >= 1, "%s: the red particle sets others in motion (%d moving)" % (name, moved))
    if dim == 2:
        check(all(float(r["z [m]"]) == 0.0 and float(r["vz [m/s]"]) == 0.0 for r in rows),
              "%s: the motion stays in the plane" % name)
    erows = list(csv.DictReader(open(os.path.join(out, "energy.csv"))))
    e0 = float(erows[0]["initial [J]"])
    emax = max(float(r["kinetic_trans [J]"]) + float(r["kinetic_rot [J]"]) + float(r["elastic [J]"]) for r in erows)
    check(emax <= e0 * (1 + 1e-6), "%s: mechanical energy never above the initial %.6e J (max %.6e J)" % (name, e0, emax))
    elast = float(erows[-1]["kinetic_trans [J]"]) + float(erows[-1]["kinetic_rot [J]"]) + float(erows[-1]["elastic [J]"])
    check(elast < 0.99 * e0, "%s: the damped impacts dissipate energy (%.3e of %.3e J left)" % (name, elast, e0))
    err = float(erows[-1]["balance_error"])
    if dim == 2:
        check(abs(err) < 1e-3, "%s: energy balance error %.2e < 1e-3" % (name, err))
    print("  %s: t = %.3f s, momentum drift %.1e, energy left %.3f, balance error %.2e"
          % (name, times[-1], worst, elast / e0, err))


def check_mesh_grains(cli, root, tmp, duration):
    """Mesh grains poured into a box: inside the walls, below the start, no NaN, KE decays."""
    scene = copy_example(root, tmp, "mesh-grains", duration)
    out = os.path.join(tmp, "mesh-grains-out")
    if not run_example(cli, scene, out, "mesh-grains"):
        return
    rows = [r for r in csv.DictReader(open(os.path.join(out, "particles.csv"))) if int(r["body"]) >= 0]  # no walls
    check(len(rows) > 0 and finite_rows(rows), "mesh-grains: particles.csv rows finite")
    frames = {}
    for r in rows:
        frames.setdefault(float(r["t [s]"]), {})[int(r["id"])] = r
    times = sorted(frames)
    first, last = frames[times[0]], frames[times[-1]]
    check(times[-1] > 0.99 * duration, "mesh-grains: ran to t = %.3f s" % times[-1])
    check(len(last) == 201, "mesh-grains: 200 grains and the L block (%d)" % len(last))
    box = 0.15
    inside = all(-1e-3 < float(r["x [m]"]) < box + 1e-3 and -1e-3 < float(r["y [m]"]) < box + 1e-3
                 and float(r["z [m]"]) > -1e-3 for r in last.values())
    check(inside, "mesh-grains: every centre inside the walled box")
    below = sum(1 for i, r in last.items() if float(r["z [m]"]) < float(first[i]["z [m]"]))
    check(below == len(last), "mesh-grains: every body below its start height (%d of %d)" % (below, len(last)))
    erows = list(csv.DictReader(open(os.path.join(out, "energy.csv"))))
    check(all(math.isfinite(float(v)) for r in erows for v in r.values()), "mesh-grains: energies finite")
    ke = [float(r["kinetic_trans [J]"]) + float(r["kinetic_rot [J]"]) for r in erows]
    kmax = max(ke)
    check(ke[-1] < 0.8 * kmax, "mesh-grains: kinetic energy decays after the impacts (%.3e of peak %.3e J)"
          % (ke[-1], kmax))
    print("  mesh-grains: t = %.3f s, KE end/peak %.2f" % (times[-1], ke[-1] / kmax))


def main():
    cli, tests = sys.argv[1], sys.argv[2]
    root = os.path.dirname(os.path.abspath(tests))
    scenes = sorted(glob.glob(os.path.join(root, "examples", "*", "scene.yaml")))
    check(len(scenes) >= 2, "example scenes found: %d" % len(scenes))
    have_mesh = True
    for sc in scenes:
        p = subprocess.run([cli, "check", sc], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           universal_newlines=True, timeout=300)
        if p.returncode != 0 and re.search(r"built without FLOE_WITH_(ASSIMP|CGAL)", p.stderr):
            have_mesh = False
            print("  skipped (floe built without mesh support): %s" % sc)
            continue
        check(p.returncode == 0, "floe check %s: exit %d\n%s" % (sc, p.returncode, p.stderr))
    tmp = tempfile.mkdtemp(prefix="floe_examples_")
    try:
        scene = os.path.join(root, "examples", "dilating-sphere", "scene.yaml")
        p = subprocess.run([cli, "run", scene, "-o", tmp, "-q"], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, universal_newlines=True, timeout=300)
        check(p.returncode == 0, "dilating-sphere run: exit %d\n%s" % (p.returncode, p.stderr))
        rows = list(csv.DictReader(open(os.path.join(tmp, "track.csv"))))
        last_t = max(float(r["t [s]"]) for r in rows)
        final = {int(r["id"]): r for r in rows if float(r["t [s]"]) == last_t}
        first = {int(r["id"]): r for r in rows if float(r["t [s]"]) == 0.0}
        c0 = (float(first[12]["x [m]"]), float(first[12]["y [m]"]))
        for nb in (11, 13, 6, 7, 16, 17):
            d0 = math.hypot(float(first[nb]["x [m]"]) - c0[0], float(first[nb]["y [m]"]) - c0[1])
            d1 = math.hypot(float(final[nb]["x [m]"]) - c0[0], float(final[nb]["y [m]"]) - c0[1])
            check(abs(d0 - 0.2) < 1e-9, "neighbour %d starts in contact (%.6f m)" % (nb, d0))
            check(d1 > 0.1 + 3.0 * 1.0, "neighbour %d pushed beyond R(3 s) = 3.1 m (%.3f m)" % (nb, d1))
            check(float(final[nb]["z [m]"]) == 0.0, "neighbour %d stays in the plane" % nb)
        erows = list(csv.DictReader(open(os.path.join(tmp, "energy.csv"))))
        err = float(erows[-1]["balance_error"])
        check(err < 1e-3, "dilating-sphere energy balance error %.2e < 1e-3" % err)
        print("  dilating sphere: last t = %.3f s, balance error %.2e" % (last_t, err))
        check_polygons(cli, root, tmp, "polygons-2d", 2, duration=1.0)
        check_polygons(cli, root, tmp, "polyhedra-3d", 3, duration=0.45)
        if have_mesh:
            check_mesh_grains(cli, root, tmp, duration=0.15)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("test_examples")


if __name__ == "__main__":
    main()
