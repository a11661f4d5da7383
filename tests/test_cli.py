#!/usr/bin/env python3
"""test_cli.py - the floe command line (cli/main.c).

usage: python3 tests/test_cli.py <floe_cli_path> <tests_dir>

Checks: `floe check` on a good scene (exit 0, summary with the critical dt) and on bad ones
(exit 1, "file:line:col: message" on stderr); `floe info` (exit 0, version); bad usage
(exit 2, usage on stderr); `floe run` of a tiny scene into a temporary directory (exit 0,
end-of-run summary, every output file written and non-empty); a run that fails part-way
(exit 1, message, outputs written so far kept). Prints "N passed, N failed".
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

from pycheck import check, finish, run


def main():
    if len(sys.argv) != 3:
        print("usage: test_cli.py <floe_cli_path> <tests_dir>", file=sys.stderr)
        sys.exit(2)
    cli, tests = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    scenes = os.path.join(tests, "scenes")
    if not check(os.access(cli, os.X_OK), "floe CLI not found at %s" % cli):
        finish("test_cli")
        sys.exit(1)
    tmp = tempfile.mkdtemp(prefix="floe_test_cli_")
    try:
        # check: good scene
        good = os.path.join(scenes, "valid_packings.yaml")
        rc, out, err = run([cli, "check", good], cwd=tmp)
        check(rc == 0, "check good scene: exit %d, stderr %s" % (rc, err))
        check(re.search(r"critical dt estimate [0-9.e+-]+ s", out) is not None,
              "check prints the critical dt:\n" + out)
        check("particles:  74" in out, "check prints the particle count:\n" + out)
        check(not os.path.exists(os.path.join(tmp, "out")), "check must not create outputs")

        # check lists PD boundary regions and every time-step estimate with the limiting one
        hole = os.path.join(os.path.dirname(tests), "examples", "plate-with-hole", "scene.yaml")
        rc, out, err = run([cli, "check", hole], cwd=tmp)
        check(rc == 0, "check plate-with-hole: exit %d, stderr %s" % (rc, err))
        check(re.search(r"boundary 0: peridynamics 0, \d+ points, body force \(-3, 0, 0\), exponential ramp over 0.1 s",
                        out) is not None, "check lists the PD boundary regions:\n" + out)
        check("<- limits" in out and "pd_nodal" in out, "check marks the limiting time-step estimate:\n" + out)

        # check: bad scenes -> exit 1 and file:line:col
        for name, loc, words in [("bad_key.yaml", "10:5", ["frition", "did you mean 'friction'"]),
                                 ("bad_unclosed.yaml", "11:15", ["never closed"]),
                                 ("bad_indent.yaml", "10:4", ["YAML"]),
                                 ("bad_missing_law.yaml", "13:50", ["no contact law"])]:
            path = os.path.join(scenes, name)
            rc, out, err = run([cli, "check", path], cwd=tmp)
            check(rc == 1, "check %s: exit %d, expected 1" % (name, rc))
            check(("%s:%s:" % (path, loc)) in err, "check %s: no '%s:%s:' in %r" % (name, path, loc, err))
            for w in words:
                check(w in err, "check %s: %r not in %r" % (name, w, err))
        rc, out, err = run([cli, "check", os.path.join(tmp, "missing.yaml")], cwd=tmp)
        check(rc == 1 and "missing.yaml" in err, "check of a missing file: exit %d, %r" % (rc, err))

        # info
        rc, out, err = run([cli, "info"], cwd=tmp)
        check(rc == 0, "info: exit %d" % rc)
        check(re.search(r"floe \d+\.\d+\.\d+", out) is not None, "info prints the version:\n" + out)
        for w in ("OpenMP", "CGAL", "CHOLMOD", "hertz_mindlin", "sphere"):
            check(w in out, "info lacks %r:\n%s" % (w, out))

        # usage errors
        for args in ([], ["frobnicate"], ["run", "-x"], ["check"], ["run", "a.yaml", "b.yaml"],
                     ["run", "-o"]):
            rc, out, err = run([cli] + args, cwd=tmp)
            check(rc == 2 and "usage" in err, "floe %s: exit %d, stderr %r" % (" ".join(args), rc, err))
        rc, out, err = run([cli, "--help"], cwd=tmp)
        check(rc == 0 and "usage" in out, "--help: exit %d" % rc)

        # run a tiny scene
        outdir = os.path.join(tmp, "tiny")
        rc, out, err = run([cli, "run", os.path.join(scenes, "tiny_run.yaml"), "-o", outdir], cwd=tmp)
        check(rc == 0, "run tiny: exit %d\n%s\n%s" % (rc, out, err))
        for w in ("steps:", "simulated time:", "wall time:", "particle-steps/s:", "contacts",
                  "neighbour rebuilds:", "energy balance", "energy watchdog:    stop (tolerance 0.05"):
            check(w in out, "run summary lacks %r:\n%s" % (w, out))
        m = re.search(r"steps:\s+(\d+)", out.split("run finished")[-1])
        check(m is not None and int(m.group(1)) == 500, "run: 500 steps expected:\n" + out)
        for f in ("frame.pvd", "frame_000000.vtu", "particles.csv", "energy.csv", "stress.csv",
                  "track.csv"):
            p = os.path.join(outdir, f)
            check(os.path.isfile(p) and os.path.getsize(p) > 0, "run: output %s missing or empty" % f)
        if os.path.isfile(os.path.join(outdir, "track.csv")):
            with open(os.path.join(outdir, "track.csv")) as fh:
                rows = fh.read().splitlines()
            ids = {r.split(",")[1] for r in rows[1:]}
            check(ids == {"0", "7"}, "tracker ids %s, expected {0, 7}" % ids)
            check(len(rows) - 1 >= 2 * 50, "tracker rows %d (every 10 of 500 steps, 2 ids)" % (len(rows) - 1))
        # -q prints nothing on success
        rc, out, err = run([cli, "run", os.path.join(scenes, "tiny_run.yaml"), "-q", "-o",
                            os.path.join(tmp, "quiet")], cwd=tmp)
        check(rc == 0 and out == "" and err == "", "run -q: exit %d, out %r, err %r" % (rc, out, err))

        # a run that blows up: exit 1, message, outputs so far kept
        bad = os.path.join(tmp, "unstable.yaml")
        with open(os.path.join(scenes, "tiny_run.yaml")) as fh:
            text = fh.read()
        text = text.replace("{duration: 0.005, dt: 1.0e-5}",
                            "{duration: 0.05, dt: 5.0e-4, allow_unstable_dt: true}")
        with open(bad, "w") as fh:
            fh.write(text)
        outbad = os.path.join(tmp, "unstable")
        rc, out, err = run([cli, "run", bad, "-o", outbad], cwd=tmp)
        check(rc == 1, "unstable run: exit %d, expected 1\n%s\n%s" % (rc, out, err))
        check("unstable" in err and "particle" in err, "unstable run: message names the particle %r" % err)
        ecsv = os.path.join(outbad, "energy.csv")
        check(os.path.isfile(ecsv), "unstable run: outputs kept")
        if os.path.isfile(ecsv):
            with open(ecsv) as fh:
                rows = [r for r in fh.read().splitlines()[1:] if r]
            # the state at the failure is flushed: a last row after t = 0
            check(len(rows) >= 2 and float(rows[-1].split(",")[0]) > 0,
                  "unstable run: energy.csv holds the state at failure (%d rows)" % len(rows))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("test_cli")


if __name__ == "__main__":
    main()
