#!/usr/bin/env python3
"""bench/machine/lanes.py: are the lane kernels still vector code?

The contact stage's sphere lanes (core/world/forces.c sph_flush_lanes) and the integrator's
particle lanes (core/integrators/step.c drift_lanes_body, kick_lanes, kick_lanes_aniso) are
written so that the compiler runs each loop over a batch (`for (int q = 0; q < SL; q++)`, `... < IL; ...`) in
vector registers. Nothing fails when one of them silently goes scalar: the results are the
same bits, only slower. From session 20 (50ff56b) to session 29 the kinematics loop of
sph_flush_lanes ran scalar in every sphere scene (a load under a select became a masked load
GCC could not vectorize) and the RVE was 15 % slower; no test could see it.

This script compiles those files with the flags of a CMake build (default build-bench, the
Release build the benchmarks use) and GCC's -fopt-info-vec, and checks that every batch loop
of the listed functions is reported vectorized (a loop GCC replaces by a library call, such as one that only
zeroes an array, has no report and is listed as such). Run it before a timing sitting:

    python3 bench/machine/lanes.py [BUILD_DIR]

Exit status 0 when all are vectorized, 1 otherwise (each scalar loop named with GCC's
reason), 2 when the build's flags cannot be read.
"""
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# file -> the functions whose batch loops must be vector code
KERNELS = {
    "core/world/forces.c": ["sph_flush_lanes"],
    "core/integrators/step.c": ["drift_lanes_body", "kick_lanes", "kick_lanes_aniso"],
}
BATCH_LOOP = re.compile(r"for \(int [a-z]+ = 0; [a-z]+ < (SL|IL|SPH_BATCH); [a-z]+\+\+\)")


def build_flags(build):
    fm = os.path.join(build, "CMakeFiles", "floe.dir", "flags.make")
    try:
        text = open(fm).read()
    except OSError as e:
        print(f"lanes.py: cannot read {fm} ({e.strerror}): configure a build first "
              "(cmake -S . -B build-bench -DCMAKE_BUILD_TYPE=Release)", file=sys.stderr)
        sys.exit(2)
    flags = []
    for key in ("C_DEFINES", "C_INCLUDES", "C_FLAGS"):
        m = re.search(rf"^{key} = (.*)$", text, re.M)
        if m:
            flags += m.group(1).split()
    return flags


def function_lines(src, name):
    """first and last line (1-based) of the definition of function `name`: a line at column 0
    naming it (not a prototype), up to the next line that starts with a closing brace"""
    lines = src.split("\n")
    for n, line in enumerate(lines):
        if re.match(r"^[A-Za-z_]", line) and re.search(rf"\b{name}\(", line) and not line.rstrip().endswith(";"):
            for e in range(n + 1, len(lines)):
                if lines[e].startswith("}"):
                    return n + 1, e + 1
    return None


def batch_loops(lines, span):
    """the lines (1-based) where GCC reports each batch loop of the span: the loop's own line,
    or, for a loop inside a macro defined there (sph_flush_lanes' copies of a loop for each
    value of a constant: LIN_TRIAL, LANES_OUT), each line that uses the macro"""
    out, in_macro, macros = [], None, {}  # out: (line, a macro's use)
    for n in range(span[0] - 1, span[1]):
        line = lines[n]
        u = re.match(r"\s*#\s*undef ([A-Za-z_0-9]+)", line)
        if u:
            macros.pop(u.group(1), None)
            continue
        m = re.match(r"\s*#\s*define ([A-Za-z_0-9]+)\(", line)
        if m:
            in_macro = m.group(1)
            macros[in_macro] = False
        if in_macro:
            macros[in_macro] |= bool(BATCH_LOOP.search(line))
            if not line.rstrip().endswith("\\"):
                in_macro = None
            continue
        if BATCH_LOOP.search(line):
            out.append((n + 1, False))
        elif any(v and re.search(rf"\b{k}\(", line) for k, v in macros.items()):
            out.append((n + 1, True))
    return out


def main():
    build = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build-bench"))
    flags = build_flags(build)
    bad = 0
    for rel, funcs in KERNELS.items():
        path = os.path.join(ROOT, rel)
        src = open(path).read()
        lines = src.split("\n")
        with tempfile.TemporaryDirectory() as tmp:
            r = subprocess.run(["cc", *flags, "-fopt-info-vec-all", "-c", path, "-o", os.path.join(tmp, "x.o")],
                               cwd=build, capture_output=True, text=True)
        if r.returncode != 0:
            print(f"lanes.py: compiling {rel} failed:\n{r.stderr[-2000:]}", file=sys.stderr)
            sys.exit(2)
        vec, why = set(), {}
        for m in re.finditer(rf"{re.escape(path)}:(\d+):\d+: (optimized|missed): (.*)", r.stderr):
            ln, kind, msg = int(m.group(1)), m.group(2), m.group(3)
            if kind == "optimized" and "loop vectorized" in msg:
                vec.add(ln)
            elif kind == "missed":  # the analysis gave up on the loop at this line (the last reason kept)
                why[ln] = msg.strip()
        for f in funcs:
            span = function_lines(src, f)
            if span is None:
                print(f"{rel}: function {f} not found (renamed? update KERNELS in this script)")
                bad += 1
                continue
            loops = batch_loops(lines, span)
            for ln, use in loops:
                if ln in vec:
                    print(f"{rel}:{ln}: {f}: vector")
                elif ln in why and "__builtin_mem" not in why[ln]:
                    print(f"{rel}:{ln}: {f}: SCALAR ({why[ln]})")
                    bad += 1
                elif use:  # a macro's copy of a batch loop with no report: not known to be vector code
                    print(f"{rel}:{ln}: {f}: NO REPORT for the macro's batch loop")
                    bad += 1
                else:  # e.g. a loop that only zeroes, made a memset call
                    print(f"{rel}:{ln}: {f}: no loop left to report (a library call, or unrolled)")
    print("lanes: all batch loops vectorized" if bad == 0 else f"lanes: {bad} batch loop(s) not vectorized")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
