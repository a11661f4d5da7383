#!/usr/bin/env python3
"""test_extending.py - the one-file components of docs/extending.md ("A PD material", "A force
provider", "A packing"), compiled against the INSTALLED headers as plugins and named in
scenes (tests/extending/):

  - spring_material.c (PD material `spring_bond`): a two-point PD body, point 0 fixed, point
    1 pulled by gravity g along x through one spring bond k: x1(t) - x1(0) =
    (m g / k)(1 - cos(sqrt(k/m) t)) at every tracked sample within 1e-3 of the amplitude
    2 m g / k (velocity Verlet at w dt = 1e-3: phase error ~1e-7);
  - anchor_force.c (force provider `anchor`): a sphere released at x = A on the tether
    F = -k x oscillates as A cos(sqrt(k/m) t) (within 1e-3 A at every sample), the fixed
    beads do not move, and the provider's stored energy closes the energy balance
    (balance_error column below 1e-6);
  - the same scene under `mpirun -np 2` (an MPI build): the anchor's class declares
    per-particle forces (version 2, .splits), so the split world runs it: its tracker and
    energy files are the same bytes as one process's; and so they are after a checkpoint
    written under 2 ranks (t = 0.14 s) and a restart from it under 2 ranks (a row appended
    to each file after the run, which the restart must cut off, and a digit changed in a row
    before the checkpoint, which it must keep);
  - line_packing.c (packing `line`): five beads at x = 0, 0.05, ..., 0.2 (exact to 1e-12 m);
  - `floe help pd_material spring_bond`, `floe help provider anchor` and `floe help packing
    line` print the plugins' schemas; a misspelt plugin key is refused with its line and
    the closest key.

usage: python3 tests/test_extending.py <floe_cli_path> <tests_dir>
"""
import csv
import math
import os
import shutil
import subprocess
import sys
import tempfile

from pycheck import check, finish, run


def rows(path):
    r = list(csv.reader(open(path)))
    return r[0], [[float(v) for v in x] for x in r[1:]]


def main():
    if len(sys.argv) != 3:
        print("usage: test_extending.py <floe_cli_path> <tests_dir>", file=sys.stderr)
        sys.exit(2)
    cli, tests = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    build = os.path.dirname(cli)
    src = os.path.join(tests, "extending")
    cc = shutil.which("cc") or shutil.which("gcc")
    if not check(cc is not None, "no C compiler (cc) on PATH"):
        finish("test_extending")
    tmp = tempfile.mkdtemp(prefix="floe_test_extending_")
    try:
        prefix = os.path.join(tmp, "prefix")
        rc, out, err = run(["cmake", "--install", build, "--prefix", prefix])
        if not check(rc == 0, "cmake --install: exit %d\n%s%s" % (rc, out, err)):
            finish("test_extending")
        floe = os.path.join(prefix, "bin", "floe")
        inc = os.path.join(prefix, "include", "floe")
        wd = os.path.join(tmp, "run")
        os.makedirs(wd)
        for name in ("spring_material", "anchor_force", "line_packing"):
            rc, out, err = run([cc, "-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-shared", "-fPIC", "-o",
                                os.path.join(wd, name + ".so"), os.path.join(src, name + ".c"), "-I" + inc])
            check(rc == 0, "%s.c builds against the installed headers: exit %d\n%s" % (name, rc, err))
        for name in ("spring_bar.yaml", "anchored.yaml"):
            shutil.copy(os.path.join(src, name), wd)

        # ---- the PD material: one spring bond, point 0 fixed, gravity along x ----
        rc, out, err = run([floe, "run", "spring_bar.yaml", "-o", "bar", "-q"], cwd=wd)
        if check(rc == 0, "floe run spring_bar.yaml: exit %d\n%s" % (rc, err)):
            _, r = rows(os.path.join(wd, "bar", "bar.csv"))
            m, g, k = 1000 * 0.01 ** 3, 10.0, 10.0
            om, x0 = math.sqrt(k / m), r[0][2]
            worst = max(abs((x[2] - x0) - m * g / k * (1 - math.cos(om * x[0]))) for x in r)
            ext = max(x[2] - x0 for x in r)
            check(worst < 1e-3 * 2 * m * g / k and len(r) > 100,
                  "spring_bond: x1 - x1(0) = (m g/k)(1 - cos w t): worst error %.3g m (tol %.3g m, %d samples)"
                  % (worst, 1e-3 * 2 * m * g / k, len(r)))
            print("  spring_bond: max extension %.6g m (2 m g / k = %.6g m), worst error %.3g m" %
                  (ext, 2 * m * g / k, worst))

        # ---- the force provider and the packing ----
        rc, out, err = run([floe, "run", "anchored.yaml", "-o", "anc", "-q"], cwd=wd)
        if check(rc == 0, "floe run anchored.yaml: exit %d\n%s" % (rc, err)):
            _, r = rows(os.path.join(wd, "anc", "anchored.csv"))
            m, k, A = 1000 * 4.0 / 3.0 * math.pi * 0.01 ** 3, 4.0, 0.1
            om = math.sqrt(k / m)
            s = [x for x in r if int(x[1]) == 0]
            worst = max(abs(x[2] - A * math.cos(om * x[0])) for x in s)
            check(worst < 1e-3 * A and s[-1][0] > math.pi / om,
                  "anchor: x = A cos(sqrt(k/m) t) over a half period: worst error %.3g m (tol %.3g m)" %
                  (worst, 1e-3 * A))
            print("  anchor: x at the last sample %.6g m (A cos w t = %.6g m), worst error %.3g m" %
                  (s[-1][2], A * math.cos(om * s[-1][0]), worst))
            beads = {int(x[1]): x[2] for x in r if int(x[1]) != 0}
            check(abs(beads.get(1, 9) - 0.0) < 1e-12 and abs(beads.get(5, 9) - 0.2) < 1e-12,
                  "line packing: beads 1 and 5 at x = 0 and 0.2 (got %r)" % beads)
            head, e = rows(os.path.join(wd, "anc", "energy.csv"))
            bal = max(abs(x[head.index("balance_error")]) for x in e)
            el = max(x[head.index("elastic [J]")] for x in e)
            check(bal < 1e-6 and abs(el - 0.5 * k * A * A) < 1e-6 * 0.5 * k * A * A,
                  "anchor: its stored energy (max %.9g J, k A^2/2 = %.9g J) closes the balance (error %.3g, tol 1e-6)"
                  % (el, 0.5 * k * A * A, bal))
        # ---- the provider under mpirun (an MPI build): its class declares per-particle forces
        # (floe_provider.h, version 2), so the split world runs it; the same bytes as one process ----
        cache = os.path.join(build, "CMakeCache.txt")
        mpi_build = os.path.exists(cache) and "FLOE_WITH_MPI:BOOL=ON" in open(cache).read()
        mpiexec = shutil.which("mpirun")
        if mpi_build and mpiexec and os.path.exists(os.path.join(wd, "anc", "anchored.csv")):
            rc, out, err = run([mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", "2", floe, "run",
                                "anchored.yaml", "-o", "anc2", "-q"], cwd=wd)
            if check(rc == 0, "mpirun -np 2 floe run anchored.yaml: exit %d\n%s%s" % (rc, out, err)):
                for f in ("anchored.csv", "energy.csv"):
                    same = open(os.path.join(wd, "anc", f), "rb").read() == open(os.path.join(wd, "anc2", f), "rb").read()
                    check(same, "anchor under mpirun -np 2: %s differs from one process's" % f)
                print("  anchor under mpirun -np 2: anchored.csv and energy.csv the same bytes as one process's")
            # a checkpoint written under 2 ranks (every 0.07 s: the file holds t = 0.14 s) and the
            # run restarted from it under 2 ranks in the same folder: the outputs cut back to the
            # checkpoint and continued, the same bytes as one process's uninterrupted run
            rc, out, err = run([mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", "2", floe, "run",
                                "anchored.yaml", "-o", "anc3", "-q", "--checkpoint-every", "0.07"], cwd=wd)
            ck = os.path.join(wd, "anc3", "checkpoint.bin")
            if check(rc == 0 and os.path.exists(ck), "mpirun -np 2 floe run --checkpoint-every 0.07: exit %d, "
                     "checkpoint %s\n%s%s" % (rc, "written" if os.path.exists(ck) else "missing", out, err)):
                # a row appended after the run, which the restart must cut off (a restart that
                # wrote nothing would leave it), and one digit changed in the 11th row, before the
                # checkpoint, which the restart must keep (a run from t = 0 would write it again)
                want = {}
                for f in ("anchored.csv", "energy.csv"):
                    path = os.path.join(wd, "anc3", f)
                    b = bytearray(open(path, "rb").read())
                    at = [i for i, c in enumerate(b) if c == ord("\n")][10] - 1
                    b[at] = ord("1") if b[at] != ord("1") else ord("2")
                    w = bytearray(open(os.path.join(wd, "anc", f), "rb").read())
                    w[at] = b[at]
                    want[f] = bytes(w)
                    open(path, "wb").write(bytes(b) + b"0.2,9,9,9\n")
                rc, out, err = run([mpiexec, "--allow-run-as-root", "--oversubscribe", "-np", "2", floe, "run",
                                    "anchored.yaml", "-o", "anc3", "-q", "--restart", ck], cwd=wd)
                if check(rc == 0, "mpirun -np 2 floe run --restart: exit %d\n%s%s" % (rc, out, err)):
                    ok = True
                    for f in ("anchored.csv", "energy.csv"):
                        same = want[f] == open(os.path.join(wd, "anc3", f), "rb").read()
                        ok = check(same, "anchor restarted under mpirun -np 2: %s differs from one process's (with "
                                   "the changed digit before the checkpoint)" % f) and ok
                    if ok:
                        print("  anchor restarted under mpirun -np 2 from t = 0.14 s: the same bytes as one process's")
        else:
            print("  anchor under mpirun: skipped (%s)" % ("no mpirun on PATH" if mpi_build else "not an MPI build"))
        rc, out, err = run([floe, "check", "anchored.yaml"], cwd=wd)
        check(rc == 0 and "particles:  6 (" in out and "body 1: particles 1..5" in out and "forces:     anchor" in out,
              "floe check anchored.yaml: 6 particles (a sphere and 5 beads), the anchor force:\n%s%s" % (out, err))

        # ---- help and errors ----
        for kind, name, plugin, word in (("pd_material", "spring_bond", "spring_material.so", "stiffness of every bond"),
                                         ("provider", "anchor", "anchor_force.so", "tether stiffness"),
                                         ("packing", "line", "line_packing.so", "evenly spaced")):
            rc, out, err = run([floe, "help", kind, name, "--plugin", "./" + plugin], cwd=wd)
            check(rc == 0 and word in out, "floe help %s %s --plugin: exit %d\n%s%s" % (kind, name, rc, out, err))
        text = open(os.path.join(src, "anchored.yaml")).read()
        bad = text.replace("{type: anchor, point: [0, 0, 0], k: 4}", "{type: anchor, point: [0, 0, 0], kk: 4}")
        with open(os.path.join(wd, "bad.yaml"), "w") as f:
            f.write(bad)
        line = [i + 1 for i, l in enumerate(bad.splitlines()) if "kk: 4" in l][0]
        rc, out, err = run([floe, "check", "bad.yaml"], cwd=wd)
        check(rc == 1 and ("bad.yaml:%d:" % line) in err and "unknown key 'kk'" in err and "did you mean 'k'" in err,
              "a misspelt key of a plugin provider: exit %d, %s" % (rc, err))
        text = open(os.path.join(src, "spring_bar.yaml")).read()
        bad = text.replace("model: spring_bond, density: 1000, k: 10", "model: spring_bond, density: 1000, k: -10")
        with open(os.path.join(wd, "badk.yaml"), "w") as f:
            f.write(bad)
        rc, out, err = run([floe, "check", "badk.yaml"], cwd=wd)
        check(rc == 1 and "peridynamics[0].material.k must be > 0 (N/m)" in err,
              "a bad plugin PD material parameter: exit %d, %s" % (rc, err))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("test_extending")


if __name__ == "__main__":
    main()
