#!/usr/bin/env python3
"""The installed library (issue 11, "A public API"): `cmake --install` into a temporary
prefix puts only public headers under include/floe (no internal header, and every include
of an installed header resolves inside the installed set); then a small C program that
loads a scene from a string, steps it and reads the world through the public view
(floe_view.h) is built twice against the installed tree, (a) with
`cc $(pkg-config --cflags --libs floe)` and (b) as a CMake project with find_package(floe),
and both must run and print the same checked figures.

argv[1]: the floe CLI (in the build directory), argv[2]: the tests directory."""
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pycheck import build_dir_of, cmake_cache  # noqa: E402

CLI, TESTS = sys.argv[1], sys.argv[2]
FAILED = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        FAILED.append(what)
    return cond


def run(cmd, **kw):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, **kw)
    return r.returncode, r.stdout


# The program: a sphere resting on a wall under gravity, placed at its static Hertz overlap
# (d = (3 m g / (4 E* sqrt(R)))^(2/3) = 0.58 um, E* = E / (2 (1 - nu^2))), 200 steps of
# 10 us; it prints what the view reads and checks it: one contact whose normal force is the
# weight within 5 % (the residual oscillation, period 1.25 ms, damped by e = 0.5, is about
# 1 %), the sphere between 0.99 and 1 radius above the wall. Its checks set the exit status.
PROGRAM = r"""
#include "floe.h"
#include "floe_newmark.h"
#include <math.h>
#include <stdio.h>

static const char *scene =
    "name: install\n"
    "dimension: 3\n"
    "time: {duration: 0.002, dt: 1.0e-5}\n"
    "gravity: [0, 0, -9.81]\n"
    "materials:\n"
    "  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}\n"
    "laws:\n"
    "  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}\n"
    "walls:\n"
    "  - {point: [0, 0, 0], normal: [0, 0, 1], material: glass}\n"
    "bodies:\n"
    "  - {shape: {sphere: {radius: 0.001}}, material: glass, position: [0, 0, 0.00099942]}\n";

int main(void) {
    char err[1024];
    floe_world *w = NULL;
    floe_scene_info info;
    if (floe_scene_load_ex("install.yaml", scene, NULL, 0, &w, &info, err, sizeof err)) {
        printf("load failed: %s\n", err);
        return 1;
    }
    /* the sparse solver's code is linked too (CHOLMOD when the library has it) */
    floe_newmark_def nd = floe_newmark_default_def();
    floe_newmark *nm = floe_newmark_create(&nd, err, sizeof err);
    floe_newmark_destroy(nm);
    floe_world_record_contacts(w, 1);
    int rc = 0;
    for (int s = 0; s < 200 && !rc; s++) rc = floe_world_step(w);
    if (rc) {
        printf("step failed: %s\n", floe_world_last_error(w));
        return 1;
    }
    floe_particles_view pv;
    floe_world_particles(w, &pv);
    const floe_contact_info *c = NULL;
    int nc = floe_world_contacts(w, &c);
    int sphere = isinf(pv.radius[0]) ? 1 : 0;
    double z = pv.x[3 * sphere + 2];
    printf("particles %d dim %d steps %ld contacts %d\n", pv.n, pv.dim, floe_world_step_count(w), nc);
    printf("sphere z %.6e m radius %.3e m mass %.6e kg\n", z, pv.radius[sphere], pv.mass[sphere]);
    printf("contact normal force %.6e N weight %.6e N\n", nc > 0 ? c[0].fn : 0.0, pv.mass[sphere] * 9.81);
    double weight = pv.mass[sphere] * 9.81;
    int ok = pv.n == 2 && nc == 1 && nc == floe_world_contact_count(w) && z > 0.00099 && z < 0.001 &&
             fabs(c[0].fn - weight) < 0.05 * weight;
    floe_world_destroy(w);
    printf("%s\n", ok ? "view ok" : "view WRONG");
    return ok ? 0 : 1;
}
"""

CMAKE_PROJECT = """cmake_minimum_required(VERSION 3.18)
project(floe_install_check C)
find_package(floe REQUIRED)
add_executable(check main.c)
target_link_libraries(check PRIVATE floe::floe)
"""


def main():
    builddir = build_dir_of(CLI)
    if not check(builddir is not None, "build directory found above the CLI (%s)" % CLI):
        return 1
    cc = cmake_cache(builddir)
    if cc.get("FLOE_FUZZ", "OFF").upper() in ("ON", "1", "TRUE"):
        # the fuzzing build instruments the library for libFuzzer: no plain program links it
        print("skipped: FLOE_FUZZ build")
        return 0
    compiler = cc.get("CMAKE_C_COMPILER", "cc")
    extra = []
    if cc.get("FLOE_SANITIZE", "OFF").upper() in ("ON", "1", "TRUE"):
        extra = ["-fsanitize=address,undefined"]
    tmp = tempfile.mkdtemp(prefix="floe-install-")
    try:
        prefix = os.path.join(tmp, "prefix")
        rc, out = run(["cmake", "--install", builddir, "--prefix", prefix])
        if not check(rc == 0, "cmake --install into a temporary prefix"):
            print(out[-3000:])
            return 1
        inc = os.path.join(prefix, "include", "floe")
        headers = sorted(os.listdir(inc))
        print("installed headers: " + " ".join(headers))
        check("floe.h" in headers and "floe_view.h" in headers and "floe_world.h" in headers,
              "floe.h, floe_world.h and floe_view.h installed")
        check(all(h == "floe.h" or h.startswith("floe_") for h in headers),
              "only public headers (floe.h, floe_*.h) installed")
        for internal in ("world_internal.h", "particle_store.h", "beam_set.h", "geometry_internal.h",
                         "file_writer.h"):
            check(internal not in headers, "internal header %s not installed" % internal)
        missing = []
        for h in headers:
            with open(os.path.join(inc, h)) as f:
                for m in re.finditer(r'^\s*#\s*include\s+"([^"]+)"', f.read(), re.M):
                    if m.group(1) not in headers:
                        missing.append("%s -> %s" % (h, m.group(1)))
        check(not missing, "every include of a public header is a public header (%s)" % (", ".join(missing) or "none"))

        src = os.path.join(tmp, "main.c")
        with open(src, "w") as f:
            f.write(PROGRAM)
        env = dict(os.environ)
        pcdirs = [os.path.join(prefix, d, "pkgconfig") for d in ("lib", "lib64", cc.get("CMAKE_INSTALL_LIBDIR", "lib"))]
        env["PKG_CONFIG_PATH"] = os.pathsep.join(pcdirs + [env.get("PKG_CONFIG_PATH", "")])
        rc, flags = run(["pkg-config", "--cflags", "--libs", "floe"], env=env)
        check(rc == 0, "pkg-config --cflags --libs floe: %s" % flags.strip())
        rcs, sflags = run(["pkg-config", "--libs", "--static", "floe"], env=env)
        check(rcs == 0 and "-lfloe" in sflags and "-lfyaml" in sflags and "-lm" in sflags.split(),
              "pkg-config --libs --static floe names floe, libfyaml and libm: %s" % sflags.strip())
        outputs = {}
        # (a) the compiler with pkg-config's flags; (b) the same, with the static link line
        _, cflags = run(["pkg-config", "--cflags", "floe"], env=env)
        for name, fl in (("pkg-config", flags), ("pkg-config --static", cflags + " " + sflags)):
            exe = os.path.join(tmp, "check_pc" if name == "pkg-config" else "check_pcs")
            rc, out = run([compiler, src, "-o", exe] + extra + fl.split())
            if not check(rc == 0, "link with %s (%s)" % (name, compiler)):
                print(out[-3000:])
                continue
            rc, out = run([exe], cwd=tmp)
            print(out.rstrip())
            check(rc == 0 and "view ok" in out, "the %s program runs and reads the view" % name)
            outputs[name] = out
        # (c) a CMake project with find_package(floe)
        proj = os.path.join(tmp, "proj")
        os.makedirs(proj)
        shutil.copy(src, os.path.join(proj, "main.c"))
        with open(os.path.join(proj, "CMakeLists.txt"), "w") as f:
            f.write(CMAKE_PROJECT)
        bdir = os.path.join(tmp, "proj-build")
        cfg = ["cmake", "-S", proj, "-B", bdir, "-DCMAKE_PREFIX_PATH=" + prefix, "-DCMAKE_C_COMPILER=" + compiler,
               "-DCMAKE_BUILD_TYPE=Release"]
        if extra:
            cfg += ["-DCMAKE_C_FLAGS=" + " ".join(extra), "-DCMAKE_EXE_LINKER_FLAGS=" + " ".join(extra)]
        rc, out = run(cfg)
        if check(rc == 0, "find_package(floe) configures"):
            rc, out = run(["cmake", "--build", bdir])
            if check(rc == 0, "the find_package(floe) project builds"):
                rc, out = run([os.path.join(bdir, "check")], cwd=tmp)
                print(out.rstrip())
                check(rc == 0 and "view ok" in out, "the find_package(floe) program runs and reads the view")
                outputs["cmake"] = out
            else:
                print(out[-3000:])
        else:
            print(out[-3000:])
        check(len(outputs) == 3 and len(set(outputs.values())) == 1,
              "the three builds print the same figures (%d of 3 ran)" % len(outputs))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print("test_install: %d failed" % len(FAILED))
    return 1 if FAILED else 0


if __name__ == "__main__":
    sys.exit(main())
