#!/usr/bin/env python3
"""test_threads_cli.py - `floe run -t N` (issue 14, docs/parallel.md): the output files of a
run are the same, byte for byte, for 1, 2 and 3 threads (every file the scene writes, and the
checkpoint).

usage: python3 tests/test_threads_cli.py <floe_cli_path> <tests_dir>

Scenes (each with more than the 2,048 pairs and particles above which the loops run
threaded):
  - walled: 1,440 spheres of ParticLS 5.3's HCP packing (smaller box) under the linear
    viscoelastic law (its dashpot reads the last accelerations), the top wall pressing down
    (kinematic), outputs vtk, csv, energy, tracker of the wall, stress, contacts and
    force_chains (the recorded steps run on one thread, the others threaded);
  - periodic: the same packing in a periodic cell shortened along z (image pairs, the
    cell's virial and the stress output);
  - settle: 2,500 random spheres of two sizes falling on a floor, Hertz-Mindlin with
    friction (history across list rebuilds), a linear drag, energy and vtk outputs;
  - sea ice: 2,600 polygon floes driven by a wind, an ocean vortex (its drag integrated
    every 3 steps and held between) and Coriolis with the sea-surface tilt, Hopkins
    contacts: the forcing providers' particle loops run threaded;
  - walled-rk2: the walled scene under RK2 for 120 steps (two force evaluations a step);
  - settle-rk2: the settling spheres under RK2 (its particle loops on the threads: 2,500
    particles, above the loops' grain);
  - pd-staggered: tests/mpi/pd.yaml's struck disc at a finer spacing (3,542 PD points) under
    the staggered PD-DEM scheme with 2 sub-steps (its particle loops on the threads), and
    with F_PD every 2 steps; pd-pull-staggered: tests/mpi/pd_pull.yaml with 3,072 spheres
    (its kinematic PD points' motion callbacks), 2 sub-steps.
Each run, restarted on 2 threads from its last checkpoint, ends with the same files.
Also: -t 0 and -t x are refused (exit 2). Prints "N passed, N failed"."""
import filecmp
import os
import shutil
import sys
import tempfile

from pycheck import check, counts, finish, run

WALLED = """name: threads-walled
dimension: 3
time: {duration: 0.015, dt: 5.0e-5}
gravity: [0, 0, 0]
materials:
  - {name: grain, density: 1}
laws:
  - {materials: [grain, grain], model: viscoelastic, kn: 20, ks: 10, gn: 0.08, gs: 0.04, friction: 0.3}
walls:
  - {point: [0, 0, 0], normal: [1, 0, 0], material: grain}
  - {point: [0.4, 0, 0], normal: [-1, 0, 0], material: grain}
  - {point: [0, 0, 0], normal: [0, 1, 0], material: grain}
  - {point: [0, 0.4, 0], normal: [0, -1, 0], material: grain}
  - {point: [0, 0, 0], normal: [0, 0, 1], material: grain}
  - {point: [0, 0, 0.382], normal: [0, 0, -1], material: grain, velocity: [0, 0, -0.35]}
bodies:
  - {packing: hexagonal, shape: {sphere: {radius: 0.019}}, material: grain, spacing: 0.038,
     region: {min: [0.0191, 0.0191, 0.0191], max: [0.3809, 0.3809, 0.3609]}}
outputs:
  - {type: stress, every: 20, file: stress.csv, group: 0}
  - {type: tracker, every: 20, file: top_wall.csv, walls: [5]}
  - {type: energy, every: 10, file: energy.csv}
  - {type: vtk, every: 100, prefix: frame}
  - {type: csv, every: 150, file: particles.csv}
  - {type: contacts, every: 150, file: contacts.csv}
  - {type: force_chains, every: 150}
"""

PERIODIC = """name: threads-periodic
dimension: 3
time: {duration: 0.015, dt: 5.0e-5}
gravity: [0, 0, 0]
materials:
  - {name: grain, density: 1}
laws:
  - {materials: [grain, grain], model: viscoelastic, kn: 20, ks: 10, gn: 0.08, gs: 0.04, friction: 0.3}
cell:
  size: [0.456, 0.4607255148, 0.4343761144]
  strain_rate: {xx: 0, yy: 0, zz: -0.5}
bodies:
  - {packing: hexagonal, shape: {sphere: {radius: 0.019}}, material: grain, spacing: 0.038,
     origin: [0.0095, 0.0095, 0.0095], counts: [12, 14, 14]}
outputs:
  - {type: stress, every: 20, file: stress.csv}
  - {type: energy, every: 10, file: energy.csv}
  - {type: vtk, every: 100, prefix: frame}
"""

SETTLE = """name: threads-settle
dimension: 3
time: {duration: 0.02, safety: 0.5}
gravity: [0, 0, -9.81]
materials:
  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}
laws:
  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}
walls:
  - {point: [0, 0, 0], normal: [0, 0, 1], material: glass}
  - {point: [0, 0, 0], normal: [1, 0, 0], material: glass}
  - {point: [0.03, 0, 0], normal: [-1, 0, 0], material: glass}
  - {point: [0, 0, 0], normal: [0, 1, 0], material: glass}
  - {point: [0, 0.03, 0], normal: [0, -1, 0], material: glass}
bodies:
  - {packing: random, shape: {sphere: {radius: 0.0007}}, material: glass,
     region: {min: [0, 0, 0.0], max: [0.03, 0.03, 0.012]}, velocity: [0.05, 0, -0.3], count: 1500, seed: 5}
  - {packing: random, shape: {sphere: {radius: 0.0005}}, material: glass,
     region: {min: [0, 0, 0.012], max: [0.03, 0.03, 0.02]}, velocity: [0, 0.05, -0.3], count: 1000, seed: 6}
forces:
  - {type: linear_drag, c: 2.0}
outputs:
  - {type: energy, every: 20, file: energy.csv}
  - {type: vtk, interval: 0.005}
"""

SEAICE = """name: threads-sea-ice
dimension: 2
mass_2d: area
time: {duration: 300}
gravity: [0, 0]
materials:
  - {name: ice, density: 920, young: 6e6, poisson: 0.3}
laws:
  - {materials: [ice, ice], model: hopkins, young: 6e6, friction: 0.3, thickness_max: 1.0}
bodies:
  - floe_field: {region: {min: [-20000, -20000], max: [20000, 20000]}, count: 2600, lloyd: 1,
                 concentration: 0.9, seed: 3, thickness: 1.0}
    material: ice
forces:
  - {type: wind_drag, velocity: [10, 2]}
  - {type: ocean_drag, field: vortex, speed: 0.5, length: 15000, center: [0, 0, 0], every: 3}
  - {type: coriolis, f: 1.4e-4, tilt: geostrophic, field: vortex, speed: 0.3, length: 15000, center: [0, 0, 0]}
outputs:
  - {type: energy, every: 10, file: energy.csv}
  - {type: csv, every: 50, file: floes.csv}
"""


def same_tree(a, b, what):
    names = lambda d: sorted(n for n in os.listdir(d) if not n.endswith(".tmp"))
    na, nb = names(a), names(b)
    if not check(na == nb, "%s: files differ: %s vs %s" % (what, na, nb)):
        return False
    _, bad, errs = filecmp.cmpfiles(a, b, na, shallow=False)
    return check(not bad and not errs, "%s: files differ from one thread's: %s" % (what, bad + errs))


def main():
    if len(sys.argv) != 3:
        print("usage: test_threads_cli.py <floe_cli_path> <tests_dir>", file=sys.stderr)
        sys.exit(2)
    cli = os.path.abspath(sys.argv[1])
    tmp = tempfile.mkdtemp(prefix="floe_test_threads_")
    try:
        rc, out, err = run([cli, "info"])
        if "openmp: no" in out.lower():
            scene = os.path.join(tmp, "settle.yaml")
            with open(scene, "w") as f:
                f.write(SETTLE)
            rc, out, err = run([cli, "run", scene, "-o", os.path.join(tmp, "x"), "-t", "2"])
            check(rc == 1 and "FLOE_WITH_OPENMP" in err, "without OpenMP -t 2 is refused naming the option: %s" % err)
            print("built without OpenMP: skipped")
            sys.exit(1 if counts["failed"] else 77)
        # RK2 (its midpoint probe, whose dashpot accelerations the end evaluation keeps)
        rk2 = WALLED.replace("time: {duration: 0.015, dt: 5.0e-5}", "time: {duration: 0.006, dt: 5.0e-5, integrator: rk2}")
        check(rk2 != WALLED, "the RK2 variant of the walled scene was made")
        # RK2's particle loops on the threads: 2,500 spheres, above the loops' grain
        rk2s = SETTLE.replace("time: {duration: 0.02, safety: 0.5}", "time: {duration: 0.008, safety: 0.5, integrator: rk2}")
        check(rk2s != SETTLE, "the RK2 variant of the settling scene was made")
        # the staggered PD-DEM scheme's particle loops on the threads: the struck disc of
        # tests/mpi/pd.yaml at a finer spacing (3,542 points, above the loops' grain), 2 sub-steps
        pd = open(os.path.join(sys.argv[2], "mpi", "pd.yaml")).read()
        stag = pd.replace("spacing: 0.0016", "spacing: 0.0011").replace(
            "time: {duration: 30.0e-6, safety: 0.5}",
            "time: {duration: 15.0e-6, safety: 0.5, pd_dem: {scheme: staggered, substeps: 2}}")
        check(stag.count("0.0011") == 1 and "staggered" in stag, "the staggered variant of the struck disc was made")
        # ... with F_PD every 2 steps (the cycle's kicks, the mean velocity over the cycle)
        stag2 = stag.replace("safety: 0.5, pd_dem: {scheme: staggered, substeps: 2}}",
                             "safety: 0.25, pd_dem: {scheme: staggered, every: 2}}")
        check(stag2 != stag, "the every-2 variant was made")
        # ... and tests/mpi/pd_pull.yaml with its sphere cloud grown to 3,072 (3,744 particles):
        # ramped velocity and displacement regions (kinematic PD points, their motion callbacks
        # on one thread after the blocks), 2 sub-steps
        pull = open(os.path.join(sys.argv[2], "mpi", "pd_pull.yaml")).read().replace(
            "counts: [4, 8, 24]", "counts: [8, 16, 24]").replace(
            "time: {duration: 120.0e-6, safety: 0.5}",
            "time: {duration: 30.0e-6, safety: 0.5, pd_dem: {scheme: staggered, substeps: 2}}")
        check("[8, 16, 24]" in pull and "staggered" in pull, "the staggered variant of the pulled bar was made")
        for name, text, every in (("walled", WALLED, "0.01"), ("periodic", PERIODIC, "0.01"), ("settle", SETTLE, "0.01"),
                                  ("sea-ice", SEAICE, "200"), ("walled-rk2", rk2, "0.004"), ("settle-rk2", rk2s, "0.005"),
                                  ("pd-staggered", stag, "7.0e-6"), ("pd-staggered-every", stag2, "7.0e-6"),
                                  ("pd-pull-staggered", pull, "1.5e-5")):
            scene = os.path.join(tmp, name + ".yaml")
            with open(scene, "w") as f:
                f.write(text)
            ref = None
            for t in (1, 2, 3):
                o = os.path.join(tmp, "%s_t%d" % (name, t))
                rc, out, err = run([cli, "run", scene, "-o", o, "-t", str(t), "--checkpoint-every", every], cwd=tmp)
                if not check(rc == 0, "%s -t %d: exit %d: %s" % (name, t, rc, err)):
                    break
                if t > 1:
                    check("threads:    %d" % t in out, "%s -t %d: the summary names the threads: %s" % (name, t, out))
                if ref is None:
                    ref = o
                    nfiles = len(os.listdir(o))
                    check(nfiles >= 3, "%s: the run wrote its outputs (%d files)" % (name, nfiles))
                else:
                    same_tree(ref, o, "%s -t %d" % (name, t))
            if ref:
                # continued from its last checkpoint on 2 threads (the list restored, not built)
                o = os.path.join(tmp, "%s_t3" % name)
                rc, out, err = run([cli, "run", scene, "-o", o, "-t", "2", "--restart", os.path.join(o, "checkpoint.bin")],
                                   cwd=tmp)
                if check(rc == 0, "%s: restart -t 2: exit %d: %s" % (name, rc, err)):
                    same_tree(ref, o, "%s restarted on 2 threads" % name)
            print("%s: %d files, the same bytes for 1, 2 and 3 threads" % (name, len(os.listdir(ref or tmp))))
        for bad in ("0", "x", "-2"):
            rc, out, err = run([cli, "run", os.path.join(tmp, "settle.yaml"), "-o", os.path.join(tmp, "bad"), "-t", bad])
            check(rc == 2 and "threads" in err, "-t %s refused with exit 2: %d %s" % (bad, rc, err))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("test_threads_cli")


if __name__ == "__main__":
    main()
