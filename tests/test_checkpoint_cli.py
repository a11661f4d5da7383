#!/usr/bin/env python3
"""test_checkpoint_cli.py - `floe run --checkpoint-every / --restart` (issue #13,
docs/checkpoints.md): a run continued from a checkpoint writes the same output files, byte
for byte, as the run that was not stopped.

usage: python3 tests/test_checkpoint_cli.py <floe_cli_path> <tests_dir>

Scenes: 3D spheres with friction against walls (outputs vtk, csv, energy, tracker, stress,
contacts, force_chains, some by steps and some by time), and a 2D floe of beam bonds
breaking on an island (outlines, floe_sizes, fracture_events, energy). Checked, for each:
  - a run writing checkpoints has the outputs of the run without (checkpoints change
    nothing);
  - the run restarted from its last checkpoint, into the same output directory, ends with
    the same files (the outputs are cut back to the checkpoint and go on);
  - a run stopped by SIGTERM (exit 143, a checkpoint written, the command to continue
    printed) and one killed by SIGKILL after a periodic checkpoint, each restarted, end with
    the same files.
Refusals (exit 1, a message, no output changed): another scene, a truncated checkpoint, a
removed output file; bad --checkpoint-every (exit 2).
Prints "N passed, N failed".
"""
import filecmp
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

from pycheck import check, finish, run

SPHERES = """name: ckpt-spheres
dimension: 3
time: {duration: 0.12, safety: 0.5}
gravity: [0, 0, -9.81]
neighbor: {skin: 0.0002}
materials:
  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}
laws:
  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}
walls:
  - {point: [0, 0, 0], normal: [0, 0, 1], material: glass}
  - {point: [0, 0, 0], normal: [1, 0, 0], material: glass}
  - {point: [0.012, 0, 0], normal: [-1, 0, 0], material: glass}
bodies:
  - {packing: random, shape: {sphere: {radius: 0.001}}, material: glass,
     region: {min: [0, 0, 0.001], max: [0.012, 0.012, 0.014]}, velocity: [0.05, 0, -0.2], count: 90, seed: 3}
outputs:
  - {type: vtk, interval: 0.01}
  - {type: csv, interval: 0.004, file: particles.csv}
  - {type: energy, every: 50, file: energy.csv}
  - {type: tracker, every: 25, file: track.csv, particles: [2, 5]}
  - {type: stress, every: 40, file: stress.csv, group: all}
  - {type: contacts, interval: 0.01, file: contacts.csv}
  - {type: force_chains, interval: 0.02}
"""

BEAMS = """name: ckpt-beams
dimension: 2
mass_2d: area
time: {duration: 40}
gravity: [0, 0]
materials:
  - {name: ice, density: 920, young: 1e8, poisson: 0.3}
laws:
  - {materials: [ice, ice], model: hopkins, young: 1e8, friction: 0.3, thickness_max: 1.0}
bodies:
  - {name: island, material: ice, motion: fixed, position: [0, 0],
     shape: {polygon: {vertices: [[-200, -150], [150, -220], [250, 50], [0, 220]]}}}
  - {name: floe, packing: hexagonal, shape: {sphere: {radius: 50}}, material: ice, thickness: 1.0,
     spacing: 100, region: {min: [-300, 260], max: [300, 560]}, velocity: [0, -4]}
bonds:
  - {young: 1e9, poisson: 0.3, radius_factor: 1.01, timoshenko: true, thickness: 1.0,
     tensile_strength: 2e4, tensile_sd: 4e3, shear_strength: 2e4, shear_sd: 4e3,
     compressive_strength: 8e4, compressive_sd: 1.6e4, friction_angle: 30, seed: 7, group: 1}
outputs:
  - {type: outlines, interval: 4}
  - {type: floe_sizes, interval: 2, file: sizes.csv}
  - {type: fracture_events, every: 10, file: breaks.csv}
  - {type: energy, every: 100, file: energy.csv}
"""


def same_tree(a, b, what):
    """the files of a and b (checkpoints left out) are equal byte for byte"""
    names = lambda d: sorted(n for n in os.listdir(d) if not n.startswith("checkpoint") and not n.endswith(".tmp"))
    na, nb = names(a), names(b)
    if not check(na == nb, "%s: files differ: %s vs %s" % (what, na, nb)):
        return False
    _, bad, errs = filecmp.cmpfiles(a, b, na, shallow=False)
    return check(not bad and not errs, "%s: files differ from the uninterrupted run: %s" % (what, bad + errs))


def stopped_run(cli, scene, out, sig, tmp):
    """starts a run writing checkpoints often, stops it with sig after its first checkpoint;
    returns (exit status, stderr) or None when it ended first"""
    ck = os.path.join(out, "checkpoint.bin")
    p = subprocess.Popen([cli, "run", scene, "-o", out, "-q", "--checkpoint-every", "0.002"], cwd=tmp,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    t0 = time.time()
    while p.poll() is None and not os.path.exists(ck) and time.time() - t0 < 60:
        time.sleep(0.005)
    time.sleep(0.05)
    if p.poll() is not None:
        p.communicate()
        return None
    p.send_signal(sig)
    _, err = p.communicate(timeout=120)
    return p.returncode, err


def main():
    if len(sys.argv) != 3:
        print("usage: test_checkpoint_cli.py <floe_cli_path> <tests_dir>", file=sys.stderr)
        sys.exit(2)
    cli = os.path.abspath(sys.argv[1])
    tmp = tempfile.mkdtemp(prefix="floe_test_ckpt_")
    try:
        for name, text, every in (("spheres", SPHERES, "0.03"), ("beams", BEAMS, "15")):
            scene = os.path.join(tmp, name + ".yaml")
            with open(scene, "w") as f:
                f.write(text)
            a, b = os.path.join(tmp, name + "_A"), os.path.join(tmp, name + "_B")
            rc, out, err = run([cli, "run", scene, "-o", a, "-q"], cwd=tmp)
            check(rc == 0, "%s: uninterrupted run: exit %d: %s" % (name, rc, err))
            rc, out, err = run([cli, "run", scene, "-o", b, "--checkpoint-every", every], cwd=tmp)
            check(rc == 0 and "checkpoints:" in out, "%s: run with checkpoints: exit %d: %s%s" % (name, rc, out, err))
            ck = os.path.join(b, "checkpoint.bin")
            check(os.path.exists(ck), "%s: %s written" % (name, ck))
            same_tree(a, b, name + ", checkpoints written along")
            rc, out, err = run([cli, "run", scene, "-o", b, "--restart", ck], cwd=tmp)
            check(rc == 0 and "restart:" in out, "%s: restart: exit %d: %s%s" % (name, rc, out, err))
            same_tree(a, b, name + ", restarted from the last checkpoint")
            if name == "beams":
                with open(os.path.join(a, "breaks.csv")) as f:
                    check(len(f.readlines()) > 5, "beams: bonds break in the run")
                continue
            # stopped by a signal, then continued
            for sig, code in ((signal.SIGTERM, 143), (signal.SIGKILL, -9)):
                c = os.path.join(tmp, name + "_C%d" % sig)
                res = stopped_run(cli, scene, c, sig, tmp)
                if res is None:
                    print("note: the run ended before signal %d; not checked" % sig)
                    continue
                rc, err = res
                check(rc == code, "%s: stopped by signal %d: exit %d (want %d): %s" % (name, sig, rc, code, err))
                if sig == signal.SIGTERM:
                    check("--restart" in err, "the stop message says how to continue: %s" % err)
                rc, out, err = run([cli, "run", scene, "-o", c, "-q", "--restart", os.path.join(c, "checkpoint.bin")],
                                   cwd=tmp)
                check(rc == 0, "%s: restart after signal %d: exit %d: %s" % (name, sig, rc, err))
                same_tree(a, c, "%s, stopped by signal %d and restarted" % (name, sig))
            # refusals
            other = os.path.join(tmp, "other.yaml")
            with open(other, "w") as f:
                f.write(text.replace("seed: 3", "seed: 4"))
            rc, out, err = run([cli, "run", other, "-o", b, "--restart", ck], cwd=tmp)
            check(rc == 1 and "another scene" in err, "another scene refused: exit %d: %s" % (rc, err))
            data = open(ck, "rb").read()
            trunc = os.path.join(tmp, "trunc.bin")
            with open(trunc, "wb") as f:
                f.write(data[: len(data) * 2 // 3])
            rc, out, err = run([cli, "run", scene, "-o", b, "--restart", trunc], cwd=tmp)
            check(rc == 1 and "truncated" in err, "a truncated checkpoint refused: exit %d: %s" % (rc, err))
            same_tree(a, b, "refused restarts change nothing")
            os.remove(os.path.join(b, "particles.csv"))
            rc, out, err = run([cli, "run", scene, "-o", b, "--restart", ck], cwd=tmp)
            check(rc == 1 and "particles.csv is missing" in err, "a removed output refused: exit %d: %s" % (rc, err))
            rc, out, err = run([cli, "run", scene, "-o", b, "--checkpoint-every", "-1"], cwd=tmp)
            check(rc == 2 and "--checkpoint-every" in err, "bad --checkpoint-every: exit %d: %s" % (rc, err))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("test_checkpoint_cli")


if __name__ == "__main__":
    main()
