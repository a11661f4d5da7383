#!/usr/bin/env python3
"""test_integrator_registry.py - the integrators as registered classes (issue #11, item 6)
and the file DAG check of scripts/check_layers.py.

usage: python3 tests/test_integrator_registry.py <floe_cli_path> <tests_dir>

Checks: `floe help integrator` lists the five registered integrators (the three a scene may
name and the two Newmark-beta solvers, documented only); `floe help integrator rk2` prints
its doc, source and critical-step factor; an unknown name fails naming the kind, and a
part of exactly one name ("verlet") is answered with that name; the scene's
time.integrator is looked up in the registry: rk2 and leapfrog load, a documented-only
class (newmark_implicit) is refused with the loader's unchanged "unknown value" message and
its choices; check_layers.py fails on a circle of calls between two files of a folder
(naming both and the functions) and passes once one direction is removed.
"""
import os
import shutil
import sys
import tempfile

from pycheck import check, finish, run


SCENE = """name: osc
dimension: 3
time: {duration: 0.0001, integrator: %s}
materials:
  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}
laws:
  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}
bodies:
  - {shape: {sphere: {radius: 0.001}}, material: glass, position: [0, 0, 0]}
  - {shape: {sphere: {radius: 0.001}}, material: glass, position: [0.0025, 0, 0], velocity: [-0.1, 0, 0]}
"""


def layer_tree(tmp, a_calls_b, b_calls_a):
    """A fake repository with one layer folder 'lib' of two sources."""
    os.makedirs(os.path.join(tmp, "lib"), exist_ok=True)
    with open(os.path.join(tmp, "CMakeLists.txt"), "w") as f:
        f.write("set(FLOE_LAYERS lib)\n")
    os.makedirs(os.path.join(tmp, "cli"), exist_ok=True)
    with open(os.path.join(tmp, "lib", "a.c"), "w") as f:
        f.write("int b_fn(int x);\n/* a_fn: the top */\nint a_fn(int x) {\n    return %s;\n}\n" %
                ("b_fn(x) + 1" if a_calls_b else "x"))
    with open(os.path.join(tmp, "lib", "b.c"), "w") as f:
        f.write(("int a_fn(int x);\n" if b_calls_a else "") + "int b_fn(int x) {\n    int a_fn_local = x; /* a namesake is no call */\n"
                "    return %s;\n}\n" % ("a_fn(a_fn_local)" if b_calls_a else "a_fn_local"))


def main():
    cli, tests = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    root = os.path.dirname(tests)
    tmp = tempfile.mkdtemp(prefix="floe_test_integ_")
    try:
        rc, out, err = run([cli, "help", "integrator"])
        check(rc == 0, "help integrator: exit %d %s" % (rc, err))
        for name in ("velocity_verlet", "leapfrog", "rk2", "newmark_explicit", "newmark_implicit"):
            check(name in out, "help integrator lists %s:\n%s" % (name, out))
        rc, out, err = run([cli, "help", "integrator", "rk2"])
        check(rc == 0 and "source: ParticLS eq 21" in out and "1 x the critical estimate" in out,
              "help integrator rk2 documents its source and factor (exit %d):\n%s%s" % (rc, out, err))
        rc, out, err = run([cli, "help", "integrator", "newmark_implicit"])
        check(rc == 0 and "beta" in out and "line_search_eps" in out,
              "help integrator newmark_implicit lists its parameters:\n%s%s" % (out, err))
        rc, out, err = run([cli, "help", "integrator", "verlet"])
        check(rc != 0 and "did you mean 'velocity_verlet'?" in err,
              "help integrator verlet points at velocity_verlet (a part of one name): %s" % err)
        rc, out, err = run([cli, "help", "integrator", "newmark"])
        check(rc != 0 and "did you mean" not in err, "a part of two names suggests neither: %s" % err)
        rc, out, err = run([cli, "help", "integrator", "euler"])
        check(rc != 0 and "no integrator named 'euler'" in err, "unknown integrator refused (exit %d): %s" % (rc, err))
        # the scene's time.integrator through the registry
        for name, ok in (("rk2", True), ("leapfrog", True), ("newmark_implicit", False), ("rk3", False)):
            path = os.path.join(tmp, "s_%s.yaml" % name)
            with open(path, "w") as f:
                f.write(SCENE % name)
            rc, out, err = run([cli, "check", path], cwd=tmp)
            if ok:
                check(rc == 0 and ("integrator: %s" % name) in out, "integrator %s loads (exit %d):\n%s%s" % (name, rc, out, err))
            else:
                check(rc == 1 and ("time.integrator: unknown value '%s'" % name) in err,
                      "integrator %s refused with the loader's message (exit %d): %s" % (name, rc, err))
        rc, out, err = run([cli, "check", os.path.join(tmp, "s_rk3.yaml")], cwd=tmp)
        check("rk2" in err, "the closest registered name is suggested for rk3: %s" % err)
        # check_layers.py: a call circle between two files of a folder fails, one direction passes
        script = os.path.join(root, "scripts", "check_layers.py")
        fake = os.path.join(tmp, "fake")
        layer_tree(fake, True, True)
        rc, out, err = run([sys.executable, script, fake])
        check(rc == 1 and "lib: call circle: a.c (b_fn) -> b.c (a_fn) -> a.c" in out,
              "check_layers fails on a call circle, naming it (exit %d):\n%s%s" % (rc, out, err))
        layer_tree(fake, True, False)
        rc, out, err = run([sys.executable, script, fake])
        check(rc == 0 and "no call circle" in out, "check_layers passes a one-way call (exit %d):\n%s%s" % (rc, out, err))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("test_integrator_registry")


if __name__ == "__main__":
    main()
