#!/usr/bin/env python3
"""test_outlines.py - the `outlines` output (observers/outline_writer.c): run the floe CLI on
a small 2D scene (a turning triangle, a moving hexagon, a disc, an ellipse, a non-convex
L-shaped compound of a polygon and a turned box, and a wall) and read its .vtu files back
(ASCII and raw binary appended data, parsed here: no VTK module needed).

usage: python3 tests/test_outlines.py <floe_cli_path> <tests_dir>

Checks, tolerances stated at each:
- the .pvd lists every frame written (one per 25 steps from step 0 to the end), in order,
  with TimeValue equal to its timestep;
- one VTK_POLYGON cell per bounded particle and per compound piece (the wall left out);
- each polygon's points are the expected world corners, counter-clockwise, to 1e-9 (relative
  to the floe size): at the first frame from the scene (the vertices as written, centroid at
  `position`, turned by `orientation`), later from the pose the vtk output writes in the same
  run (x + R(q) R(q0)^T (corner0 - x0));
- the disc's points all at distance r from its centre (1e-9 relative), the ellipse's on the
  ellipse, and their areas equal to the inscribed N-gon's, (N/2) r^2 sin(2 pi / N) (1e-9
  relative; within 1 % of pi r^2 for N = 48); the polygons' areas to 1e-9;
- cell data id / body / material / velocity / angular_velocity / area / thickness (one floe 0.5 m
  thick, the others 0);
- the same scene written in binary with segments: 12 gives the same polygons bit for bit
  and 12-point curved outlines;
- a 3D scene with an outlines output is refused with "outlines is a 2D output";
- where python3-vtk9 is installed: VTK's own reader (vtkXMLUnstructuredGridReader) loads every
  frame without errors or warnings and reads the same cells, points and areas.
Prints "N passed, N failed".
"""
import glob
import math
import os
import shutil
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET

# python3-vtk9 is a Debian package: when the python3 on PATH is another interpreter (pyenv,
# venv) without it, re-run under the system one (as tests/test_vtk.py does); without it the
# VTK reader check is skipped
try:
    import vtk
except ImportError:
    if os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3") \
            and os.path.exists("/usr/bin/python3") and not os.environ.get("FLOE_TEST_VTK_REEXEC"):
        os.environ["FLOE_TEST_VTK_REEXEC"] = "1"
        os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
    vtk = None

from pycheck import check, finish as _finish

DT = 0.001
STEPS = 100
EVERY = 25
TOL = 1e-9

TRIANGLE = [[0, 0], [2, 0], [0, 1]]
HEXAGON = [[math.cos(math.pi * k / 3), math.sin(math.pi * k / 3)] for k in range(6)]
DISC_R = 0.7
ELLIPSE = (1.0, 0.5)
# the compound: a 2 x 1 polygon at the compound's origin and a 2 x 1 box turned by 90 degrees
# about z, its centre at (-0.5, 1.5): an L of area 4
PIECE0 = [[-1, -0.5], [1, -0.5], [1, 0.5], [-1, 0.5]]
PIECE1_POS, PIECE1_TURN = (-0.5, 1.5), math.pi / 2
PIECE1 = [[-1, -0.5], [1, -0.5], [1, 0.5], [-1, 0.5]]


def q_of(angle):
    """unit quaternion [w, x, y, z] of a rotation by angle about z"""
    return [math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2)]


def turn(p, a):
    c, s = math.cos(a), math.sin(a)
    return [c * p[0] - s * p[1], s * p[0] + c * p[1]]


def q_angle(q):
    return 2.0 * math.atan2(q[3], q[0])


def signed_area(poly):
    return 0.5 * sum(poly[k][0] * poly[(k + 1) % len(poly)][1] - poly[(k + 1) % len(poly)][0] * poly[k][1]
                     for k in range(len(poly)))


def centroid(poly):
    a = signed_area(poly)
    cx = sum((poly[k][0] + poly[k - 1][0]) * (poly[k - 1][0] * poly[k][1] - poly[k][0] * poly[k - 1][1])
             for k in range(len(poly))) / (6 * a)
    cy = sum((poly[k][1] + poly[k - 1][1]) * (poly[k - 1][0] * poly[k][1] - poly[k][0] * poly[k - 1][1])
             for k in range(len(poly))) / (6 * a)
    return [cx, cy]


def ccw(poly):
    return poly if signed_area(poly) > 0 else poly[::-1]


# body entries: name, position, angle (orientation), velocity, angular velocity (z)
BODIES = [
    ("triangle", (0.0, 0.0), math.radians(30), (0.3, -0.2), 2.0),
    ("hexagon", (5.0, 0.0), 0.0, (-0.5, 0.4), -1.5),
    ("disc", (10.0, 0.0), 0.0, (0.0, 0.0), 0.0),
    ("ellipse", (15.0, 0.0), math.radians(20), (0.0, 0.0), 1.0),
    ("compound", (20.0, 0.0), math.radians(-40), (0.1, 0.1), 0.7),
]


def scene_text(outlines):
    q = lambda a: "[%r, 0, 0, %r]" % (q_of(a)[0], q_of(a)[3])
    pts = lambda vs: "[" + ", ".join("[%r, %r]" % (v[0], v[1]) for v in vs) + "]"
    shapes = {
        "triangle": "{polygon: {vertices: %s}}" % pts(TRIANGLE),
        "hexagon": "{polygon: {vertices: %s}}" % pts(HEXAGON),
        "disc": "{sphere: {radius: %r}}" % DISC_R,
        "ellipse": "{ellipsoid: {semi_axes: [%r, %r, 0.5]}}" % ELLIPSE,
        "compound": "{compound: {pieces: [{shape: {polygon: {vertices: %s}}}, "
                    "{shape: {box: {size: [2, 1, 1]}}, position: [%r, %r], orientation: %s}]}}"
                    % (pts(PIECE0), PIECE1_POS[0], PIECE1_POS[1], q(PIECE1_TURN)),
    }
    # mass_2d: area: a compound of polygon pieces has no 3D mass (sea-ice floes: area x density)
    lines = ["name: outlines-test", "dimension: 2", "mass_2d: area", "time: {duration: %r, dt: %r}" % (STEPS * DT, DT),
             "gravity: [0, 0]", "materials:", "  - {name: ice, density: 917}", "laws:",
             "  - {materials: [ice, ice], model: linear, kn: 1000, ks: 500, friction: 0.3}",
             "walls:", "  - {point: [0, -10], normal: [0, 1], material: ice}", "bodies:"]
    for k, (name, pos, ang, vel, om) in enumerate(BODIES):
        # the first body is a floe 0.5 m thick (the cell array `thickness`; 0 for the others)
        lines.append("  - {material: ice, position: [%r, %r], orientation: %s, velocity: [%r, %r], "
                     "angular_velocity: [0, 0, %r], %sshape: %s}" % (pos[0], pos[1], q(ang), vel[0], vel[1], om,
                                                                     "thickness: 0.5, " if k == 0 else "",
                                                                     shapes[name]))
    lines.append("outputs:")
    lines.append("  - {type: vtk, every: %d, prefix: frame, ascii: true}" % EVERY)
    lines.append("  - " + outlines)
    return "\n".join(lines) + "\n"


def scene_3d(outlines):
    return ("dimension: 3\ntime: {duration: 0.01, dt: 0.001}\ngravity: [0, 0, 0]\nmaterials:\n"
            "  - {name: ice, density: 917}\nlaws:\n"
            "  - {materials: [ice, ice], model: linear, kn: 1000, ks: 500, friction: 0.3}\nbodies:\n"
            "  - {material: ice, position: [0, 0, 0], shape: {sphere: {radius: 0.5}}}\noutputs:\n  - %s\n" % outlines)


def run_cli(cli, text, outdir):
    shutil.rmtree(outdir, ignore_errors=True)
    os.makedirs(outdir)
    scene = os.path.join(outdir, "scene.yaml")
    with open(scene, "w") as f:
        f.write(text)
    try:
        p = subprocess.run([cli, "run", scene, "-o", outdir], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           timeout=600, universal_newlines=True)
        return p.returncode, p.stdout
    except subprocess.TimeoutExpired:
        return -1, "timeout"


# ---- .vtu reading: ASCII and raw appended data ----

FMT = {"Int32": "i", "Int64": "q", "UInt8": "B", "Float64": "d"}


def read_vtu(path):
    """{'time', 'npoints', 'ncells', 'cell': {name: tuples}, 'point': {...}, 'points', 'conn',
    'offsets', 'types'}"""
    data = open(path, "rb").read()
    raw = b""
    k = data.find(b"<AppendedData")
    if k >= 0:
        start = data.index(b"_", data.index(b">", k)) + 1
        end = data.rindex(b"</AppendedData>")
        raw = data[start:end]
        head = data[:k] + b"</VTKFile>"
    else:
        head = data
    root = ET.fromstring(head.decode("utf-8"))
    order = "<" if root.get("byte_order") == "LittleEndian" else ">"
    check(root.get("header_type") == "UInt64", "%s: header_type %s" % (path, root.get("header_type")))

    def values(da):
        t, nc = da.get("type"), int(da.get("NumberOfComponents", "1"))
        if da.get("format") == "ascii":
            conv = float if t == "Float64" else int
            flat = [conv(v) for v in (da.text or "").split()]
        else:
            off = int(da.get("offset"))
            (nbytes,) = struct.unpack(order + "Q", raw[off:off + 8])
            size = struct.calcsize(FMT[t])
            flat = list(struct.unpack(order + FMT[t] * (nbytes // size), raw[off + 8:off + 8 + nbytes]))
        return [flat[i:i + nc] for i in range(0, len(flat), nc)]

    grid = root.find("UnstructuredGrid")
    piece = grid.find("Piece")
    out = {"npoints": int(piece.get("NumberOfPoints")), "ncells": int(piece.get("NumberOfCells"))}
    tv = [d for d in grid.find("FieldData").findall("DataArray") if d.get("Name") == "TimeValue"]
    out["time"] = float(tv[0].text) if tv else None
    for sec, key in (("CellData", "cell"), ("PointData", "point")):
        node = piece.find(sec)
        out[key] = {d.get("Name"): (d.get("type"), values(d)) for d in (node if node is not None else [])}
    out["points"] = values(piece.find("Points").find("DataArray"))
    cells = {d.get("Name"): values(d) for d in piece.find("Cells").findall("DataArray")}
    out["conn"] = [r[0] for r in cells["connectivity"]]
    out["offsets"] = [r[0] for r in cells["offsets"]]
    out["types"] = [r[0] for r in cells["types"]]
    return out


def check_with_vtk(path, f):
    """VTK's reader loads the frame without complaint and reads what read_vtu read"""
    messages = []
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.AddObserver("ErrorEvent", lambda o, e: messages.append(e))
    reader.AddObserver("WarningEvent", lambda o, e: messages.append(e))
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    name = os.path.basename(path)
    check(not messages and reader.GetErrorCode() == 0, "%s: VTK reported %s" % (name, messages))
    check(grid.GetNumberOfCells() == f["ncells"] and grid.GetNumberOfPoints() == f["npoints"],
          "%s: VTK reads %d cells, %d points" % (name, grid.GetNumberOfCells(), grid.GetNumberOfPoints()))
    polys = polygons(f)
    same = grid.GetNumberOfCells() == len(polys)
    for j in range(min(grid.GetNumberOfCells(), len(polys))):
        cell = grid.GetCell(j)
        same = same and cell.GetCellType() == 7 and cell.GetNumberOfPoints() == len(polys[j])
        same = same and all(list(grid.GetPoint(cell.GetPointId(k)))[:2] == polys[j][k] for k in range(len(polys[j])))
    check(same, "%s: VTK reads other polygons" % name)
    arr = grid.GetCellData().GetArray("area")
    check(arr is not None and [arr.GetValue(j) for j in range(arr.GetNumberOfTuples())]
          == [r[0] for r in f["cell"]["area"][1]], "%s: VTK reads other areas" % name)


def polygons(f):
    """the cells' point lists (2D)"""
    polys, start = [], 0
    for end in f["offsets"]:
        polys.append([f["points"][f["conn"][j]][:2] for j in range(start, end)])
        start = end
    return polys


def read_series(outdir, prefix):
    """[(time, path)] from PREFIX.pvd"""
    pvd = os.path.join(outdir, prefix + ".pvd")
    if not check(os.path.isfile(pvd), "%s missing" % pvd):
        return []
    try:
        root = ET.parse(pvd).getroot()
    except ET.ParseError as e:
        check(False, "%s is not valid XML: %s" % (pvd, e))
        return []
    return [(float(d.get("timestep")), os.path.join(outdir, d.get("file"))) for d in root.iter("DataSet")]


def same_cycle(got, want, scale, what):
    """got == want as counter-clockwise cycles (any starting corner), to TOL x scale"""
    if not check(len(got) == len(want), "%s: %d points, expected %d" % (what, len(got), len(want))):
        return
    d = lambda p, q: math.hypot(p[0] - q[0], p[1] - q[1])
    s = min(range(len(want)), key=lambda k: d(got[0], want[k]))
    err = max(d(got[j], want[(s + j) % len(want)]) for j in range(len(got)))
    check(err <= TOL * scale, "%s: corners off by %.3g (tolerance %.3g)\n  got  %s\n  want %s"
          % (what, err, TOL * scale, got, want[s:] + want[:s]))
    check(signed_area(got) > 0, "%s: not counter-clockwise" % what)


def expected_local():
    """each body's outline(s) relative to its centre of mass in the first frame's world
    orientation: polygons (CCW lists of corners), None for curved shapes"""
    out = {}
    for name, pos, ang, vel, om in BODIES:
        if name in ("triangle", "hexagon"):
            vs = ccw([list(v) for v in (TRIANGLE if name == "triangle" else HEXAGON)])
            c = centroid(vs)
            out[name] = [[turn([v[0] - c[0], v[1] - c[1]], ang) for v in vs]]
        elif name == "compound":
            p0 = ccw([list(v) for v in PIECE0])
            p1 = ccw([[PIECE1_POS[0] + t[0], PIECE1_POS[1] + t[1]] for t in (turn(v, PIECE1_TURN) for v in PIECE1)])
            a0, a1 = signed_area(p0), signed_area(p1)
            c0, c1 = centroid(p0), centroid(p1)
            c = [(a0 * c0[k] + a1 * c1[k]) / (a0 + a1) for k in range(2)]
            out[name] = [[turn([v[0] - c[0], v[1] - c[1]], ang) for v in p] for p in (p0, p1)]
        else:
            out[name] = None
    return out


def check_run(outdir, segments, frames_vtk):
    """checks the outlines series of one run against the scene and the vtk poses; returns the
    polygons of every frame"""
    series = read_series(outdir, "floes")
    vtus = sorted(glob.glob(os.path.join(outdir, "floes_*.vtu")))
    nframes = STEPS // EVERY + 1
    check(len(series) == nframes, "%s: pvd lists %d frames, expected %d" % (outdir, len(series), nframes))
    check([p for _, p in series] == vtus, "%s: pvd files %s != frames on disk %s" % (outdir, series, vtus))
    check([t for t, _ in series] == sorted(t for t, _ in series) and len({t for t, _ in series}) == len(series),
          "%s: pvd times not increasing" % outdir)
    check(len(frames_vtk) == len(series), "%s: %d vtk frames for %d outline frames" % (outdir, len(frames_vtk),
                                                                                        len(series)))
    local = expected_local()
    ids = {}
    result = []
    for k, (t, path) in enumerate(series):
        name = os.path.basename(path)
        if not check(os.path.isfile(path), "%s missing" % path):
            continue
        f = read_vtu(path)
        if vtk is not None:
            check_with_vtk(path, f)
        check(abs(f["time"] - t) <= 1e-12 * max(1.0, t), "%s: TimeValue %r != pvd %r" % (name, f["time"], t))
        check(abs(t - k * EVERY * DT) <= 1e-9, "%s: time %r, expected %r" % (name, t, k * EVERY * DT))
        check(f["ncells"] == 6, "%s: %d cells, expected 6 (4 shapes, 2 compound pieces; no wall)"
              % (name, f["ncells"]))
        check(set(f["types"]) == {7}, "%s: cell types %s, expected VTK_POLYGON (7)" % (name, set(f["types"])))
        check(f["npoints"] == len(f["points"]) == len(f["conn"]), "%s: point counts" % name)
        check(all(p[2] == 0.0 for p in f["points"]), "%s: z not 0" % name)
        want = {"id": ("Int32", 1), "body": ("Int32", 1), "material": ("Int32", 1),
                "velocity": ("Float64", 3), "angular_velocity": ("Float64", 3), "area": ("Float64", 1),
                "thickness": ("Float64", 1)}
        for a, (typ, nc) in want.items():
            have = f["cell"].get(a)
            if check(have is not None, "%s: cell array %s missing" % (name, a)):
                check(have[0] == typ and len(have[1]) == f["ncells"] and all(len(r) == nc for r in have[1]),
                      "%s: %s is %s with %s tuples" % (name, a, have[0], len(have[1])))
        if any(a not in f["cell"] for a in want):
            continue
        th = [r[0] for r in f["cell"]["thickness"][1]]
        check(th.count(0.5) == 1 and all(t in (0.0, 0.5) for t in th),
              "%s: one floe 0.5 m thick, the others 0 (%s)" % (name, th))
        polys = polygons(f)
        result.append(polys)
        cid = [r[0] for r in f["cell"]["id"][1]]
        area = [r[0] for r in f["cell"]["area"][1]]
        vel = f["cell"]["velocity"][1]
        om = f["cell"]["angular_velocity"][1]
        pose = frames_vtk[k] if k < len(frames_vtk) else None
        if pose is None:
            continue
        vid = [int(r[0]) for r in pose["point"]["id"][1]]
        vx = {i: pose["points"][j] for j, i in enumerate(vid)}
        vq = {i: pose["point"]["orientation"][1][j] for j, i in enumerate(vid)}
        vv = {i: pose["point"]["velocity"][1][j] for j, i in enumerate(vid)}
        if k == 0:  # the particle of each body entry: the one at its position
            for b, (bname, pos, ang, v0, w0) in enumerate(BODIES):
                near = [i for i in vid if math.hypot(vx[i][0] - pos[0], vx[i][1] - pos[1]) < 1e-9]
                if check(len(near) == 1, "body %s: no particle at %s in the vtk output" % (bname, pos)):
                    ids[bname] = near[0]
            check(sorted(set(cid)) == sorted(ids.values()), "%s: cell ids %s, particles %s" % (name, cid, ids))
            q0 = {i: vq[i] for i in vid}
        body = {}
        for b, (bname, pos, ang, v0, w0) in enumerate(BODIES):
            i = ids.get(bname)
            cells = [j for j, c in enumerate(cid) if c == i]
            body[bname] = cells
            if not check(len(cells) == (2 if bname == "compound" else 1), "%s: %s has %d cells" % (name, bname,
                                                                                                  len(cells))):
                continue
            for j in cells:
                check(all(abs(vel[j][c] - vv[i][c]) <= 1e-12 for c in range(3)), "%s: %s velocity %s != vtk %s"
                      % (name, bname, vel[j], vv[i]))
                check(abs(om[j][2] - w0) <= 1e-9 and om[j][0] == om[j][1] == 0.0, "%s: %s angular velocity %s"
                      % (name, bname, om[j]))
                check(f["cell"]["body"][1][j][0] == b, "%s: %s body %s" % (name, bname, f["cell"]["body"][1][j]))
            # the turn since the first frame, from the vtk orientations
            dang = q_angle(vq[i]) - q_angle(q0[i])
            xc = vx[i]
            if local[bname] is not None:
                for piece, j in enumerate(cells):
                    want_poly = [[xc[0] + p[0], xc[1] + p[1]] for p in (turn(v, dang) for v in local[bname][piece])]
                    same_cycle(polys[j], want_poly, 3.0, "%s: %s piece %d" % (name, bname, piece))
                    check(abs(area[j] - abs(signed_area(local[bname][piece]))) <= TOL * area[j],
                          "%s: %s piece %d area %r, expected %r" % (name, bname, piece, area[j],
                                                                   abs(signed_area(local[bname][piece]))))
                if k == 0:  # the scene's own placement (centroid at position)
                    check(math.hypot(xc[0] - pos[0], xc[1] - pos[1]) <= 1e-12, "%s: %s at %s" % (name, bname, xc))
            else:
                j = cells[0]
                poly = polys[j]
                check(len(poly) == segments, "%s: %s has %d points, expected %d" % (name, bname, len(poly),
                                                                                  segments))
                check(signed_area(poly) > 0, "%s: %s not counter-clockwise" % (name, bname))
                if bname == "disc":
                    r = DISC_R
                    dev = max(abs(math.hypot(p[0] - xc[0], p[1] - xc[1]) - r) for p in poly) / r
                    check(dev <= TOL, "%s: disc points off the circle by %.3g (relative)" % (name, dev))
                    ngon = 0.5 * segments * r * r * math.sin(2 * math.pi / segments)
                else:
                    a, b = ELLIPSE
                    tot = q_angle(vq[i])
                    dev = 0.0
                    for p in poly:
                        u = turn([p[0] - xc[0], p[1] - xc[1]], -tot)
                        dev = max(dev, abs(math.hypot(u[0] / a, u[1] / b) - 1.0))
                    check(dev <= TOL, "%s: ellipse points off the ellipse by %.3g (relative)" % (name, dev))
                    # rays at 2 pi k / N from the body x axis: the inscribed polygon's area
                    ngon = 0.0
                    for m in range(segments):
                        t0, t1 = 2 * math.pi * m / segments, 2 * math.pi * (m + 1) / segments
                        r0 = 1.0 / math.hypot(math.cos(t0) / a, math.sin(t0) / b)
                        r1 = 1.0 / math.hypot(math.cos(t1) / a, math.sin(t1) / b)
                        ngon += 0.5 * r0 * r1 * math.sin(t1 - t0)
                check(abs(area[j] - ngon) <= TOL * ngon, "%s: %s area %r, inscribed %d-gon %r" % (name, bname,
                                                                                                 area[j], segments,
                                                                                                 ngon))
                check(abs(signed_area(poly) - area[j]) <= TOL * area[j], "%s: %s area %r, its points' %r"
                      % (name, bname, area[j], signed_area(poly)))
                if bname == "disc" and segments == 48:
                    check(abs(area[j] - math.pi * r * r) <= 0.01 * math.pi * r * r,
                          "%s: 48-gon area %r not within 1 %% of pi r^2" % (name, area[j]))
        if k == len(series) - 1 and "triangle" in ids:  # the triangle turned: the poses are followed
            check(abs(q_angle(vq[ids["triangle"]]) - q_angle(q0[ids["triangle"]]) - 2.0 * STEPS * DT) <= 1e-6,
                  "triangle turned by %r, expected %r" % (q_angle(vq[ids["triangle"]]) - q_angle(q0[ids["triangle"]]),
                                                          2.0 * STEPS * DT))
    return result


def main():
    if len(sys.argv) != 3:
        print("usage: test_outlines.py <floe_cli_path> <tests_dir>", file=sys.stderr)
        sys.exit(2)
    cli = os.path.abspath(sys.argv[1])
    if not check(os.path.isfile(cli) and os.access(cli, os.X_OK), "floe CLI not found at %s" % cli):
        _finish("test_outlines")
    base = os.path.abspath("test_outlines_out")
    runs = {}
    for tag, outl, segs in (("ascii", "{type: outlines, every: %d, prefix: floes, ascii: true}" % EVERY, 48),
                            ("binary", "{type: outlines, every: %d, prefix: floes, segments: 12}" % EVERY, 12)):
        outdir = os.path.join(base, tag)
        rc, out = run_cli(cli, scene_text(outl), outdir)
        if not check(rc == 0, "%s run exited %s:\n%s" % (tag, rc, out[-3000:])):
            continue
        poses = [read_vtu(p) for _, p in read_series(outdir, "frame")]
        if tag == "binary":
            raw = open(sorted(glob.glob(os.path.join(outdir, "floes_*.vtu")))[0], "rb").read()
            check(b'format="appended"' in raw and b"<AppendedData" in raw, "binary run: no appended data")
        runs[tag] = check_run(outdir, segs, poses)
    if "ascii" in runs and "binary" in runs and check(len(runs["ascii"]) == len(runs["binary"]), "frame counts"):
        for k, (a, b) in enumerate(zip(runs["ascii"], runs["binary"])):
            curved = {2, 3}  # cells of the disc and the ellipse (in scene order: no wall cells)
            same = all(a[j] == b[j] for j in range(min(len(a), len(b))) if j not in curved)
            check(same and len(a) == len(b), "frame %d: the binary polygons differ from the ASCII ones" % k)

    # 3D: refused at creation
    outdir = os.path.join(base, "3d")
    rc, out = run_cli(cli, scene_3d("{type: outlines, every: 1}"), outdir)
    check(rc != 0, "a 3D scene with outlines ran (exit 0)")
    check("outlines is a 2D output (dimension: 2); use vtk in 3D" in out, "3D refusal message missing:\n%s"
          % out[-2000:])
    check(not glob.glob(os.path.join(outdir, "*.vtu")), "3D: frames written")
    if vtk is None:
        print("test_outlines: python3 VTK module not found: VTK's reader not tried")
    _finish("test_outlines")


if __name__ == "__main__":
    main()
