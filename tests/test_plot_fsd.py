#!/usr/bin/env python3
"""test_plot_fsd.py - scripts/plot_fsd.py: the PNG of the floe size distribution from a
floe_sizes CSV.

usage: python3 tests/test_plot_fsd.py <floe_cli_path> <tests_dir>

Checks:
- on a generated floe_sizes CSV (three frames of 40, 55 and 80 floes with power-law areas)
  the script exits 0 and writes a PNG: the file starts with the PNG signature
  (89 50 4E 47 0D 0A 1A 0A), holds more than 1 kB and an IHDR of 640 x 480 pixels;
- with --times and --fit as well;
- a missing file and a file that is not a floe_sizes CSV exit 1 with a message naming it.
Without matplotlib (Debian python3-matplotlib) the test is skipped: it prints why and exits
77, which tests/CMakeLists.txt declares as ctest's skip code.
Prints "N passed, N failed"."""
import os
import random
import shutil
import struct
import subprocess
import sys
import tempfile

# python3-matplotlib is a Debian package: under another python3 (pyenv, venv) without it,
# re-run under the system one (as tests/test_vtk.py does for VTK)
try:
    import matplotlib  # noqa: F401
except ImportError:
    if os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3") \
            and os.path.exists("/usr/bin/python3") and not os.environ.get("FLOE_TEST_MPL_REEXEC"):
        os.environ["FLOE_TEST_MPL_REEXEC"] = "1"
        os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
    print("test_plot_fsd: skipped: matplotlib is not installed (Debian python3-matplotlib, scripts/install-deps.sh)")
    sys.exit(77)

from pycheck import check, finish

SIG = b"\x89PNG\r\n\x1a\n"


def write_csv(path):
    rnd = random.Random(5)
    with open(path, "w") as f:
        f.write("t [s],floe,particles,area [m^2],x [m],y [m]\n")
        for t, n in ((0.0, 40), (100.0, 55), (200.0, 80)):
            for k in range(n):
                d = 100 * (1 - rnd.random() * 0.99) ** -0.5  # N(>D) ~ D^-2 on [100, 1000]
                f.write("%g,%d,1,%.10g,%g,%g\n" % (t, k, 3.141592653589793 * d * d / 4, 10.0 * k, 0.0))


def run(script, args):
    p = subprocess.run([sys.executable, script] + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                       universal_newlines=True, timeout=300)
    return p.returncode, p.stdout + p.stderr


def check_png(path, what):
    ok = check(os.path.exists(path), "%s: %s written" % (what, path))
    if not ok:
        return
    data = open(path, "rb").read()
    check(data[:8] == SIG, "%s: starts with the PNG signature (%r)" % (what, data[:8]))
    check(len(data) > 1000, "%s: %d bytes (> 1 kB)" % (what, len(data)))
    w, h = struct.unpack(">II", data[16:24]) if data[12:16] == b"IHDR" else (0, 0)
    check((w, h) == (640, 480), "%s: IHDR %d x %d (640 x 480)" % (what, w, h))
    print("  %s: %d bytes, %d x %d" % (what, len(data), w, h))


def main():
    tests_dir = sys.argv[2] if len(sys.argv) > 2 else os.path.dirname(os.path.abspath(__file__))
    script = os.path.join(tests_dir, "..", "scripts", "plot_fsd.py")
    tmp = tempfile.mkdtemp(prefix="floe_plot_fsd_")
    try:
        csv_path = os.path.join(tmp, "floe_sizes.csv")
        write_csv(csv_path)
        png = os.path.join(tmp, "fsd.png")
        rc, out = run(script, [csv_path, "-o", png])
        check(rc == 0, "plot_fsd exits 0 (%d): %s" % (rc, out))
        check_png(png, "first and last frames")
        png2 = os.path.join(tmp, "fsd_fit.png")
        rc, out = run(script, [csv_path, "-o", png2, "--times", "0", "90", "1e9", "--fit"])
        check(rc == 0, "plot_fsd --times --fit exits 0 (%d): %s" % (rc, out))
        check_png(png2, "three frames with fits")
        missing = os.path.join(tmp, "nope.csv")
        rc, out = run(script, [missing, "-o", os.path.join(tmp, "x.png")])
        check(rc == 1 and "nope.csv" in out, "a missing file: exit 1 naming it (%d: %s)" % (rc, out.strip()))
        bad = os.path.join(tmp, "bad.csv")
        with open(bad, "w") as f:
            f.write("a,b,c\n1,2,3\n")
        rc, out = run(script, [bad, "-o", os.path.join(tmp, "y.png")])
        check(rc == 1 and "not a floe_sizes CSV" in out, "a wrong CSV: exit 1 with a message (%d: %s)" % (rc, out.strip()))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("test_plot_fsd")


if __name__ == "__main__":
    main()
