#!/usr/bin/env python3
"""test_examples.py - the example scenes stay valid and the small one reproduces its figure.

usage: python3 tests/test_examples.py <floe_cli_path> <tests_dir>

- `floe check` accepts every examples/*/*.yaml (the RVE builds its 16,483 spheres; a
  scene with plugins from its copy in the build tree, next to the built plugin).
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
- examples/plate-with-hole, brittle-cylinder-impact and rubber-cube (issue #4), shortened:
  cracks at the top and bottom of the hole and not at its sides; damage under the impact
  point of a 3 mm cylinder and none at its bottom rim; the spheres' indentation shows in the
  strain (E_zz most compressive at a contact face) and von Mises arrays; energy balances.
- examples/kalthoff-winkler (issue #10) at dx = 2 mm: each crack is a straight path from its
  pre-cracked notch at 61.5-70 degrees (line fit through the tip, measured 64.0; 59.2
  without the PMB's alpha = 0.25, which the scene now has); energy balances.
- examples/sea-ice-free-drift (issue #12): the floe reaches the steady free drift (the balance
  solved by Newton) within 0.1 % after two days.
- examples/sea-ice-breakup (issue #12) to t = 500 s: the bonded floe breaks into >= 20
  fragments (floe_sizes output) whose areas add up to the floe's; the energy ledger closes.
- examples/sea-ice-strait/jam.yaml (issue #12) reduced to 40 floes, 50 h, safety 0.5: with
  friction (mu = 0.7) at most 6 floes cross the constriction and at most 2 in the last 10 h while
  >= 30 floes wait upstream (the arch); without friction at least 4 more cross and >= 2 in the
  last 10 h (the floes keep flowing).
- examples/rve-periodic (issue #13) to t = 0.4 s: the periodic cell's stress servo holds
  sxx = syy = szz = -10 kPa within 1 %, coordination > 3, the energy ledger closes.
- examples/rve-compaction (issue #13): the preparation (servo walls, then friction) leaves
  every wall at 2 kPa within 2 % at the start of the run and at its end; the ledger closes.
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


# ---- peridynamics examples (issue #4): plate-with-hole, brittle-cylinder-impact, rubber-cube ----

def check_free_drift(cli, root, tmp):
    """examples/sea-ice-free-drift: after two days the floe drifts at the steady free drift
    (the balance of wind stress, turned water stress and Coriolis, solved here by Newton)
    within 0.1 %, and its outline series lists 49 frames."""
    out = os.path.join(tmp, "free-drift")
    scene = os.path.join(root, "examples", "sea-ice-free-drift", "scene.yaml")
    p = subprocess.run([cli, "run", scene, "-o", out, "-q"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                       universal_newlines=True, timeout=300)
    check(p.returncode == 0, "sea-ice-free-drift run: exit %d\n%s" % (p.returncode, p.stderr))
    if p.returncode:
        return
    th, f, h = math.radians(15), 1.4e-4, 1.0

    def res(u):
        ax, ay = 10 - u[0], -u[1]
        sa = 1.2e-3 * math.hypot(ax, ay)
        so = 1027 * 3e-3 * math.hypot(u[0], u[1])
        b = 920 * h * f
        return (sa * ax + so * (-math.cos(th) * u[0] + math.sin(th) * u[1]) + b * u[1],
                sa * ay + so * (-math.sin(th) * u[0] - math.cos(th) * u[1]) - b * u[0])
    u = [0.2, 0.0]
    for _ in range(60):
        r, e = res(u), 1e-7
        J = [[0.0, 0.0], [0.0, 0.0]]
        for k in range(2):
            up = list(u)
            up[k] += e
            rp = res(up)
            J[0][k], J[1][k] = (rp[0] - r[0]) / e, (rp[1] - r[1]) / e
        det = J[0][0] * J[1][1] - J[0][1] * J[1][0]
        u = [u[0] - (J[1][1] * r[0] - J[0][1] * r[1]) / det, u[1] - (-J[1][0] * r[0] + J[0][0] * r[1]) / det]
    rows = list(csv.DictReader(open(os.path.join(out, "floe.csv"))))
    last = rows[-1]
    v = (float(last["vx [m/s]"]), float(last["vy [m/s]"]))
    err = math.hypot(v[0] - u[0], v[1] - u[1]) / math.hypot(u[0], u[1])
    print("  free drift: (%.5f, %.5f) m/s vs steady (%.5f, %.5f), %.2f %% of the wind at %.1f deg right; "
          "error %.1e" % (v[0], v[1], u[0], u[1], 10 * math.hypot(*u), -math.degrees(math.atan2(u[1], u[0])), err))
    check(err < 1e-3, "sea-ice-free-drift: steady free drift within 0.1 %% (%.2e)" % err)
    pvd = open(os.path.join(out, "floe.pvd")).read()
    check(pvd.count("<DataSet") == 49, "sea-ice-free-drift: 49 outline frames (%d)" % pvd.count("<DataSet"))


def check_breakup(cli, root, tmp):
    """examples/sea-ice-breakup to t = 500 s: one floe of 428 bonded cells at t = 0 breaks into
    at least 20 fragments (the floe_sizes output), whose areas add up to the floe's (1e-9),
    and the energy ledger closes (1e-3)."""
    scene = copy_example(root, tmp, "sea-ice-breakup", 500)
    out = os.path.join(tmp, "breakup-out")
    if not run_example(cli, scene, out, "sea-ice-breakup"):
        return
    rows = list(csv.DictReader(open(os.path.join(out, "floe_sizes.csv"))))
    times = sorted({float(r["t [s]"]) for r in rows})
    first = [r for r in rows if float(r["t [s]"]) == times[0]]
    last = [r for r in rows if float(r["t [s]"]) == times[-1]]
    check(len(first) == 1 and int(first[0]["particles"]) == 428, "sea-ice-breakup: one floe of 428 cells at t = 0")
    check(len(last) >= 20, "sea-ice-breakup: at least 20 fragments at t = %g s (%d)" % (times[-1], len(last)))
    a0 = sum(float(r["area [m^2]"]) for r in first)
    a1 = sum(float(r["area [m^2]"]) for r in last)
    check(abs(a1 - a0) <= 1e-9 * a0, "sea-ice-breakup: fragment areas add up to the floe's (%.10g vs %.10g)" % (a1, a0))
    erows = list(csv.DictReader(open(os.path.join(out, "energy.csv"))))
    err = float(erows[-1]["balance_error"])
    check(abs(err) < 1e-3, "sea-ice-breakup: energy balance error %.2e < 1e-3" % err)
    print("  sea-ice break-up: %d fragments at t = %g s, largest %d cells" %
          (len(last), times[-1], max(int(r["particles"]) for r in last)))


def strait_jam_run(cli, src, tmp, mu):
    """Run the reduced jam scene with friction MU; return (crossing times in h, the gate's
    last time in h, floes upstream of the gate at the end) or None."""
    text = open(src).read()
    subs = [(r"count: 100,", "count: 40,"), (r"max: \[59500, 119500\]", "max: [59500, 84100]"),
            (r"time: \{duration: 288000\}", "time: {duration: 180000, safety: 0.5}"),
            (r"friction: 0\.7,", "friction: %g," % mu)]
    for pat, rep in subs:
        text, n = re.subn(pat, rep, text)
        check(n == 1, "sea-ice-strait jam.yaml: '%s' found once" % pat)
    scene = os.path.join(os.path.dirname(src), "jam-%g.yaml" % mu)
    open(scene, "w").write(text)
    out = os.path.join(tmp, "strait-jam-%g" % mu)
    if not run_example(cli, scene, out, "sea-ice-strait jam (mu = %g)" % mu):
        return None
    rows = list(csv.reader(open(os.path.join(out, "gate.csv"))))[1:]
    times, prev = [], 0
    for r in rows:
        n = int(float(r[1]))
        times += [float(r[0]) / 3600] * max(0, n - prev)
        prev = n
    floes = list(csv.DictReader(open(os.path.join(out, "floes.csv"))))
    t_end = max(float(r["t [s]"]) for r in floes)
    upstream = sum(1 for r in floes if float(r["t [s]"]) == t_end and float(r["y [m]"]) > 30000)
    return times, float(rows[-1][0]) / 3600, upstream


def check_strait_jam(cli, root, tmp):
    """examples/sea-ice-strait/jam.yaml reduced to 40 floes (the same floe size, a shorter
    column upstream), 50 h and safety 0.5 (the 80 h, 100-floe scene takes 3 min per run):
    with friction the floes jam at the 11 km constriction, without they keep flowing.
    Measured (seed 3, the scene's): 4 crossings with friction, the last at 37.5 h, 36 floes
    upstream; 13 without, 4 in the last 10 h. The outcome is chaotic (a build with other
    floating-point contractions follows another path), so the bounds were set on eight seeds
    (3-10): with friction 0-5 crossings, 0-2 in the last 10 h, >= 35 upstream; without 6-13,
    >= 2 in the last 10 h, and at least 5 more than with friction in every seed."""
    src = os.path.join(tmp, "sea-ice-strait", "jam.yaml")
    if not os.path.exists(src):
        shutil.copytree(os.path.join(root, "examples", "sea-ice-strait"), os.path.dirname(src))
    res = {mu: strait_jam_run(cli, src, tmp, mu) for mu in (0.7, 0.0)}
    if None in res.values():
        return
    (fr, t1, up1), (fl, t0, up0) = res[0.7], res[0.0]
    late1 = sum(1 for t in fr if t > t1 - 10)
    late0 = sum(1 for t in fl if t > t0 - 10)
    check(t1 > 49.9 and t0 > 49.9, "sea-ice-strait jam: both runs reach 50 h (%.1f, %.1f)" % (t1, t0))
    check(len(fr) <= 6 and late1 <= 2 and up1 >= 30,
          "sea-ice-strait jam: with friction the flux stops: %d floes through (<= 6), %d in the last 10 h (<= 2), "
          "%d of 40 upstream (>= 30)" % (len(fr), late1, up1))
    check(len(fl) >= len(fr) + 4 and late0 >= 2,
          "sea-ice-strait jam: without friction the floes keep flowing: %d through (>= %d + 4), %d in the last "
          "10 h (>= 2)" % (len(fl), len(fr), late0))
    print("  sea-ice-strait jam (40 floes, 50 h): mu = 0.7: %d floes through, the last at %.1f h, %d upstream; "
          "mu = 0: %d through, %d in the last 10 h" % (len(fr), fr[-1] if fr else 0, up1, len(fl), late0))


def read_vtu_arrays(path):
    """Point arrays of a floe .vtu (raw appended or ASCII) as {name: [tuple, ...]}."""
    import struct
    data = open(path, "rb").read()
    cut = data.find(b"<AppendedData")
    head = data[:cut if cut >= 0 else len(data)].decode("latin-1")
    raw = data[data.index(b"_", cut) + 1:] if cut >= 0 else b""
    fmt = {"Float64": ("d", 8), "Int32": ("i", 4), "Int64": ("q", 8), "UInt8": ("B", 1)}
    bo = "<" if 'byte_order="LittleEndian"' in head else ">"
    out = {}
    for m in re.finditer(r'<DataArray([^>]*?)(/?)>', head):
        attrs = dict(re.findall(r'(\w+)="([^"]*)"', m.group(1)))
        nc = int(attrs.get("NumberOfComponents", "1"))
        if attrs.get("format") == "appended":
            off = int(attrs["offset"])
            nbytes = struct.unpack(bo + "Q", raw[off:off + 8])[0]
            code, size = fmt[attrs["type"]]
            vals = struct.unpack(bo + code * (nbytes // size), raw[off + 8:off + 8 + nbytes])
        elif attrs.get("format") == "ascii" and m.group(2) == "":
            vals = [float(x) for x in head[m.end():head.index("</DataArray>", m.end())].split()]
        else:
            continue
        out[attrs["Name"]] = [tuple(vals[i:i + nc]) for i in range(0, len(vals), nc)]
    return out


def pd_example(cli, root, tmp, name, duration, subs=()):
    """Copy and shorten a PD example, apply (regex, replacement) edits, keep only the first
    and last VTK frames, run it; returns (outdir, arrays of the last frame) or None."""
    scene = copy_example(root, tmp, name, duration)
    text = open(scene).read()
    for pat, rep in subs:
        text, n = re.subn(pat, rep, text)
        check(n >= 1, "%s: '%s' found in the scene" % (name, pat))
    text, n = re.subn(r"\{type: vtk, (every|interval): [0-9.eE+-]+\}", "{type: vtk, every: 100000000}", text)
    check(n == 1, "%s: one vtk output" % name)
    open(scene, "w").write(text)
    out = os.path.join(tmp, name + "-out")
    if not run_example(cli, scene, out, name):
        return None
    frames = sorted(glob.glob(os.path.join(out, "frame_*.vtu")))
    check(len(frames) >= 2, "%s: first and last VTK frames written (%d)" % (name, len(frames)))
    if len(frames) < 2:
        return None
    last = read_vtu_arrays(frames[-1])
    check(abs(last["TimeValue"][0][0] - duration) < 0.01 * duration, "%s: ran to t = %g s" % (name, last["TimeValue"][0][0]))
    erows = list(csv.DictReader(open(os.path.join(out, "energy.csv"))))
    err = float(erows[-1]["balance_error"])
    check(abs(err) < 1e-3, "%s: energy balance error %.2e < 1e-3" % (name, err))
    return out, last


def check_plate_with_hole(cli, root, tmp):
    """ParticLS §5.4: cracks nucleate at the top and bottom of the hole, not at its sides."""
    dx = 1.0 / 64
    res = pd_example(cli, root, tmp, "plate-with-hole", 0.5)
    if not res:
        return
    out, a = res
    pts = list(zip(a["Points"], a["damage"]))
    check(len(pts) > 3000, "plate-with-hole: %d points" % len(pts))

    def near(cx, cy):
        return [d[0] for p, d in pts if math.hypot(p[0] - cx, p[1] - cy) < 2.5 * dx]
    # hole semi-axes 0.08 (x) and 0.16 (y) at (0.5, 0.5)
    top, bottom = max(near(0.5, 0.66)), max(near(0.5, 0.34))
    left, right = max(near(0.42, 0.5)), max(near(0.58, 0.5))
    far = max(d[0] for p, d in pts if abs(p[1] - 0.5) < 0.1 and (p[0] < 0.3 or p[0] > 0.7))
    check(top > 0.3 and bottom > 0.3, "plate-with-hole: damage at the hole's top %.2f and bottom %.2f > 0.3" % (top, bottom))
    check(left < 0.05 and right < 0.05, "plate-with-hole: no damage at the hole's sides (%.3f, %.3f < 0.05)" % (left, right))
    check(far < 0.05, "plate-with-hole: none in the ligaments left and right of the hole (%.3f)" % far)
    check("force_density" in a and "strain" in a, "plate-with-hole: force_density and strain written")
    print("  plate-with-hole: t = 0.5 s, damage top %.2f bottom %.2f, sides %.3f %.3f, ligaments %.3f"
          % (top, bottom, left, right, far))


def check_brittle_cylinder(cli, root, tmp):
    """003 §4.3 at a tiny resolution: damage under the impact point, none at the far bottom."""
    dx = 0.003
    res = pd_example(cli, root, tmp, "brittle-cylinder-impact", 60e-6, [(r"spacing: 0\.002", "spacing: %g" % dx)])
    if not res:
        return
    out, a = res
    pts = [(p, d[0]) for p, d, b in zip(a["Points"], a["damage"], a["body"]) if b[0] == -2]
    under = max(d for p, d in pts if math.hypot(p[0], p[1]) < 2 * dx and p[2] > 0.03 - 3 * dx)
    rim = max(d for p, d in pts if math.hypot(p[0], p[1]) > 0.03 - 2 * dx and p[2] < 0.01)
    nd = sum(1 for p, d in pts if d > 0.3)
    outside = max(d for p, d in pts if math.hypot(p[0], p[1]) > 0.015)
    check(under > 0.3, "brittle-cylinder: damage under the impact point %.2f > 0.3" % under)
    check(rim < 0.1 and outside < 0.3, "brittle-cylinder: none at the bottom rim (%.3f < 0.1), below 0.3 beyond "
          "r = 15 mm (%.3f)" % (rim, outside))
    imp = list(csv.DictReader(open(os.path.join(out, "impactor.csv"))))
    vz = float(imp[-1]["vz [m/s]"])
    check(vz > -35 * 0.9, "brittle-cylinder: the impactor is slowed (vz %.1f m/s)" % vz)
    print("  brittle-cylinder-impact: %d points at %g m, 60 us: damage under the impact %.2f, rim %.3f, %d points "
          "> 0.3, impactor vz %.1f m/s" % (len(pts), dx, under, rim, nd, vz))


def kw_branch_fit(X, dmg, tip, sgn, rmin=0.005, rmax=0.06):
    """Kalthoff-Winkler crack path angle of one branch: the line through the notch tip fitted
    (least squares, perpendicular distances) to the points with damage > 0.35 on the outer
    side of the notch (sgn: +1 upper, -1 lower notch, mirrored), 5-60 mm from the tip and more
    than 30 degrees from the notch direction (the damage arcs from the plate's mid-line reach
    above the notch line near x = 75 mm at 10-20 degrees). Reference positions. Returns
    (angle in degrees from the notch direction, rms distance of the points from the line in m,
    count)."""
    pts = []
    for p, d in zip(X, dmg):
        u, v = p[0] - tip[0], sgn * (p[1] - tip[1])
        if d[0] > 0.35 and v > 0 and math.atan2(v, u) > math.radians(30) and rmin <= math.hypot(u, v) < rmax:
            pts.append((u, v))
    if len(pts) < 3:
        return float("nan"), float("nan"), len(pts)
    suu = sum(u * u for u, v in pts)
    svv = sum(v * v for u, v in pts)
    suv = sum(u * v for u, v in pts)
    th = 0.5 * math.atan2(2 * suv, suu - svv)
    c, s = math.cos(th), math.sin(th)
    rms = math.sqrt(sum((c * v - s * u) ** 2 for u, v in pts) / len(pts))
    return math.degrees(th), rms, len(pts)


def check_kalthoff_winkler(cli, root, tmp):
    """Issue #10 and the crack-angle study (examples/kalthoff-winkler/README.md): at dx = 2 mm
    (the notches moved to y = +-24 mm, between two rows of points) each crack is a straight
    path from its notch tip (line fit through the tip, rms distance < 2.5 mm) at 61.5-70 deg
    (measured 64.0; Silling 2003: about 68 deg, experiment about 70). The scene's PMB has
    Silling & Askari's compression term alpha = 0.25; with a constant critical stretch
    (alpha = 0) the same plate gives 59.2 deg and fails here. The two branches mirror each
    other to 0.5 deg."""
    subs = [(r"spacing: 0\.001", "spacing: 0.002"), (r"0\.025\], \[0\.05, 0\.025\]", "0.024], [0.05, 0.024]"),
            (r"-0\.025\], \[0\.05, -0\.025\]", "-0.024], [0.05, -0.024]"),
            (r"min: \[-1, -0\.025\], max: \[0\.003, 0\.025\]", "min: [-1, -0.024], max: [0.006, 0.024]")]
    res = pd_example(cli, root, tmp, "kalthoff-winkler", 90e-6, subs)
    if not res:
        return
    out, a = res
    first = read_vtu_arrays(sorted(glob.glob(os.path.join(out, "frame_*.vtu")))[0])
    up = kw_branch_fit(first["Points"], a["damage"], (0.05, 0.024), 1)
    lo = kw_branch_fit(first["Points"], a["damage"], (0.05, -0.024), -1)
    for name, (ang, rms, n) in (("upper", up), ("lower", lo)):
        check(n >= 30 and 61.5 < ang < 70, "kalthoff-winkler: %s crack at %.1f deg in (61.5, 70) over %d damaged points"
              % (name, ang, n))
        check(rms < 2.5e-3, "kalthoff-winkler: %s crack is a straight path (rms %.2f mm < 2.5 mm from the line)"
              % (name, rms * 1e3))
    check(abs(up[0] - lo[0]) < 0.5, "kalthoff-winkler: branches mirror each other (%.1f vs %.1f deg)" % (up[0], lo[0]))
    print("  kalthoff-winkler: dx = 2 mm, 90 us: crack path angles %.1f / %.1f deg (line fit through the tips, "
          "rms %.1f / %.1f mm, %d / %d points)" % (up[0], lo[0], up[1] * 1e3, lo[1] * 1e3, up[2], lo[2]))


def check_rubber_cube(cli, root, tmp):
    """000 §5.2, shortened: the spheres indent the cube, strain and von Mises at the contacts."""
    res = pd_example(cli, root, tmp, "rubber-cube", 0.1)
    if not res:
        return
    out, a = res
    cube = [i for i, b in enumerate(a["body"]) if b[0] == -2]
    ezz = [a["strain"][i][8] for i in cube]
    exx = [a["strain"][i][0] for i in cube]
    vm = [a["von_mises"][i][0] for i in cube]
    i = min(cube, key=lambda k: a["strain"][k][8])
    z = a["Points"][i][2]
    check(min(ezz) < -0.02, "rubber-cube: compressive E_zz under the spheres (min %.4f)" % min(ezz))
    check(abs(z) > 0.1, "rubber-cube: E_zz is most compressive at a contact face (z = %.3f m)" % z)
    check(max(exx) > 0, "rubber-cube: the nearly incompressible cube bulges sideways (max E_xx %.4f)" % max(exx))
    check(max(vm) > 0, "rubber-cube: von Mises stress written (max %.3g Pa)" % max(vm))
    print("  rubber-cube: t = 0.1 s, E_zz min %.4f at z = %.3f m, E_xx max %.4f, von Mises max %.3g Pa"
          % (min(ezz), z, max(exx), max(vm)))


def check_rve_periodic(cli, root, tmp):
    """examples/rve-periodic (issue #13) to t = 0.4 s: the cell's servo holds every normal
    stress at -10 kPa within 1 % (mean of the last 5 rows), the packing is jammed (coordination
    > 3), and the energy ledger closes with the cell's work booked (balance_error < 1e-3)."""
    scene = copy_example(root, tmp, "rve-periodic", 0.4)
    out = os.path.join(tmp, "rve-periodic-out")
    if not run_example(cli, scene, out, "rve-periodic"):
        return
    rows = list(csv.DictReader(open(os.path.join(out, "stress.csv"))))[-5:]
    for c in ("sxx [Pa]", "syy [Pa]", "szz [Pa]"):
        m = sum(float(r[c]) for r in rows) / len(rows)
        check(abs(m + 1e4) < 100, "rve-periodic: %s = %.1f Pa, target -10000 within 1 %%" % (c, m))
    z = float(rows[-1]["coordination"])
    check(z > 3, "rve-periodic: jammed, coordination %.2f > 3" % z)
    erows = list(csv.DictReader(open(os.path.join(out, "energy.csv"))))
    err = float(erows[-1]["balance_error"])
    check(err < 1e-3, "rve-periodic: energy balance error %.2e < 1e-3" % err)
    print("  rve-periodic: coordination %.2f, balance error %.2e" % (z, err))


def check_rve_compaction(cli, root, tmp):
    """examples/rve-compaction (issue #13): the preparation compacts the sample to 2 kPa on
    every servo wall; the main run (friction on) starts and ends there: each wall's pressure
    -F.n / A (A the product of the other walls' separations) within 2 % of 2 kPa at t = 0
    and at the end, the porosity of a random packing (0.3 to 0.5), the energy ledger closes."""
    scene = os.path.join(root, "examples", "rve-compaction", "scene.yaml")
    out = os.path.join(tmp, "rve-compaction")
    if not run_example(cli, scene, out, "rve-compaction"):
        return
    rows = list(csv.DictReader(open(os.path.join(out, "walls.csv"))))
    ids = sorted({int(r["id"]) for r in rows})
    check(len(ids) == 6, "rve-compaction: six walls tracked (%d)" % len(ids))
    if len(ids) != 6:
        return
    times = sorted({float(r["t [s]"]) for r in rows})
    vbox_end = None
    for t in (times[0], times[-1]):
        w = {int(r["id"]): r for r in rows if float(r["t [s]"]) == t}
        L = [float(w[ids[2 * a + 1]]["xyz"[a] + " [m]"]) - float(w[ids[2 * a]]["xyz"[a] + " [m]"]) for a in range(3)]
        ps = []
        for a in range(3):
            A = L[(a + 1) % 3] * L[(a + 2) % 3]
            for k in range(2):
                f = float(w[ids[2 * a + k]]["f" + "xyz"[a] + " [N]"])
                ps.append(abs(f) / A)
        worst = max(abs(p - 2000.0) / 2000.0 for p in ps)
        check(worst <= 0.02, "rve-compaction at t = %g s: every wall at 2 kPa within 2 %% (%s)"
              % (t, ", ".join("%.0f" % p for p in ps)))
        vbox = L[0] * L[1] * L[2]
        print("  rve-compaction t = %.3f s: box %.4f x %.4f x %.4f m, wall pressures %s Pa (worst %.2f %%)"
              % (t, L[0], L[1], L[2], " ".join("%.0f" % p for p in ps), 100 * worst))
        vbox_end = vbox
    erows = list(csv.DictReader(open(os.path.join(out, "energy.csv"))))
    err = float(erows[-1]["balance_error"])
    check(err < 1e-3, "rve-compaction energy balance error %.2e < 1e-3" % err)
    check(vbox_end is not None and 0.00015 < vbox_end < 0.00030, "rve-compaction: the box shrank from 3.4e-4 m^3 (%.3g)"
          % vbox_end)


def main():
    cli, tests = sys.argv[1], sys.argv[2]
    root = os.path.dirname(os.path.abspath(tests))
    # every scene of every example (scene.yaml and the others: periodic.yaml, walled.yaml ...)
    scenes = sorted(glob.glob(os.path.join(root, "examples", "*", "*.yaml")))
    check(len(scenes) >= 2, "example scenes found: %d" % len(scenes))
    have_mesh = True
    for sc in scenes:
        if "\nplugins:" in open(sc).read():
            # a scene with plugins is checked where the build put its plugin (examples/plugin:
            # the scene is copied next to torus_plugin.so in the build tree)
            sc = os.path.join(os.path.dirname(os.path.abspath(cli)), "examples",
                              os.path.basename(os.path.dirname(sc)), "scene.yaml")
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
        check_plate_with_hole(cli, root, tmp)
        check_brittle_cylinder(cli, root, tmp)
        check_rubber_cube(cli, root, tmp)
        check_kalthoff_winkler(cli, root, tmp)
        check_free_drift(cli, root, tmp)
        check_breakup(cli, root, tmp)
        check_strait_jam(cli, root, tmp)
        check_rve_periodic(cli, root, tmp)
        check_rve_compaction(cli, root, tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("test_examples")


if __name__ == "__main__":
    main()
