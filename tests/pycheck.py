"""pycheck.py - the Python tests' harness: check(cond, msg) counts a pass or prints a
failure; run(args) runs a command; finish(name) prints "N passed, N failed" and exits."""
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
