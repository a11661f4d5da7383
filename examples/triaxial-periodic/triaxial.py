#!/usr/bin/env python3
"""triaxial.py - drained triaxial compression of a dense sphere packing, in a periodic cell
and in a box of frictionless servo walls, side by side (examples/triaxial-periodic/README.md,
docs/granular.md "Triaxial compression").

Both samples are the same 1,000 spheres (radii uniform in [4, 6] mm, linear contacts
kn = 1e5 N/m, mu = 0.3), compacted WITHOUT friction to p0 = 10 kPa by the scene's `prepare`
block (the cell's stress servo; the walls' servos), friction switched on, then sheared:

  periodic.yaml  L_zz = -rate (constant true strain rate), sigma_xx = sigma_yy = -p0 held by
                 the cell's servo, the shear components of L fixed at 0;
  walled.yaml    the z walls move in at speeds that keep the same true strain rate, the four
                 side walls are servo walls at p0; every wall frictionless.

Recorded every `--every` steps: principal stresses s1 >= s3 (compression positive), the
mobilised friction sin(phi) = (s1 - s3) / (s1 + s3), q/p, the axial strain eps_a = ln(H0/H)
and the volumetric strain eps_v = ln(V0/V) (compression positive). Reported: the peak and
residual (mean over the last fifth of the axial strain) friction angles, the largest
dilatancy angle sin(psi) = -d eps_v / (2 d eps_a - d eps_v) (slopes over 1 % of axial strain),
the inertial number I = rate d sqrt(rho / p0), and how well the confining stress was held.

Run:  FLOE_LIBRARY=build/libfloe.so /usr/bin/python3 examples/triaxial-periodic/triaxial.py
      [--n 1000] [--strain 0.25] [--inertial 8e-4] [--which both|periodic|walled] [--out DIR]
"""
import argparse
import os
import re
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "python"))
if "FLOE_LIBRARY" not in os.environ and os.path.exists(os.path.join(ROOT, "build", "libfloe.so")):
    os.environ["FLOE_LIBRARY"] = os.path.join(ROOT, "build", "libfloe.so")

import floe  # noqa: E402
from floe._api import lib  # noqa: E402

RHO = 2650.0     # grain density, kg/m^3 (the scenes')
P0 = 1.0e4       # confining pressure, Pa (the scenes')
D_MEAN = 0.010   # mean diameter, m (radii uniform in [4, 6] mm)
CONTROL = 100    # steps between the updates of the lateral targets (outer integral loop)


def scene_text(name, n, seed=None, friction=None):
    """The scene's YAML with the particle count replaced by n (the region scaled so the
    initial solid fraction stays the same), the placement's seed by seed and the friction
    switched on after the compaction by friction."""
    text = open(os.path.join(HERE, name)).read()
    if friction is not None:
        text = text.replace("then: {friction: 0.3}", "then: {friction: %g}" % friction)
    if seed is not None:
        text = re.sub(r"seed: 7\b", "seed: %d" % seed, text)
    if n is None:
        return text
    n0 = int(re.search(r"count: (\d+)", text).group(1))
    s = (n / n0) ** (1.0 / 3.0)
    text = re.sub(r"count: \d+", "count: %d" % n, text)

    def scale(m):
        return "%.6g" % (float(m.group(0)) * s)
    # every length of the box / cell (0.12 m), not the radii
    return re.sub(r"(?<![\d.])0\.12(?![\d])", scale, text)


def principal(sigma):
    """Principal stresses, compression positive, largest first."""
    return np.sort(np.linalg.eigvalsh(-0.5 * (sigma + sigma.T)))[::-1]


# ---------------------------------------------------------------------------------------
def run_periodic(n, strain, rate, every, outdir, log, seed=None, friction=None, scene="periodic.yaml"):
    t0 = time.time()
    rve = floe.RVE.from_string(scene_text(scene, n, seed, friction), path=os.path.join(HERE, scene),
                               outdir=outdir, outputs=True)
    w = rve.world
    m0 = rve.measures()
    name = scene.split(".")[0]
    log("%s: %d spheres prepared in %.1f s: porosity %.4f, coordination %.2f, sigma %s Pa"
        % (name, m0["particles"], time.time() - t0, m0["porosity"], m0["coordination"],
           np.array2string(np.diag(m0["sigma"]), precision=0)))
    _, H0 = rve.cell()
    V0 = rve.volume
    L = np.zeros((3, 3))
    L[2, 2] = -rate
    # xx, yy held at -P0 by the cell's servo (default time, 50 steps; its largest rate ten
    # times the axial rate). A first-order servo lags a stress that the loading keeps pushing,
    # by (d sigma / dt) tau: ~8 % of p0 at I = 2e-3. An outer integral loop on its targets,
    # every CONTROL steps, takes that steady error away: target += (P0 - p_lateral) / 2.
    target = [P0, P0]

    def control():
        rve.set_control(rate=L, stress={(0, 0): -target[0], (1, 1): -target[1]}, max_rate=10 * rate)
    control()
    rows = []
    nsteps = int(np.ceil(strain / (rate * w.dt)))
    t1 = time.time()
    k = 0
    while True:
        if k % every == 0:
            m = rve.measures()
            _, H = rve.cell()
            s = principal(m["sigma"])
            rows.append((np.log(H0[2, 2] / H[2, 2]), np.log(V0 / rve.volume), m["sigma"][0, 0], m["sigma"][1, 1],
                         m["sigma"][2, 2], s[0], s[2], m["porosity"], m["coordination"], m["fabric"][2, 2]))
        if k >= nsteps:
            break
        if k:
            sig = rve.stress()
            for a in range(2):
                target[a] = min(max(target[a] + 0.5 * (P0 + sig[a, a]), 0.5 * P0), 1.5 * P0)
            control()
        n = min(CONTROL, nsteps - k)
        w.step(n)
        k += n
    log("%s: %d steps in %.1f s (%.2f us per particle-step)"
        % (name, nsteps, time.time() - t1, 1e6 * (time.time() - t1) / (nsteps * m0["particles"])))
    return np.array(rows), m0


# ---------------------------------------------------------------------------------------
def walls_of(w):
    """{(axis, 0|1): particle id} of the box's six walls (radius inf), given in the scene in
    the order x0 x1 y0 y1 z0 z1 (checked: each pair apart along its own axis)."""
    p = w.particles()
    ids = [i for i in range(w.n) if not np.isfinite(p.radius[i])]
    if len(ids) != 6:
        raise RuntimeError("walled.yaml: six walls expected, found %d" % len(ids))
    out = {}
    for a in range(3):
        out[(a, 0)], out[(a, 1)] = ids[2 * a], ids[2 * a + 1]
        if not p.x[ids[2 * a + 1]][a] > p.x[ids[2 * a]][a]:
            raise RuntimeError("walled.yaml: walls %d, %d are not the pair of axis %d"
                               % (ids[2 * a], ids[2 * a + 1], a))
    return out


def box(w, walls):
    x = w.particles().x
    return np.array([x[walls[(a, 1)]][a] - x[walls[(a, 0)]][a] for a in range(3)])


def run_walled(n, strain, rate, every, outdir, log, seed=None, friction=None):
    t0 = time.time()
    w = floe.World.from_string(scene_text("walled.yaml", n, seed, friction), path=os.path.join(HERE, "walled.yaml"),
                               outdir=outdir, outputs=True)
    w.record_contacts(True)
    w.prepare()
    walls = walls_of(w)
    lib().floe_world_refresh_forces(w.ptr)
    L0 = box(w, walls)
    V0 = np.prod(L0)
    solid = float(np.sum(4.0 / 3.0 * np.pi * w.particles().radius[np.isfinite(w.particles().radius)] ** 3))

    def pressures():
        return np.array([[lib().floe_world_wall_pressure(w.ptr, walls[(a, k)]) for k in range(2)] for a in range(3)])

    pr = pressures()
    log("walled: %d spheres prepared in %.1f s: porosity %.4f, box %s m, wall pressures %s Pa"
        % (w.n - 6, time.time() - t0, 1 - solid / V0, np.array2string(L0, precision=4),
           np.array2string(pr.ravel(), precision=0)))
    rows = []
    nsteps = int(np.ceil(strain / (rate * w.dt)))
    # The side walls' servos are proportional: under a steady loading they lag by the speed
    # the wall needs over their gain (~15 % of p0 at I = 2e-3). An outer integral loop on
    # their targets, every CONTROL steps, takes that steady error away: P_set += (P0 - p) / 2.
    target = {(a, j): P0 for a in range(2) for j in range(2)}
    t1 = time.time()
    k = 0
    while True:
        Lb = box(w, walls)
        if k % every == 0:
            pr = pressures()
            sig = -np.diag(pr.mean(axis=1))          # tension positive, as the cell's
            s = principal(sig)
            rows.append((np.log(L0[2] / Lb[2]), np.log(V0 / np.prod(Lb)), sig[0, 0], sig[1, 1], sig[2, 2],
                         s[0], s[2], 1 - solid / np.prod(Lb), np.nan, np.nan))
        if k >= nsteps:
            break
        # both z walls move in, together at rate x height (a constant true strain rate)
        for j in range(2):
            w.check(lib().floe_world_servo_set_speed(w.ptr, walls[(2, j)], -0.5 * rate * Lb[2]))
        if k:
            for key in target:
                target[key] += 0.5 * (P0 - lib().floe_world_wall_pressure(w.ptr, walls[key]))
                target[key] = min(max(target[key], 0.5 * P0), 1.5 * P0)
                w.check(lib().floe_world_servo_set_pressure(w.ptr, walls[key], target[key]))
        n = min(CONTROL, nsteps - k)
        w.step(n)
        k += n
    log("walled: %d steps in %.1f s" % (nsteps, time.time() - t1))
    return np.array(rows)


# ---------------------------------------------------------------------------------------
def analyse(rows, window=0.01):
    """peak and residual sin(phi), angles; largest dilatancy angle; servo error."""
    ea, ev, sxx, syy = rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3]
    s1, s3 = rows[:, 5], rows[:, 6]
    sphi = (s1 - s3) / (s1 + s3)
    k = 5  # moving average over 5 records for the peak (noise of a small sample)
    smooth = np.convolve(sphi, np.ones(k) / k, mode="valid")
    ipk = int(np.argmax(smooth)) + k // 2
    peak = float(np.max(smooth))
    end = ea[-1]
    res_sel = ea >= 0.8 * end
    res = float(np.mean(sphi[res_sel]))
    res_sd = float(np.std(sphi[res_sel]))
    # dilatancy: slopes d ev / d ea over a window of axial strain
    sin_psi = np.full(len(ea), np.nan)
    for i in range(len(ea)):
        sel = np.abs(ea - ea[i]) <= window / 2
        if ea[i] - window / 2 < ea[0] or ea[i] + window / 2 > end or sel.sum() < 3:
            continue
        dv = np.polyfit(ea[sel], ev[sel], 1)[0]
        sin_psi[i] = -dv / (2.0 - dv)
    ipsi = int(np.nanargmax(sin_psi))
    lat = np.concatenate([sxx[1:], syy[1:]])
    servo = float(np.max(np.abs(-lat - P0)) / P0)
    servo_mean = float(max(abs(np.mean(-sxx[1:]) - P0), abs(np.mean(-syy[1:]) - P0)) / P0)
    deg = np.degrees
    return dict(peak=peak, phi_peak=float(deg(np.arcsin(peak))), ea_peak=float(ea[ipk]),
                res=res, res_sd=res_sd, phi_res=float(deg(np.arcsin(res))),
                sin_psi=float(sin_psi[ipsi]), psi_max=float(deg(np.arcsin(sin_psi[ipsi]))),
                ea_psi=float(ea[ipsi]), ev_min=float(np.min(ev)), ev_end=float(ev[-1]),
                ea_end=float(end), servo_max=servo, servo_mean=servo_mean,
                q_p_peak=float(6 * peak / (3 - peak)), q_p_res=float(6 * res / (3 - res)))


def report(name, r, log):
    log("%-8s peak sin(phi) %.3f (phi %.1f deg, q/p %.3f) at eps_a %.3f; residual %.3f +- %.3f (phi %.1f deg, q/p %.3f)"
        % (name, r["peak"], r["phi_peak"], r["q_p_peak"], r["ea_peak"], r["res"], r["res_sd"], r["phi_res"],
           r["q_p_res"]))
    log("%-8s max dilatancy sin(psi) %.3f (psi %.1f deg) at eps_a %.3f; eps_v min %.4f, at the end %.4f (eps_a %.3f)"
        % (name, r["sin_psi"], r["psi_max"], r["ea_psi"], r["ev_min"], r["ev_end"], r["ea_end"]))
    log("%-8s lateral stress vs %.0f Pa: largest deviation %.2f %%, mean %.3f %%"
        % (name, P0, 100 * r["servo_max"], 100 * r["servo_mean"]))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=None, help="spheres (default: the scenes' 1,000)")
    ap.add_argument("--strain", type=float, default=0.25, help="axial (log) strain to reach")
    ap.add_argument("--inertial", type=float, default=8e-4, help="inertial number I = rate d sqrt(rho/p)")
    ap.add_argument("--seed", type=int, default=None, help="the placement's seed (default: the scenes' 7)")
    ap.add_argument("--friction", type=float, default=None, help="mu for the test (default: the scenes' 0.3)")
    ap.add_argument("--every", type=int, default=500, help="steps between records")
    ap.add_argument("--which", choices=["both", "periodic", "walled", "fcc"], default="both",
                    help="fcc: the analytical check, a face-centred cubic array (fcc.yaml; --n ignored)")
    ap.add_argument("--out", default="out/triaxial-periodic")
    a = ap.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    rate = a.inertial / (D_MEAN * np.sqrt(RHO / P0))

    def log(msg):
        print(msg, flush=True)

    log("axial strain rate %.4g 1/s: inertial number I = rate d sqrt(rho/p) = %.2g (d %.3g m, rho %g, p %g Pa)"
        % (rate, a.inertial, D_MEAN, RHO, P0))
    res = {}
    head = "eps_a,eps_v,sigma_xx,sigma_yy,sigma_zz,s1,s3,porosity,coordination,fabric_zz"
    if a.which in ("both", "periodic"):
        rows, _ = run_periodic(a.n, a.strain, rate, a.every, os.path.join(a.out, "periodic"), log, a.seed, a.friction)
        np.savetxt(os.path.join(a.out, "periodic.csv"), rows, delimiter=",", header=head, comments="")
        res["periodic"] = analyse(rows)
        report("periodic", res["periodic"], log)
    if a.which in ("both", "walled"):
        rows = run_walled(a.n, a.strain, rate, a.every, os.path.join(a.out, "walled"), log, a.seed, a.friction)
        np.savetxt(os.path.join(a.out, "walled.csv"), rows, delimiter=",", header=head, comments="")
        res["walled"] = analyse(rows)
        report("walled", res["walled"], log)
    if a.which == "fcc":
        rows, _ = run_periodic(None, a.strain, rate, a.every, os.path.join(a.out, "fcc"), log, None, a.friction,
                               scene="fcc.yaml")
        np.savetxt(os.path.join(a.out, "fcc.csv"), rows, delimiter=",", header=head, comments="")
        res["fcc"] = r = analyse(rows)
        report("fcc", r, log)
        mu = 0.3 if a.friction is None else a.friction
        ratio = np.max(rows[:, 5] / rows[:, 6])
        exact = 2 * (1 + mu) / (1 - mu)
        r["ratio"], r["ratio_exact"] = float(ratio), exact
        log("fcc      largest s1/s3 %.4f; Thornton (1979), rigid spheres: 2 (1 + mu) / (1 - mu) = %.4f (%+.2f %%)"
            % (ratio, exact, 100 * (ratio / exact - 1)))
    return res


if __name__ == "__main__":
    main()
