#!/usr/bin/env python3
"""test_overlap_scene.py - the overlap-area law through a scene (tests/scenes/overlap_floes.yaml):
two 2 km square floes meeting edge on edge, off-centre, frictionless and undamped, must keep
their kinetic energy (after the contact, within 1e-4); a law for spheres is refused with a
message naming the law and the particles.

usage: python3 tests/test_overlap_scene.py <floe_cli_path> <tests_dir>
Prints "N passed, N failed"."""
import csv
import os
import subprocess
import sys
import tempfile

cli, tests = sys.argv[1], sys.argv[2]
passed = failed = 0


def check(cond, what):
    global passed, failed
    if cond:
        passed += 1
    else:
        failed += 1
        print("FAIL:", what)


with tempfile.TemporaryDirectory() as out:
    scene = os.path.join(tests, "scenes", "overlap_floes.yaml")
    r = subprocess.run([cli, "run", "-q", scene, "-o", out], capture_output=True, text=True)
    check(r.returncode == 0, "overlap_floes runs: " + r.stderr)
    rows = list(csv.DictReader(open(os.path.join(out, "energy.csv"))))
    e0 = float(rows[0]["kinetic_trans [J]"]) + float(rows[0]["kinetic_rot [J]"])
    e1 = float(rows[-1]["kinetic_trans [J]"]) + float(rows[-1]["kinetic_rot [J]"])
    el = float(rows[-1]["elastic [J]"])
    rot_gain = float(rows[-1]["kinetic_rot [J]"]) - float(rows[0]["kinetic_rot [J]"])
    print("  kinetic energy before %.9g J, after %.9g J (rel %.2e), elastic after %g, rotation gained %.3g J"
          % (e0, e1, abs(e1 - e0) / e0, el, rot_gain))
    check(el == 0, "the floes separated (elastic energy 0 at the end)")
    check(rot_gain > 0.1 * e0, "the off-centre hit spins the floes (rotational energy gained %.3g J)" % rot_gain)
    check(abs(e1 - e0) <= 1e-4 * e0, "energy conserved within 1e-4: %.3g" % (abs(e1 - e0) / e0))

    bad = os.path.join(out, "spheres.yaml")
    with open(bad, "w") as f:
        f.write("""dimension: 2
time: {duration: 0.01}
gravity: [0, 0]
materials: [{name: m, density: 1000}]
laws: [{materials: [m, m], model: overlap_area, stiffness: 1.0e6}]
bodies:
  - {material: m, position: [0, 0], shape: {sphere: {radius: 0.1}}}
  - {material: m, position: [0.15, 0], shape: {sphere: {radius: 0.1}}}
""")
    r = subprocess.run([cli, "run", "-q", bad, "-o", out], capture_output=True, text=True)
    msg = r.stdout + r.stderr
    print("  spheres under overlap_area:", msg.strip().splitlines()[-1] if msg.strip() else "(no message)")
    check(r.returncode != 0 and "overlap_area" in msg and "polytopes" in msg and "particles 0 and 1" in msg,
          "overlap_area on spheres refused naming the law and the particles")

print("%d passed, %d failed" % (passed, failed))
sys.exit(1 if failed else 0)
