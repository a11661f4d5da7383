#!/usr/bin/env python3
"""test_vtk.py - run the floe CLI on tests/scenes/vtk_small.yaml and read its VTK output
back with VTK 9 (vtkXMLUnstructuredGridReader; the .pvd is parsed as XML).

usage: python3 tests/test_vtk.py <floe_cli_path> <tests_dir>

Checks: the .pvd lists the frames with strictly increasing times from 0 to the duration;
every frame loads without VTK errors or warnings, has one VTK_VERTEX cell per sphere (the
wall is left out), the arrays id / radius / velocity / angular_velocity / force / body /
material / orientation with the right number of components, finite values, ids that are
the consecutive particle indices of the spheres, unit quaternions, TimeValue equal to the
.pvd timestep, and free fall of the top layer (vz = -g t) before anything touches it.
Also the energy CSV the scene asks for (found by its header). Prints "N passed, N failed".
"""
import csv
import glob
import math
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

# python3-vtk9 is a Debian package: when the python3 on PATH is another interpreter
# (pyenv, venv) without it, re-run under the system one.
try:
    import vtk  # noqa: F401
except ImportError:
    if os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3") \
            and os.path.exists("/usr/bin/python3") and not os.environ.get("FLOE_TEST_VTK_REEXEC"):
        os.environ["FLOE_TEST_VTK_REEXEC"] = "1"
        os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
    vtk = None

N_SPHERES = 3 * 3 * 2
N_WALLS = 1
RADIUS = 0.001
DURATION = 0.01
DT = 1.0e-5
G = 9.81
EXPECTED_ARRAYS = {"id": 1, "radius": 1, "velocity": 3, "angular_velocity": 3, "force": 3,
                   "body": 1, "material": 1, "orientation": 4}

from pycheck import check, finish as _finish


def finish():
    _finish("test_vtk")


def read_vtu(path):
    """Returns (grid, messages) where messages are VTK errors/warnings raised while reading."""
    messages = []
    reader = vtk.vtkXMLUnstructuredGridReader()

    def on_event(obj, event):
        messages.append(event)

    reader.AddObserver("ErrorEvent", on_event)
    reader.AddObserver("WarningEvent", on_event)
    reader.SetFileName(path)
    reader.Update()
    if reader.GetErrorCode() != 0:
        messages.append("error code %d" % reader.GetErrorCode())
    return reader.GetOutput(), messages


def array_values(arr):
    n, c = arr.GetNumberOfTuples(), arr.GetNumberOfComponents()
    return [[arr.GetComponent(t, k) for k in range(c)] for t in range(n)]


def check_frame(path, t_pvd, is_last):
    grid, messages = read_vtu(path)
    name = os.path.basename(path)
    check(not messages, "%s: VTK reported %s" % (name, messages))
    n = grid.GetNumberOfPoints()
    check(n == N_SPHERES, "%s: %d points, expected %d" % (name, n, N_SPHERES))
    check(grid.GetNumberOfCells() == n, "%s: %d cells for %d points" % (name, grid.GetNumberOfCells(), n))
    types = {grid.GetCellType(k) for k in range(grid.GetNumberOfCells())}
    check(types <= {1}, "%s: cell types %s, expected VTK_VERTEX (1)" % (name, types))
    pts = [list(grid.GetPoint(k)) for k in range(n)]
    check(all(math.isfinite(v) for p in pts for v in p), "%s: non-finite point" % name)

    pd = grid.GetPointData()
    arrays = {}
    for aname, ncomp in EXPECTED_ARRAYS.items():
        arr = pd.GetArray(aname)
        if not check(arr is not None, "%s: array %s missing" % (name, aname)):
            continue
        check(arr.GetNumberOfComponents() == ncomp,
              "%s: %s has %d components, expected %d" % (name, aname, arr.GetNumberOfComponents(), ncomp))
        check(arr.GetNumberOfTuples() == n, "%s: %s has %d tuples" % (name, aname, arr.GetNumberOfTuples()))
        vals = array_values(arr)
        check(all(math.isfinite(v) for row in vals for v in row), "%s: %s not finite" % (name, aname))
        arrays[aname] = vals

    if "id" in arrays:
        ids = [int(r[0]) for r in arrays["id"]]
        lo = min(ids) if ids else 0
        # spheres are the particles that are not walls: ids 0..n-1, or shifted by the wall
        # count when the scene adds the walls first
        check(sorted(ids) == list(range(lo, lo + N_SPHERES)) and lo in (0, N_WALLS),
              "%s: ids %s are not consecutive particle indices" % (name, sorted(ids)))
    if "radius" in arrays:
        check(all(abs(r[0] - RADIUS) <= 1e-12 for r in arrays["radius"]), "%s: radius != %g" % (name, RADIUS))
    if "orientation" in arrays:
        check(all(abs(sum(c * c for c in q) - 1.0) < 1e-9 for q in arrays["orientation"]),
              "%s: orientation not unit quaternions" % name)
    if "material" in arrays:
        check(len({r[0] for r in arrays["material"]}) == 1, "%s: one material expected" % name)
    if "body" in arrays:
        check(all(float(r[0]).is_integer() for r in arrays["body"]), "%s: body not integer" % name)

    fd = grid.GetFieldData()
    tv = fd.GetArray("TimeValue") if fd is not None else None
    if check(tv is not None, "%s: TimeValue field data missing" % name):
        check(abs(tv.GetComponent(0, 0) - t_pvd) <= 1e-12 * max(1.0, abs(t_pvd)),
              "%s: TimeValue %r != pvd timestep %r" % (name, tv.GetComponent(0, 0), t_pvd))

    # free fall: the top layer touches nothing during the run (gaps between layers stay
    # open), so vz = -g t there (velocity Verlet is exact for constant acceleration)
    if "velocity" in arrays and pts:
        ztop = max(p[2] for p in pts)
        top = [arrays["velocity"][k][2] for k in range(n) if pts[k][2] > ztop - 0.5 * RADIUS]
        vz = sum(top) / len(top)
        check(abs(vz - (-G * t_pvd)) <= 1e-3 * G * DURATION,
              "%s: top layer vz %g, expected %g (free fall)" % (name, vz, -G * t_pvd))
    if is_last:
        check(all(p[2] > 0 for p in pts), "%s: a sphere centre is below the floor" % name)


def check_energy_csv(outdir):
    found = None
    for path in glob.glob(os.path.join(outdir, "**", "*.csv"), recursive=True):
        with open(path, newline="") as f:
            header = f.readline()
        if header.startswith("t [s],kinetic_trans"):
            found = path
    if not check(found is not None, "no energy CSV (header 't [s],kinetic_trans...') in %s" % outdir):
        return
    with open(found, newline="") as f:
        rows = list(csv.reader(f))
    header, data = rows[0], rows[1:]
    check(len(header) == 9 and header[-1] == "balance_error", "energy header %s" % header)
    check(len(data) >= int(DURATION / DT / 100), "energy: %d rows for every 100 steps" % len(data))
    vals = [[float(v) for v in r] for r in data]
    check(all(math.isfinite(v) for r in vals for v in r), "energy: non-finite value")
    ts = [r[0] for r in vals]
    check(all(b > a for a, b in zip(ts, ts[1:])), "energy: times not increasing")


PERIODIC = """
dimension: 3
time: {duration: 0.25, dt: 1.0e-4}
gravity: [0, 0, 0]
materials: [{name: g, density: 1000}]
laws: [{materials: [g, g], model: viscoelastic, kn: 1.0e3, ks: 5.0e2, gn: 0, gs: 0, friction: 0}]
cell: {size: [0.1, 0.1, 0.1]}
bodies:
  - {packing: random, shape: {sphere: {radius: 0.004}}, material: g, count: 8, velocity: [1.0, 0.5, -0.3],
     region: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}, seed: 5}
outputs:
  - {type: vtk, every: 500, prefix: frame}
"""


def check_periodic(cli):
    """In a periodic cell (fixed, 0.1 m) the vtk output writes the points wrapped into the
    cell and their integer image n: Points + L n is the unwrapped position, which for spheres
    drifting at a constant velocity across the faces (8 spheres at (1, 0.5, -0.3) m/s for
    0.25 s: 2.5 cell widths in x) moves by v t exactly (to round-off)."""
    outdir = os.path.abspath("test_vtk_periodic_out")
    shutil.rmtree(outdir, ignore_errors=True)
    os.makedirs(outdir)
    scene = os.path.join(outdir, "periodic.yaml")
    with open(scene, "w") as f:
        f.write(PERIODIC)
    proc = subprocess.run([cli, "run", scene, "-o", os.path.join(outdir, "out")], stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, timeout=600, universal_newlines=True)
    if not check(proc.returncode == 0, "periodic: floe run exited %s:\n%s" % (proc.returncode, proc.stdout[-3000:])):
        return
    frames = sorted(glob.glob(os.path.join(outdir, "out", "frame_*.vtu")))
    if not check(len(frames) >= 2, "periodic: frames written (%d)" % len(frames)):
        return
    L, v, t_end = 0.1, (1.0, 0.5, -0.3), 0.25

    def read(path):
        grid, msgs = read_vtu(path)
        check(not msgs, "periodic: %s reads without VTK messages (%s)" % (path, msgs))
        pts = grid.GetPoints()
        img = grid.GetPointData().GetArray("image")
        if not check(img is not None and img.GetNumberOfComponents() == 3, "periodic: an image array (3 ints)"):
            return None
        n = grid.GetNumberOfPoints()
        return [(pts.GetPoint(i), img.GetTuple3(i)) for i in range(n)]

    first, last = read(frames[0]), read(frames[-1])
    if first is None or last is None:
        return
    inside = all(0 <= x[c] < L for x, _ in first + last for c in range(3))
    check(inside, "periodic: every point wrapped into the cell [0, 0.1)^3")
    crossed = sum(1 for _, n in last if any(n))
    check(crossed == len(last), "periodic: every sphere has left the cell at least once (%d of %d)" % (crossed, len(last)))
    worst = 0.0
    for (x0, n0), (x1, n1) in zip(first, last):
        for c in range(3):
            u0, u1 = x0[c] + L * n0[c], x1[c] + L * n1[c]
            worst = max(worst, abs((u1 - u0) - v[c] * t_end))
    check(worst < 1e-9, "periodic: unwrapped displacement = v t to %.2e m (< 1e-9)" % worst)
    print("  periodic vtk: %d points wrapped, displacement error %.2e m" % (len(last), worst))


def main():
    if len(sys.argv) != 3:
        print("usage: test_vtk.py <floe_cli_path> <tests_dir>", file=sys.stderr)
        sys.exit(2)
    cli, tests_dir = sys.argv[1], sys.argv[2]
    if not check(vtk is not None, "python3 VTK module not found (install python3-vtk9)"):
        finish()
    if not check(os.path.isfile(cli) and os.access(cli, os.X_OK), "floe CLI not found at %s" % cli):
        finish()
    scene = os.path.join(tests_dir, "scenes", "vtk_small.yaml")
    outdir = os.path.abspath("test_vtk_out")
    shutil.rmtree(outdir, ignore_errors=True)
    try:
        proc = subprocess.run([cli, "run", scene, "-o", outdir], stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, timeout=600, universal_newlines=True)
        out, rc = proc.stdout, proc.returncode
    except subprocess.TimeoutExpired:
        out, rc = "timeout", -1
    if not check(rc == 0, "floe run exited %s:\n%s" % (rc, out[-3000:])):
        finish()

    pvds = sorted(glob.glob(os.path.join(outdir, "**", "*.pvd"), recursive=True))
    if not check(len(pvds) == 1, "expected one .pvd in %s, found %s" % (outdir, pvds)):
        finish()
    pvd = pvds[0]
    try:
        root = ET.parse(pvd).getroot()
    except ET.ParseError as e:
        check(False, "%s is not valid XML: %s" % (pvd, e))
        finish()
    check(root.tag == "VTKFile" and root.get("type") == "Collection", "pvd root %s %s" % (root.tag, root.attrib))
    datasets = root.findall("./Collection/DataSet")
    times = [float(d.get("timestep")) for d in datasets]
    nsteps = int(round(DURATION / DT))
    # frames at steps 0, 200, ..., 1000 (and possibly a final one at the end of the run)
    check(nsteps // 200 + 1 <= len(datasets) <= nsteps // 200 + 2,
          "pvd lists %d frames, expected %d" % (len(datasets), nsteps // 200 + 1))
    check(all(b > a for a, b in zip(times, times[1:])), "pvd times not increasing: %s" % times)
    check(bool(times) and times[0] == 0.0, "first frame at t = 0: %s" % times[:1])
    check(bool(times) and abs(times[-1] - DURATION) <= 1.5 * DT, "last frame at t = %s" % times[-1:])
    files = [os.path.join(os.path.dirname(pvd), d.get("file")) for d in datasets]
    check(len(set(files)) == len(files), "pvd repeats a file")
    for k, (path, t) in enumerate(zip(files, times)):
        if check(os.path.isfile(path), "frame file %s missing" % path):
            check_frame(path, t, k == len(files) - 1)
    check_energy_csv(outdir)
    check_periodic(cli)
    finish()


if __name__ == "__main__":
    main()
