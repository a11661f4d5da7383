"""test_triaxial.py - a small, quick version of examples/triaxial-periodic (drained triaxial
compression of a dense sphere packing, in a periodic cell and in a box of frictionless servo
walls; docs/granular.md, "Triaxial compression"), through the Python package (floe.RVE).

300 spheres (radii uniform in [4, 6] mm, kn = 1e5 N/m, mu = 0.3), compacted without friction
to 10 kPa, sheared to 8 % axial (log) strain at an inertial number of 2e-3. What is robust at
this size (the tolerances come from six placements, seeds 1-6, measured 2026-12-02; see the
example's README):
  - the lateral stresses held at 10 kPa: mean within 1 % (measured <= 0.06 % periodic,
    <= 0.16 % walled), largest deviation within 3 % periodic (1.3-1.6 %) and 6 % walled
    (2.0-4.1 %);
  - the periodic sample starts at random close packing: porosity in [0.35, 0.37]
    (measured 0.357-0.361);
  - peak sin(phi) = (s1 - s3) / (s1 + s3): periodic in [0.36, 0.52] (0.411-0.475, mean
    0.442, sd 0.024), walled in [0.27, 0.45] (0.335-0.408), and the periodic peak above the
    walled one (by 0.015-0.14 in all six);
  - dilation after the peak: eps_v at the end below -0.015 periodic (-0.030 to -0.041) and
    -0.008 walled (-0.015 to -0.028), the largest sin(psi) above 0.12 periodic (0.19-0.27)
    and 0.08 walled (0.16-0.26).
These bands were measured before the linear dashpot's static fix (docs/models.md, "Static
stiffness"); the test passes with it. The test's own placement (the scenes' seed 7) gave then,
deterministically: peak sin(phi) 0.463
periodic and 0.397 walled, eps_v -0.035 and -0.030, sin(psi) 0.226 and 0.246, lateral
stress mean 0.022 % and 0.033 % off (largest 1.3 % and 2.7 %).

And the analytical check: a face-centred cubic array of equal spheres (fcc.yaml, 108 spheres,
cube axes on x, y, z) compressed along z fails at s1/s3 = 2 (1 + mu) / (1 - mu) (Thornton 1979,
Geotechnique 29(4):441-459): the largest ratio within 2 % (measured -0.51 % at mu = 0.3).

Python tests do not run under the sanitizers (the interpreter cannot open an ASan library):
in a FLOE_SANITIZE build, or without libfloe.so (FLOE_BUILD_PYTHON=OFF), it says so and
exits 77, which ctest reports as skipped."""
import importlib.util
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from pycheck import build_dir_of, check, cmake_cache, finish  # noqa: E402


def main():
    cli, tests = sys.argv[1], sys.argv[2]
    root = os.path.dirname(os.path.abspath(tests))
    bdir = build_dir_of(cli)
    cc = cmake_cache(bdir) if bdir else {}
    so = os.path.join(bdir or "", "libfloe.so")
    if cc.get("FLOE_SANITIZE", "OFF").upper() in ("ON", "1", "TRUE") or not os.path.exists(so):
        print("test_triaxial: skipped (a sanitizer build, or no libfloe.so: FLOE_BUILD_PYTHON=OFF)")
        return 77
    try:
        import numpy  # noqa: F401
        import cffi  # noqa: F401
    except ImportError:
        # ctest's python3 may not be the one with numpy and cffi (CMakeLists.txt: Debian's)
        if os.path.exists("/usr/bin/python3") and os.path.realpath(sys.executable) != "/usr/bin/python3":
            os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
        print("test_triaxial: skipped (no numpy or cffi for %s)" % sys.executable)
        return 77
    os.environ["FLOE_LIBRARY"] = so
    spec = importlib.util.spec_from_file_location(
        "triaxial", os.path.join(root, "examples", "triaxial-periodic", "triaxial.py"))
    tx = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tx)
    import numpy as np

    out = os.path.join(os.getcwd(), "test_triaxial_out")
    os.makedirs(out, exist_ok=True)
    inertial, strain, n, every = 2e-3, 0.08, 300, 250
    rate = inertial / (tx.D_MEAN * np.sqrt(tx.RHO / tx.P0))
    log = print
    rows_p, m0 = tx.run_periodic(n, strain, rate, every, os.path.join(out, "periodic"), log)
    rp = tx.analyse(rows_p)
    tx.report("periodic", rp, log)
    rows_w = tx.run_walled(n, strain, rate, every, os.path.join(out, "walled"), log)
    rw = tx.analyse(rows_w)
    tx.report("walled", rw, log)

    # the analytical check: an FCC array (108 spheres, cube axes on x, y, z) fails at
    # s1/s3 = 2 (1 + mu) / (1 - mu) (Thornton 1979); measured -0.51 % at mu = 0.3 (-0.35 % at
    # mu = 0, -0.81 % at 0.5: the contacts' finite stiffness and the sampling of the records)
    rows_f, mf = tx.run_periodic(None, 0.03, 8e-4 / (tx.D_MEAN * np.sqrt(tx.RHO / tx.P0)), 100,
                                 os.path.join(out, "fcc"), log, scene="fcc.yaml")
    ratio = float(np.max(rows_f[:, 5] / rows_f[:, 6]))
    exact = 2 * 1.3 / 0.7
    check(abs(mf["coordination"] - 12) < 1e-9, "fcc: coordination %.3f = 12" % mf["coordination"])
    check(abs(ratio / exact - 1) < 0.02, "fcc: largest s1/s3 %.4f within 2 %% of 2 (1 + mu) / (1 - mu) = %.4f"
          % (ratio, exact))

    check(0.35 <= m0["porosity"] <= 0.37, "periodic: prepared porosity %.4f in [0.35, 0.37]" % m0["porosity"])
    check(rp["servo_mean"] < 0.01, "periodic: lateral stress mean off by %.3f %% < 1 %%" % (100 * rp["servo_mean"]))
    check(rp["servo_max"] < 0.03, "periodic: lateral stress largest deviation %.2f %% < 3 %%" % (100 * rp["servo_max"]))
    check(rw["servo_mean"] < 0.01, "walled: lateral stress mean off by %.3f %% < 1 %%" % (100 * rw["servo_mean"]))
    check(rw["servo_max"] < 0.06, "walled: lateral stress largest deviation %.2f %% < 6 %%" % (100 * rw["servo_max"]))
    check(0.36 <= rp["peak"] <= 0.52, "periodic: peak sin(phi) %.3f in [0.36, 0.52]" % rp["peak"])
    check(0.27 <= rw["peak"] <= 0.45, "walled: peak sin(phi) %.3f in [0.27, 0.45]" % rw["peak"])
    check(rp["peak"] > rw["peak"], "periodic peak %.3f above the walled %.3f" % (rp["peak"], rw["peak"]))
    check(rp["ev_end"] < -0.015, "periodic: dilated, eps_v %.4f < -0.015 at the end" % rp["ev_end"])
    check(rw["ev_end"] < -0.008, "walled: dilated, eps_v %.4f < -0.008 at the end" % rw["ev_end"])
    check(rp["sin_psi"] > 0.12, "periodic: largest sin(psi) %.3f > 0.12" % rp["sin_psi"])
    check(rw["sin_psi"] > 0.08, "walled: largest sin(psi) %.3f > 0.08" % rw["sin_psi"])
    finish("test_triaxial")


if __name__ == "__main__":
    sys.exit(main())
