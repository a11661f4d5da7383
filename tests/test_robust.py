#!/usr/bin/env python3
"""test_robust.py - a run never lies and never hangs (cli/main.c, core/scene/scene.c, observers).

usage: python3 tests/test_robust.py <floe_cli_path> <tests_dir>

Checks: SIGTERM / SIGINT stop a write-heavy run cleanly (exit 128 + signal, a message, every
CSV line whole and every frame complete); hostile scene files (alias bombs, huge counts,
FIFOs as mesh files, ...) are refused quickly with a message naming the file; a large closed
mesh in hull mode is fast. Prints "N passed, N failed".
"""
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

from pycheck import check, finish, run

HEAD = """dimension: 3
time: {duration: %s, dt: 1.0e-6}
materials:
  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}
laws:
  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}
"""


def write(tmp, name, text):
    p = os.path.join(tmp, name)
    with open(p, "w") as fh:
        fh.write(text)
    return p


def test_signal(cli, tmp, sig):
    """a run writing ~1 MB per step, stopped by sig after about 1 s"""
    scene = write(tmp, "heavy.yaml", HEAD % "10" + """bodies:
  - {packing: lattice, shape: {sphere: {radius: 0.001}}, material: glass,
     origin: [0, 0, 0], counts: [16, 16, 16], spacing: 0.003}
outputs:
  - {type: csv, every: 1, file: particles.csv}
""")
    outdir = os.path.join(tmp, "heavy_%d" % sig)
    csv = os.path.join(outdir, "particles.csv")
    p = subprocess.Popen([cli, "run", scene, "-q", "-o", outdir], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, universal_newlines=True)
    t0 = time.time()
    # wait for the first frames, then about a second of writing
    while time.time() - t0 < 60 and p.poll() is None:
        if os.path.isfile(csv) and os.path.getsize(csv) > 1000000:
            break
        time.sleep(0.05)
    time.sleep(1.0)
    p.send_signal(sig)
    try:
        out, err = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        p.kill()
        out, err = p.communicate()
        check(False, "signal %d: the run did not stop within 60 s" % sig)
        return
    name = "SIGTERM" if sig == signal.SIGTERM else "SIGINT"
    check(p.returncode == 128 + sig, "%s: exit %d, expected %d (stderr %r)" % (name, p.returncode, 128 + sig, err))
    check(("stopped by %s" % name) in err, "%s: message %r" % (name, err))
    if not check(os.path.isfile(csv), "%s: csv missing" % name):
        return
    with open(csv) as fh:
        data = fh.read()
    check(data.endswith("\n"), "%s: the CSV ends inside a line" % name)
    lines = data.splitlines()
    nf = len(lines[0].split(","))
    bad = [i for i, l in enumerate(lines) if len(l.split(",")) != nf]
    check(not bad, "%s: %d of %d CSV lines have a wrong field count (first: line %d %r)" %
          (name, len(bad), len(lines), bad[0] + 1 if bad else 0, lines[bad[0]] if bad else ""))
    rows = len(lines) - 1
    check(rows >= 2 * 4096 and rows % 4096 == 0,
          "%s: %d data rows, expected whole frames of 4096 particles (at least 2)" % (name, rows))
    print("  %s: exit %d, %d frames, %r" % (name, p.returncode, rows // 4096, err.strip()))


def peak_rss_mb(args, cwd):
    """run args, return (rc, stdout, stderr, seconds, peak RSS of the child in MB)"""
    import resource
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t0 = time.time()
    p = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=cwd, timeout=120,
                       universal_newlines=True)
    el = time.time() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return p.returncode, p.stdout, p.stderr, el, max(after, before) / 1024.0


def test_alias_bomb(cli, tmp):
    """a 1.2 KB billion-laughs scene: refused in seconds, small memory, message names the file"""
    lines = ["a0: &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    for i in range(1, 12):
        lines.append("a%d: &a%d [%s]" % (i, i, ", ".join(["*a%d" % (i - 1)] * 10)))
    bomb = write(tmp, "bomb.yaml", "\n".join(lines) + "\n")
    size = os.path.getsize(bomb)
    rc, out, err, el, mb = peak_rss_mb([cli, "check", bomb], tmp)
    check(rc == 1, "alias bomb: exit %d, expected 1" % rc)
    check(bomb in err and "YAML nodes" in err, "alias bomb: message %r" % err)
    check(el < 10, "alias bomb: %.1f s (limit 10 s)" % el)
    check(mb < 200, "alias bomb: peak RSS %.0f MB (limit 200 MB)" % mb)
    print("  alias bomb (%d bytes): exit %d in %.2f s, peak RSS <= %.0f MB, %r" % (size, rc, el, mb, err.strip()))


def test_memory_estimate(cli, tmp):
    """floe check prints a memory estimate; it covers the peak RSS of a short run of 64,000
    touching spheres, and is within a factor 2 of it"""
    scene = write(tmp, "mem.yaml", HEAD % "2.0e-6" + """bodies:
  - {packing: lattice, shape: {sphere: {radius: 0.001}}, material: glass,
     origin: [0, 0, 0], counts: [40, 40, 40], spacing: 0.002}
outputs:
  - {type: vtk, every: 1, prefix: f}
""")
    rc, out, err = run([cli, "check", scene], cwd=tmp)
    m = re.search(r"memory:\s+about ([0-9.e+]+) MB \(estimate; this machine has ([0-9.e+]+) GB\)", out)
    if not check(rc == 0 and m is not None, "check prints the memory estimate: exit %d\n%s%s" % (rc, out, err)):
        return
    est = float(m.group(1))
    with open(cli, "rb") as fh:
        if b"__asan_init" in fh.read():
            print("  memory: estimate %.1f MB (sanitizer build: RSS not comparable, skipped)" % est)
            return
    # a fresh child: its peak RSS alone (RUSAGE_CHILDREN is the largest child so far)
    code = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL); "
            "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")
    rc2, out2, err2 = run([sys.executable, "-c", code, cli, "run", scene, "-q", "-o", os.path.join(tmp, "mem")], cwd=tmp)
    rss = float(out2.strip()) / 1024.0 if rc2 == 0 and out2.strip() else -1
    check(rss > 0 and rss <= est <= 2.0 * rss,
          "memory estimate %.1f MB vs peak RSS %.1f MB of the run (expected RSS <= estimate <= 2 RSS)" % (est, rss))
    print("  memory: estimate %.1f MB, peak RSS of the run %.1f MB" % (est, rss))


def main():
    if len(sys.argv) != 3:
        print("usage: test_robust.py <floe_cli_path> <tests_dir>", file=sys.stderr)
        sys.exit(2)
    cli = os.path.abspath(sys.argv[1])
    tmp = tempfile.mkdtemp(prefix="floe_test_robust_")
    try:
        test_alias_bomb(cli, tmp)
        test_memory_estimate(cli, tmp)
        test_signal(cli, tmp, signal.SIGTERM)
        test_signal(cli, tmp, signal.SIGINT)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("test_robust")


if __name__ == "__main__":
    main()
