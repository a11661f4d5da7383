#!/usr/bin/env python3
"""test_mpi_cli.py - `floe run` under mpirun needs nothing else (docs/parallel.md).

Runs tests/mpi/settle.yaml (216 spheres and 24 boxes settling in a walled box, 6,667 steps)
with the MPI build's CLI on one process and under `mpirun -np K` (K = 2, 4), and
tests/scenes/vtk_small.yaml (18 spheres falling, few ghosts: a rank's particle count
changes at rebuilds) with K = 8, kinematic_wall.yaml (a moving wall, leapfrog) and
settle_2d.yaml (a 2D world) with K = 3, bonded.yaml (a block of beam-bonded spheres
breaking on the floor: 83 breaks) with K = 2 and 4, bonded_loose.yaml (the same block beside
loose spheres: a rank without bonds; the ranks' ghost records must agree) with K = 2,
bonded_2d.yaml (a bonded 2D plate: 184
breaks; floe_sizes reads the bonds gathered into rank 0's mirror) with K = 3, contacts.yaml
(spheres and boxes squeezed by a moving wall; the outputs that read contacts: stress of every
particle by steps and of the boxes by simulated time, the contacts' CSV in the serial list's
order, force chains, the walls' tracker; rank 0's mirror reads the contacts gathered from every
rank) with K = 2 and 4, adaptive.yaml (adaptive steps: 72 rejections in 8,558 trials, the
stress by simulated time) with K = 2 and 3, servo_rk2.yaml (servo.yaml under RK2, made here:
VARIANTS) with K = 2 and 3, and compares
every output file: the CSV files (particles, energy, tracker, written by rank 0) and every
number of every VTK frame (the vtk output's frames: a .pvtu and a piece per rank, read
together and ordered by id) must agree within 1e-9 of the column's (file's) largest magnitude
(a text column, the mode of a break in fracture_events.csv, must be equal): the split run
sums the contact forces in another order, nothing else differs.
settle.yaml also runs under -np 2 with --balance time (the cuts by measured speed), compared
the same way. The summary of settle.yaml under -np 2 carries the traffic line (floe_comm_stats): the mean
reverse traffic is 48 B x the mean ghosts per rank (within the printed digits, 0.5 %), the
ghost traffic between 72 and 312 B a ghost, the mean at most the largest rank's; and the
force time line (mean between the smallest and the largest). `--balance fast` is refused.

With SCENE:K1,K2 arguments after the folder, only those scenes (in TESTS_MPI_DIR) are run and
compared, under the ranks given (the traffic line is left out): test_mpi_servo, test_mpi_drag
and test_mpi_sea_ice (tests/CMakeLists.txt) run the force providers of
core/parallel/par_forcing.c that way. test_mpi_errors runs tests/mpi/errors.yaml and its
variants (FAILING): runs that fail inside a step must exit 1 on every rank with rank 0's one
error line equal to one process's (the particles by their index in the scene), without
MPI_Abort, and with the outputs up to the failure equal to one process's.

Usage: test_mpi_cli.py FLOE MPIEXEC TESTS_MPI_DIR [SCENE:K1,K2 ...]
"""
import atexit
import os
import re
import shutil
import subprocess
import sys
import tempfile

floe, mpiexec, here = sys.argv[1], sys.argv[2], sys.argv[3]
SCENES = [(os.path.join(here, "settle.yaml"), (2, 4)),
          (os.path.join(here, "..", "scenes", "vtk_small.yaml"), (8,)),
          (os.path.join(here, "kinematic_wall.yaml"), (3,)),
          (os.path.join(here, "settle_2d.yaml"), (3,)),
          (os.path.join(here, "bonded.yaml"), (2, 4)),
          (os.path.join(here, "bonded_loose.yaml"), (2,)),
          (os.path.join(here, "bonded_2d.yaml"), (3,)),
          (os.path.join(here, "contacts.yaml"), (2, 4)),
          (os.path.join(here, "adaptive.yaml"), (2, 3)),
          (os.path.join(here, "rk2_grow.yaml"), (2, 3)),
          (os.path.join(here, "rk2_adaptive.yaml"), (2,)),
          (os.path.join(here, "pd_pull.yaml"), (2, 3))]
# scenes made from another by a change of its text, written to a temporary folder: servo
# walls under RK2 (their controllers count the particles at the free particles' midpoint,
# summed over the ranks before the walls' motion; a half-length run: RK2 with the servo
# amplifies the sums' other order from 1e-16 to 1e-9 of the walls' scale by t = 0.03 s)
VARIANTS = {"servo_rk2.yaml": ("servo.yaml", lambda t: t.replace("time: {duration: 0.03, safety: 0.2}",
                                                                  "time: {duration: 0.015, safety: 0.2, integrator: rk2}"))}
SCENES.append((os.path.join(here, "servo_rk2.yaml"), (2, 3)))
# runs that fail inside a step (tests/mpi/errors.yaml; test_mpi_errors): exit 1 on every rank
# after the outputs end, one error line from rank 0 equal to one process's, no MPI_Abort;
# the outputs up to the failure compared as any other
FAILING = ("errors.yaml", "errors_motion.yaml", "errors_motion_lf.yaml", "errors_rk2.yaml", "errors_adaptive.yaml",
           "errors_lps.yaml", "errors_lps_g.yaml")
_hit = "velocity: [0, 0, -40]"
VARIANTS["errors_motion.yaml"] = ("errors.yaml", lambda t: t.replace(_hit, "velocity: [0, 0, -50]"))
# the same under leapfrog: its close's agreement rides with the energy watchdog's reduction
# too, and the ranks whose close passed put back its last step as one process leaves it
VARIANTS["errors_motion_lf.yaml"] = ("errors.yaml", lambda t: t.replace(_hit, "velocity: [0, 0, -50]").replace(
    "allow_unstable_dt: true}", "allow_unstable_dt: true, integrator: leapfrog}"))
VARIANTS["errors_rk2.yaml"] = ("errors.yaml", lambda t: t.replace("allow_unstable_dt: true}",
                                                                  "allow_unstable_dt: true, integrator: rk2}"))
VARIANTS["errors_adaptive.yaml"] = ("errors.yaml", lambda t: t.replace("allow_unstable_dt: true}",
                                                                       "allow_unstable_dt: true, adaptive: true}"))
# an LPS body beside (its dilatation exchange is a collective inside the force evaluation,
# which the failing rank must still reach)
VARIANTS["errors_lps.yaml"] = ("errors.yaml", lambda t: t.replace("outputs:", """peridynamics:
  - name: slab
    region: {box: {min: [0.0, 0.03, 0.0], max: [0.027, 0.036, 0.006]}}
    spacing: 0.003
    horizon: 2
    material: {model: lps, density: 1000, bulk_modulus: 1.0e4, shear_modulus: 5.0e3}
    contact_material: soft
outputs:""", 1))
# the same under gravity: the body forces' work of the failed step is booked as their stage
# runs (before the contacts fail), and stays on every rank as in one process, while the ranks
# whose evaluation passed put back the rest of what it booked (step.c forces_agreed; before,
# 1.1e-9 of the energy's scale off at -np 3). Gravity has x and y parts so that every force
# column has a scale (along z alone, fx and fy were round-off, 1e-16 N, compared to itself)
VARIANTS["errors_lps_g.yaml"] = ("errors.yaml", lambda t: VARIANTS["errors_lps.yaml"][1](t).replace(
    "time: {", "gravity: [-3.0, 2.0, -9.81]\ntime: {", 1))
if len(sys.argv) > 4:
    SCENES = [(os.path.join(here, a.split(":")[0]), tuple(int(k) for k in a.split(":")[1].split(",")))
              for a in sys.argv[4:]]
_vdir = tempfile.mkdtemp(prefix="floe_mpi_variants_")
atexit.register(shutil.rmtree, _vdir, True)
for i, (sc, ks) in enumerate(SCENES):
    v = VARIANTS.get(os.path.basename(sc))
    if v and not os.path.exists(sc):
        text = open(os.path.join(here, v[0])).read()
        made = v[1](text)
        if made == text:
            sys.exit(f"FAIL: the variant {os.path.basename(sc)} of {v[0]} was not made")
        SCENES[i] = (os.path.join(_vdir, os.path.basename(sc)), ks)
        open(SCENES[i][0], "w").write(made)
TOL = 1e-9
fails = 0


def run(scene, outdir, np_, extra=()):
    cmd = [floe, "run", scene, "-o", outdir, "-q"] + list(extra)
    if np_ > 1:
        cmd = [mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", str(np_)] + cmd
    failing = os.path.basename(scene) in FAILING
    try:  # (a failing run that never ends: the ranks did not agree on its failure)
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=120 if failing else 600)
    except subprocess.TimeoutExpired:
        sys.exit(f"FAIL: {' '.join(cmd)} did not end")
    if failing:
        errs = [ln for ln in r.stderr.splitlines() if ln.startswith("floe: error")]
        if (r.returncode != 1 or len(errs) != 1 or "MPI_ABORT" in r.stdout + r.stderr
                or f"outputs written so far are in {outdir}" not in r.stderr):
            print(r.stdout, r.stderr)
            sys.exit(f"FAIL: {' '.join(cmd)}: not one error line and exit 1 after the outputs (exit {r.returncode})")
        return errs[0]
    if r.returncode != 0:
        print(r.stdout, r.stderr)
        sys.exit(f"FAIL: {' '.join(cmd)} exited {r.returncode}")
    return None


def csv_rows(path):
    with open(path) as f:
        head = f.readline()
        return head, [[cell(v) for v in line.strip().split(",")] for line in f if line.strip()]


def cell(v):
    try:
        return float(v)
    except ValueError:
        return v


def compare_csv(a, b, name):
    global fails
    ha, ra = csv_rows(a)
    hb, rb = csv_rows(b)
    if ha != hb or len(ra) != len(rb):
        print(f"FAIL {name}: header or row count differs ({len(ra)} vs {len(rb)})")
        fails += 1
        return
    worst = 0.0
    cols = ha.strip().split(",")
    # energy.csv: every column in J against the largest energy of the file (the balance
    # error, a ratio of round-off, is left out); other files: each column's own scale
    joule = [c for c, h in enumerate(cols) if "[J]" in h]
    for c in range(len(ra[0]) if ra else 0):
        if name == "energy.csv" and c not in joule and c != 0:
            continue
        if any(isinstance(r[c], str) for r in ra + rb):  # text: equal
            worst = max(worst, 0.0 if [r[c] for r in ra] == [r[c] for r in rb] else float("inf"))
            continue
        scale = max(max(abs(r[c]) for r in ra), 1e-300)
        if c in joule:
            scale = max(max(abs(r[j]) for r in ra for j in joule), 1e-300)
        d = max(abs(x[c] - y[c]) for x, y in zip(ra, rb)) / scale
        worst = max(worst, d)
    ok = worst <= TOL
    fails += not ok
    print(f"  {'ok  ' if ok else 'FAIL'} {name}: {len(ra)} rows, largest difference {worst:.2e} of the column's scale (tol {TOL:g})")


def vtu_arrays(path):
    """the arrays of a .vtu, or of a .pvtu's pieces together (the vtk output under mpirun), the
    points in the order of their ids"""
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader, vtkXMLPUnstructuredGridReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
    r = vtkXMLPUnstructuredGridReader() if path.endswith(".pvtu") else vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    out = {"points": vtk_to_numpy(g.GetPoints().GetData())}
    pd = g.GetPointData()
    for k in range(pd.GetNumberOfArrays()):
        out[pd.GetArrayName(k)] = vtk_to_numpy(pd.GetArray(k))
    if "id" in out:
        order = out["id"].argsort(kind="stable")
        out = {k: v[order] for k, v in out.items()}
    return out


def compare_vtu(a, b, name):
    """largest difference over the arrays, each against its own largest magnitude"""
    global fails
    xa, xb = vtu_arrays(a), vtu_arrays(b)
    if sorted(xa) != sorted(xb) or any(xa[k].shape != xb[k].shape for k in xa):
        print(f"FAIL {name}: arrays differ")
        fails += 1
        return 0.0
    worst = 0.0
    for k in xa:
        sc = max(float(abs(xa[k]).max()) if xa[k].size else 0.0, 1e-300)
        if xa[k].size:
            worst = max(worst, float(abs(xa[k].astype(float) - xb[k].astype(float)).max()) / sc)
    return worst


def comm_line(name, subset, ppr_want=None):
    """`floe run` of tests/mpi/NAME under mpirun -np 2: its traffic line checked; subset: a
    step refreshes only the ghosts the lists read (True), or every ghost held (False: beam
    bonds, PD bodies). Returns the run's stdout (None when the line is missing)."""
    global fails
    scene = os.path.join(here, name)
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", "2", floe, "run", scene, "-o", tmp]
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    m = re.search(r"comm/step/rank: +([0-9.]+) B mean, ([0-9.]+) B max, ([0-9.]+) messages \(ghost ([0-9.]+), "
                  r"reverse ([0-9.]+), migrate ([0-9.]+), reduce ([0-9.]+), output ([0-9.]+) B\); "
                  r"ghosts/rank ([0-9.]+), particles/rank ([0-9.]+); ([0-9]+) rebuilds; refreshed ghosts/rank ([0-9.]+)",
                  r.stdout)
    if r.returncode != 0 or not m:
        print(r.stdout, r.stderr)
        print(f"FAIL: the traffic line of `floe run` {name} under mpirun -np 2")
        fails += 1
        return None
    mean, mx, msgs, gh, rev, mig, red, out, gpr, ppr, reb, fpr = (float(v) for v in m.groups())
    # a step refreshes the ghosts its list reads (fpr of the gpr held; all of them with beam
    # bonds or PD bodies): 72 B or more each and 48 B back; a rebuild sends every ghost held
    # (312 B, and a byte back with a subset). The line rounds rev to 1 B and fpr to 0.1
    ok = (mean <= mx and (0 < fpr < gpr if subset else fpr == gpr) and (ppr_want is None or ppr == ppr_want)
          and abs(rev - 48 * fpr) <= 0.005 * rev + 0.5 + 48 * 0.05
          and 72 * fpr * 0.995 <= gh <= 313 * gpr * 1.005 + 60 and reb > 0 and red >= 4)
    fails += not ok
    print(f"  {'ok  ' if ok else 'FAIL'} traffic line ({name}, {'the ghosts read' if subset else 'every ghost'}): "
          f"{m.group(0)}")
    return r.stdout


def check_comm_line():
    global fails
    scene = os.path.join(here, "settle.yaml")
    comm_line("drag.yaml", True)      # a provider that runs split refreshes the subset too
    comm_line("bonded.yaml", False)   # beam bonds: every ghost
    out = comm_line("settle.yaml", True, 120.0)
    if out is None:
        return
    # outputs: reduced and gathered ones are counted
    m = re.search(r"output ([0-9.]+) B\)", out)
    ok = bool(m) and float(m.group(1)) > 0
    fails += not ok
    print(f"  {'ok  ' if ok else 'FAIL'} output traffic counted: {m.group(0) if m else out}")
    # the ranks' force time: mean between the smallest and the largest, their ratio printed
    m = re.search(r"force time/rank: +([0-9.]+) s mean, ([0-9.]+) s max, ([0-9.]+) s min \(max/mean ([0-9.]+)", out)
    ok = bool(m) and 0 < float(m.group(3)) <= float(m.group(1)) <= float(m.group(2)) and float(m.group(4)) >= 1.0
    fails += not ok
    print(f"  {'ok  ' if ok else 'FAIL'} force time line: {m.group(0) if m else out}")
    # --balance takes weights or time, nothing else
    r = subprocess.run([floe, "run", scene, "--balance", "fast"], capture_output=True, text=True, timeout=60)
    ok = r.returncode == 2 and "--balance takes 'weights' or 'time'" in r.stderr
    fails += not ok
    print(f"  {'ok  ' if ok else 'FAIL'} --balance fast refused: exit {r.returncode}, {r.stderr.strip()}")


if len(sys.argv) <= 4:
    check_comm_line()
for scene, ranks in SCENES:
  with tempfile.TemporaryDirectory() as tmp:
    ref = os.path.join(tmp, "np1")
    err1 = run(scene, ref, 1)
    # settle.yaml at -np 2 also under --balance time (cuts by the ranks' measured speeds)
    variants = [(k, ()) for k in ranks]
    if len(sys.argv) <= 4 and os.path.basename(scene) == "settle.yaml":
        variants.append((2, ("--balance", "time")))
    for k, extra in variants:
        out = os.path.join(tmp, f"np{k}{'_'.join(extra)}")
        errk = run(scene, out, k, extra)
        print(f"{os.path.basename(scene)}: mpirun -np {k} {' '.join(extra)} against one process:")
        if err1 is not None:
            ok = errk == err1
            fails += not ok
            print(f"  {'ok  ' if ok else 'FAIL'} the error: {errk}" + ("" if ok else f" (one process: {err1})"))
        files = sorted(os.listdir(ref))
        # the vtk output under mpirun: PREFIX_NNNNNN.pvtu and a piece per rank for each serial
        # PREFIX_NNNNNN.vtu (test_mpi_pvtu.py checks the pieces themselves)
        par = {n[:-len(".pvtu")] + ".vtu" for n in os.listdir(out) if n.endswith(".pvtu")}
        pieces = {n for n in os.listdir(out) for f in par if re.fullmatch(re.escape(f[:-4]) + r"_\d+\.vtu", n)}
        got = sorted((set(os.listdir(out)) - pieces - {f[:-4] + ".pvtu" for f in par}) | par)
        if got != files:
            print(f"FAIL: files differ: {got} vs {files}")
            fails += 1
        for name in files:
            if name.endswith(".csv"):
                compare_csv(os.path.join(ref, name), os.path.join(out, name), name)
        try:
            import vtkmodules.vtkIOXML  # noqa: F401 (python3-vtk9)
        except ImportError:
            print("  (no python3-vtk9: the VTK frames are not compared)")
            continue
        vtus = [n for n in files if n.endswith(".vtu")]
        if not vtus:
            continue
        worst = max(compare_vtu(os.path.join(ref, n), os.path.join(out, n if n not in par else n[:-4] + ".pvtu"), n)
                    for n in vtus)
        ok = worst <= TOL
        fails += not ok
        print(f"  {'ok  ' if ok else 'FAIL'} {len(vtus)} VTK files: largest difference {worst:.2e} of the file's scale (tol {TOL:g})")
print(f"test_mpi_cli: {fails} failed")
sys.exit(1 if fails else 0)
