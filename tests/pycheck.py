"""pycheck.py - the Python tests' harness: check(cond, msg) counts a pass or prints a
failure; run(args) runs a command; finish(name) prints "N passed, N failed" and exits;
build_dir_of(cli) and cmake_cache(builddir) find the build a CLI belongs to and read its
CMakeCache.txt."""
import os
import re
import subprocess
import sys

counts = {"passed": 0, "failed": 0}


def check(cond, msg):
    if cond:
        counts["passed"] += 1
    else:
        counts["failed"] += 1
        print("FAIL: " + msg, file=sys.stderr)
    return cond


def run(args, cwd=None, timeout=300):
    p = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=cwd,
                       timeout=timeout, universal_newlines=True)
    return p.returncode, p.stdout, p.stderr


def finish(name):
    print("%s: %d passed, %d failed" % (name, counts["passed"], counts["failed"]))
    sys.exit(1 if counts["failed"] else 0)


def build_dir_of(cli):
    """The build directory (the one holding CMakeCache.txt) above the CLI's path, or None."""
    d = os.path.dirname(os.path.abspath(cli))
    while d != os.path.dirname(d):
        if os.path.exists(os.path.join(d, "CMakeCache.txt")):
            return d
        d = os.path.dirname(d)
    return None


def cmake_cache(builddir):
    """CMakeCache.txt as {NAME: value}."""
    vals = {}
    with open(os.path.join(builddir, "CMakeCache.txt")) as f:
        for line in f:
            m = re.match(r"^([A-Za-z_0-9]+):[A-Z]+=(.*)$", line.rstrip("\n"))
            if m:
                vals[m.group(1)] = m.group(2)
    return vals
