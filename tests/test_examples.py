#!/usr/bin/env python3
"""test_examples.py - the example scenes stay valid and the small one reproduces its figure.

usage: python3 tests/test_examples.py <floe_cli_path> <tests_dir>

- `floe check` accepts every examples/*/scene.yaml (the RVE builds its 16,483 spheres).
- examples/dilating-sphere (ParticLS §5.2, Fig. 6) runs to t = 3 s: the middle sphere's six
  neighbours are pushed outward (each ends farther than R(t=3) = 3.1 m from the centre
  particle's position, while starting in contact at 0.2 m), the energy ledger closes
  (balance_error < 1e-3), and the cluster stays in the plane (z = 0).
Prints "N passed, N failed".
"""
import csv
import glob
import math
import os
import shutil
import subprocess
import sys
import tempfile

from pycheck import check, finish


def main():
    cli, tests = sys.argv[1], sys.argv[2]
    root = os.path.dirname(os.path.abspath(tests))
    scenes = sorted(glob.glob(os.path.join(root, "examples", "*", "scene.yaml")))
    check(len(scenes) >= 2, "example scenes found: %d" % len(scenes))
    for sc in scenes:
        p = subprocess.run([cli, "check", sc], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           universal_newlines=True, timeout=300)
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
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("test_examples")


if __name__ == "__main__":
    main()
