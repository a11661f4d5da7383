#!/usr/bin/env python3
"""test_plugin.py - plugins: a shape, a law and an output named in a scene without rebuilding
floe (core/scene/plugin.c, examples/plugin, docs/extending.md).

usage: python3 tests/test_plugin.py <floe_cli_path> <tests_dir>

Installs the build into a temporary prefix (cmake --install), builds examples/plugin's
torus_plugin.c against the installed headers only (no library linked: the CLI exports
floe's symbols), and runs the example scene with the installed `floe`:
  - a bead dropped over the torus's tube comes to rest on top of it at r + rho - m g / kn
    (within 5 % of the sag m g / kn, 2.5e-7 m) and does not slide off (x stays R within
    1e-9 m: the plugin's exact gradient makes the normal vertical);
  - a bead over the hole falls through it (no contact);
  - two beads meeting through the plugin's Hooke law restitute 1 (within 1e-5: an undamped
    spring under velocity Verlet) after a contact of pi sqrt(m_eff / k) (within 2 steps);
  - the plugin's `contact_count` output writes a row every step.
Then the registry's errors: a scene naming the torus without the plugin, a missing plugin
file, a plugin without floe_plugin_init, a bad torus parameter (the constructor's message
at the shape's line), a misspelled key of a plugin law (closest key), and `floe help` /
`floe info` listing the plugin's components.
"""
import csv
import math
import os
import shutil
import subprocess
import sys
import tempfile

from pycheck import check, finish, run


def compile_plugin(cc, src, inc, out):
    return run([cc, "-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-shared", "-fPIC", "-o", out, src,
                "-I" + inc])


def main():
    if len(sys.argv) != 3:
        print("usage: test_plugin.py <floe_cli_path> <tests_dir>", file=sys.stderr)
        sys.exit(2)
    cli, tests = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    build = os.path.dirname(cli)
    src_root = os.path.dirname(tests)
    example = os.path.join(src_root, "examples", "plugin")
    cc = shutil.which("cc") or shutil.which("gcc")
    if not check(cc is not None, "no C compiler (cc) on PATH"):
        finish("test_plugin")
    tmp = tempfile.mkdtemp(prefix="floe_test_plugin_")
    try:
        prefix = os.path.join(tmp, "prefix")
        rc, out, err = run(["cmake", "--install", build, "--prefix", prefix])
        if not check(rc == 0, "cmake --install: exit %d\n%s%s" % (rc, out, err)):
            finish("test_plugin")
        floe = os.path.join(prefix, "bin", "floe")
        inc = os.path.join(prefix, "include", "floe")
        check(os.path.exists(os.path.join(inc, "floe.h")) and os.path.exists(os.path.join(inc, "floe_registry.h")),
              "installed headers: floe.h and floe_registry.h under include/floe")
        run_dir = os.path.join(tmp, "run")
        os.makedirs(run_dir)
        so = os.path.join(run_dir, "torus_plugin.so")
        rc, out, err = compile_plugin(cc, os.path.join(example, "torus_plugin.c"), inc, so)
        if not check(rc == 0, "the plugin builds against the installed headers: exit %d\n%s" % (rc, err)):
            finish("test_plugin")
        shutil.copy(os.path.join(example, "scene.yaml"), run_dir)

        # ---- the example scene ----
        rc, out, err = run([floe, "run", "scene.yaml", "-o", "out", "-q"], cwd=run_dir)
        check(rc == 0, "floe run scene.yaml with the plugin: exit %d\n%s" % (rc, err))
        rows = list(csv.reader(open(os.path.join(run_dir, "out", "bodies.csv"))))[1:]
        last = {}
        for r in rows:
            last[int(r[1])] = [float(v) for v in r]
        rho, r_tube, R, kn, g = 0.005, 0.006, 0.02, 1.0e3, 9.81
        m = 1000 * 4.0 / 3.0 * math.pi * rho ** 3
        z_rest = r_tube + rho - m * g / kn
        z_top = last[1][4]
        # the sag m g / kn is 5.1 um; the law's discrete dashpot shifts it by gn dt / 2m* (2 %)
        check(abs(z_top - z_rest) < 0.05 * m * g / kn and abs(last[1][2] - R) < 1e-9,
              "bead on the tube rests at z %.9g (expected r + rho - m g / kn = %.9g within 5 %% of the sag, x %.9g)"
              % (z_top, z_rest, last[1][2]))
        check(last[2][4] < -0.1, "bead over the hole falls through it (z %.3g m)" % last[2][4])
        e = abs(last[4][5] - last[3][5]) / 0.2
        check(abs(e - 1) < 1e-5, "Hooke beads restitute 1 (got %.9g)" % e)
        crow = list(csv.reader(open(os.path.join(run_dir, "out", "contacts.csv"))))
        check(crow[0][:2] == ["t [s]", "contacts"], "contacts output header: %r" % crow[0])
        t = [float(r[0]) for r in crow[1:]]
        n = [int(r[1]) for r in crow[1:]]
        dt = t[2] - t[1]
        steps = int(round(0.3 / dt))
        check(abs(len(t) - (steps + 1)) <= 2, "contacts output: a row per step (%d rows, %d steps)" % (len(t), steps))
        # the pair meets at t = 0.05 s; the top bead lands at about 0.06 s: count before that
        dur = sum(1 for ti, ni in zip(t, n) if ni > 0 and ti < 0.058) * dt
        T = math.pi * math.sqrt(m / 2 / 100.0)
        check(abs(dur - T) <= 2 * dt, "Hooke contact lasts %.6g s (pi sqrt(m_eff/k) = %.6g s, step %.3g s)" %
              (dur, T, dt))

        # ---- help and info list the plugin's components ----
        rc, out, err = run([floe, "help", "law", "hooke", "--plugin", so], cwd=run_dir)
        check(rc == 0 and "spring stiffness" in out and "N/m" in out and so in out,
              "floe help law hooke --plugin: exit %d\n%s%s" % (rc, out, err))
        rc, out, err = run([floe, "--plugin", so, "info"], cwd=run_dir)
        check(rc == 0 and "torus (plugin)" in out and "contact_count (plugin)" in out,
              "floe info --plugin lists the plugin's components:\n%s%s" % (out, err))

        # ---- errors ----
        text = open(os.path.join(example, "scene.yaml")).read()

        def scene_error(name, new_text, *words):
            path = os.path.join(run_dir, name)
            with open(path, "w") as f:
                f.write(new_text)
            rc, out, err = run([floe, "check", name], cwd=run_dir)
            ok = rc == 1 and all(w in err for w in words)
            check(ok, "%s: exit %d, stderr %r lacks %r" % (name, rc, err, words))
            return err

        no_plugin = text.replace("plugins: [torus_plugin.so]", "")
        line = [i + 1 for i, l in enumerate(no_plugin.splitlines()) if "model: hooke" in l][0]
        scene_error("no_plugin.yaml", no_plugin, "no_plugin.yaml:%d:" % line, "unknown value 'hooke'")
        no_torus = no_plugin.replace("model: hooke, k:", "model: linear, ks: 10, kn:")
        line = [i + 1 for i, l in enumerate(no_torus.splitlines()) if "torus:" in l][0]
        scene_error("no_torus.yaml", no_torus, "no_torus.yaml:%d:" % line, "unknown key 'torus'")
        scene_error("missing.yaml", text.replace("torus_plugin.so]", "nothere.so]"), "missing.yaml:6:",
                    "nothere.so", "cannot load")
        bad_src = os.path.join(run_dir, "noinit.c")
        with open(bad_src, "w") as f:
            f.write("int floe_not_init(void);\nint floe_not_init(void) { return 0; }\n")
        rc, out, err = compile_plugin(cc, bad_src, inc, os.path.join(run_dir, "noinit.so"))
        check(rc == 0, "noinit.so builds: %s" % err)
        scene_error("noinit.yaml", text.replace("torus_plugin.so]", "noinit.so]"), "noinit.yaml:6:",
                    "floe_plugin_init")
        bad = text.replace("{major: 0.02, minor: 0.006}", "{major: 0.02, minor: 0.03}")
        line = [i + 1 for i, l in enumerate(bad.splitlines()) if "torus:" in l][0]
        scene_error("minor.yaml", bad, "minor.yaml:%d:" % line, "minor", "must be below major")
        bad = text.replace("{major: 0.02, minor: 0.006}", "{major: 0.02, minr: 0.006}")
        scene_error("minr.yaml", bad, "unknown key 'minr'", "did you mean 'minor'?")
        bad = text.replace("model: hooke, k: 100}\n  - {materials: [pair, pair]",
                           "model: hooke, kk: 100}\n  - {materials: [pair, pair]")
        scene_error("kk.yaml", bad, "unknown key 'kk'", "model 'hooke'", "did you mean 'k'?")
        bad = text.replace("model: hooke, k: 100}\n  - {materials: [pair, pair]",
                           "model: hooke, k: -1}\n  - {materials: [pair, pair]")
        scene_error("kneg.yaml", bad, "laws[1].k must be > 0 (N/m) (got -1)")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("test_plugin")


if __name__ == "__main__":
    main()
