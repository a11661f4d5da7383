#!/usr/bin/env python3
"""FEM x DEM: a 2D biaxial compression with a periodic DEM cell at every Gauss point.

The hierarchical scheme of Guo & Zhao (2014, IJNME 99:789-818): the sample is a mesh of
bilinear quadrilaterals (plane strain, 2 x 2 Gauss points); at each Gauss point a periodic
cell of discs (floe.RVE) is the material. A load step moves the top platen; Newton's method
finds the nodal displacements for which the RVEs' stresses balance the confining pressure and
the platens: in each iteration every RVE is put back to its state at the end of the last
step, given the strain increment of its Gauss point (the cell goes from H to (I + de) H at a
quasi-static rate) and asked for its stress; the stiffness is assembled from each RVE's
contact tangent (ParticLS eq 29, floe_world_tangent_contact). At convergence the states are
kept.

As in Shahin et al. (2016, IJNME, doi 10.1002/nme.5202), several packings prepared
independently from the same recipe are spread over the Gauss points: their differences are
the imperfection from which the strain localises after the peak.

    python3 examples/fem-dem/biaxial.py                   # 3 x 6 elements, 72 RVEs, minutes
    python3 examples/fem-dem/biaxial.py --quick           # 1 x 2 elements, a few steps
    python3 examples/fem-dem/biaxial.py --help

Writes OUT/curve.csv (axial strain, stresses, volumetric strain, Newton iterations),
OUT/field_NNN.vtk (the mesh, displaced, with each element's shear strain, volumetric strain
and stresses; ParaView) and prints a map of the shear strain at the end.
Units: SI; 2D stresses are forces per unit length over 1 m of thickness (Pa).
"""
import argparse
import math
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "python"))
import floe  # noqa: E402


# -- the micro scale: one periodic cell of discs --------------------------------------------
def rve_scene(n, seed, p0, kn, mu, rmin, rmax, damping):
    """A periodic cell of n discs, radii uniform in [rmin, rmax], placed at random at a solid
    fraction of 0.45 and compacted without friction by the cell's servo to p0; then friction."""
    r2 = (rmin * rmin + rmin * rmax + rmax * rmax) / 3.0  # E[r^2], r uniform
    L = math.sqrt(n * math.pi * r2 / 0.45)
    rho = 2650.0
    rbar = 0.5 * (rmin + rmax)
    m = rho * 4.0 / 3.0 * math.pi * rbar ** 3  # a 2D disc without thickness: a sphere's mass
    gn = 2.0 * damping * math.sqrt(kn * m / 2.0)  # damping ratio of a head-on pair
    return f"""
name: fem-dem-rve
dimension: 2
time: {{duration: 1.0, dt: auto}}
gravity: [0, 0]
materials:
  - {{name: sand, density: {rho}}}
laws:
  - {{materials: [sand, sand], model: viscoelastic, kn: {kn}, ks: {kn / 2}, gn: {gn}, gs: {gn / 2}, friction: 0}}
cell:
  size: [{L}, {L}]
  stress: {{xx: {-p0}, yy: {-p0}, xy: 0}}
  max_strain_rate: 50
prepare:
  compact: {{pressure: {p0}}}
  then: {{friction: {mu}}}
  max_time: 2.0
  hold: 200
bodies:
  - packing: random
    name: grains
    radius_distribution: {{uniform: [{rmin}, {rmax}], seed: {seed}}}
    material: sand
    count: {n}
    region: {{min: [0, 0], max: [{L}, {L}]}}
    seed: {seed}
"""


class Packing:
    """One prepared packing: an RVE whose state is swapped in and out for every Gauss point
    that uses it (all those states come from the same scene)."""

    def __init__(self, args, seed):
        self.mu, self.kt = args.mu, args.kn / 2
        self.sliding = 0
        text = rve_scene(args.discs, seed, args.p0, args.kn, args.mu, args.rmin, args.rmax, 0.2)
        # loading runs the scene's `prepare` block (compaction, then friction); no files
        self.rve = floe.RVE.from_string(text, path=f"<rve seed {seed}>", outputs=False)
        w = self.rve.world
        w.set_dt(args.dt_factor * w.critical_dt)
        # the rate of a quasi-static increment: inertial number I = rate d sqrt(rho / p)
        mass = float(np.sum(w.particles()["mass"]))
        rho_eff = mass / self.rve.volume
        self.rate = args.inertial * math.sqrt(args.p0 / rho_eff) / (args.rmin + args.rmax)
        # the compaction servoed the normal stresses only: hold xx, yy at -p0 and xy at 0 with
        # friction on (the cell may shear) until the shear stress is gone
        self.rve.set_control(stress={(0, 0): -args.p0, (1, 1): -args.p0, (0, 1): 0.0, (1, 0): 0.0},
                             max_rate=self.rate, servo_time=500 * w.dt)
        w.step(args.hold)
        # then the cell fixed while the vibrations the servo stirred die out
        self.rve.set_control()  # from here every component strain-controlled, rate 0
        w.step(args.hold)
        # the stress and contacts of this last step
        m = self.rve.measures()
        self.porosity, self.coordination = m["porosity"], m["coordination"]
        self.sigma = voigt_stress(m["sigma"])
        self.state = self.rve.save_state()
        self.D = self.tangent()

    def tangent(self):
        """ParticLS eq 29 in Voigt form (xx, yy, xy with engineering shear), less the
        tangential stiffness of the contacts that slide (|f_t| >= 0.98 mu f_n): a sliding
        contact carries no more tangential force for more tangential displacement."""
        _, V = self.rve.tangent("contact")
        D = V[np.ix_([0, 1, 5], [0, 1, 5])]
        if self.mu > 0:
            c = self.rve.world.contacts()
            n, l, f = c["n"][:, :2], c["branch"][:, :2], c["force"][:, :2]
            t = np.stack([-n[:, 1], n[:, 0]], axis=1)
            fn = np.abs(np.einsum("ci,ci->c", f, n))
            ft = np.abs(np.einsum("ci,ci->c", f, t))
            s = ft >= 0.98 * self.mu * fn
            if np.any(s):
                # k_t t_i l_j t_k l_l summed over the sliding contacts, in the same Voigt form
                T = np.einsum("ci,cj,ck,cl->ijkl", t[s], l[s], t[s], l[s]) * (self.kt / self.rve.volume)
                Tv = np.empty((3, 3))
                rows = (T[0, 0], T[1, 1], 0.5 * (T[0, 1] + T[1, 0]))
                for r, R in enumerate(rows):
                    Tv[r] = (R[0, 0], R[1, 1], 0.5 * (R[0, 1] + R[1, 0]))
                D = D - Tv
            self.sliding = int(np.sum(s))
        return D

    def evaluate(self, state, de_voigt):
        """From `state`, the strain increment de = (exx, eyy, gxy): (stress, tangent, new state,
        steps)."""
        self.rve.restore_state(state)
        de = np.zeros((3, 3))
        de[0, 0], de[1, 1] = de_voigt[0], de_voigt[1]
        de[0, 1] = de[1, 0] = 0.5 * de_voigt[2]
        steps = 0
        if np.max(np.abs(de)) > 0:
            steps = self.rve.strain(de, max_rate=self.rate)
        sig = voigt_stress(self.rve.stress())
        return sig, self.tangent(), self.rve.save_state(), steps


def element_test(pack, a, path):
    """The drained biaxial test on one RVE (the FEM's homogeneous limit): eyy in steps of
    -dstrain at the RVE's rate, sigma_xx held at -p0 by the cell's servo. Rows (axial strain,
    sigma_yy, sigma_xx, volumetric strain)."""
    rve = pack.rve
    rve.restore_state(pack.state)
    rve.set_control(stress={(0, 0): -a.p0}, max_rate=5 * pack.rate, servo_time=a.servo_steps * rve.world.dt)
    V0, rows = rve.volume, []
    with open(path, "w") as f:
        f.write("step,axial_strain,sigma_yy,sigma_xx,sin_phi,volumetric_strain\n")
        for step in range(1, a.steps + 1):
            de = np.zeros((3, 3))
            de[1, 1] = -a.dstrain
            rve.strain(de, max_rate=pack.rate, stress_mask=[[1, 0, 0], [0, 0, 0], [0, 0, 0]])
            s = rve.stress()
            ev = rve.volume / V0 - 1
            sinphi = (s[0, 0] - s[1, 1]) / -(s[0, 0] + s[1, 1])
            rows.append((step * a.dstrain, s[1, 1], s[0, 0], ev))
            f.write(f"{step},{step * a.dstrain:.6g},{s[1, 1]:.9g},{s[0, 0]:.9g},{sinphi:.6g},{ev:.6g}\n")
    rve.set_control()
    rve.restore_state(pack.state)
    return rows


def voigt_stress(s):
    return np.array([s[0, 0], s[1, 1], 0.5 * (s[0, 1] + s[1, 0])])


# -- the macro scale: bilinear quadrilaterals, plane strain -----------------------------------
GAUSS = [(-1 / math.sqrt(3), -1 / math.sqrt(3)), (1 / math.sqrt(3), -1 / math.sqrt(3)),
         (1 / math.sqrt(3), 1 / math.sqrt(3)), (-1 / math.sqrt(3), 1 / math.sqrt(3))]


class Mesh:
    """nx x ny bilinear quadrilaterals over width x height, 2 x 2 Gauss points each. With
    bbar (Hughes 1980), each Gauss point's volumetric strain is the element's mean: full
    integration of a dilatant (or isochoric) flow otherwise locks a coarse mesh."""

    def __init__(self, nx, ny, width, height, bbar=True):
        self.nx, self.ny = nx, ny
        xs, ys = np.linspace(0, width, nx + 1), np.linspace(0, height, ny + 1)
        self.X = np.array([(x, y) for y in ys for x in xs])
        self.elems = []
        for j in range(ny):
            for i in range(nx):
                a = j * (nx + 1) + i
                self.elems.append((a, a + 1, a + nx + 2, a + nx + 1))
        self.elems = np.array(self.elems)
        self.ndof = 2 * len(self.X)
        # B matrices and weights of every Gauss point
        self.B, self.w = [], []
        for e in self.elems:
            xe = self.X[e]
            for xi, eta in GAUSS:
                dN = 0.25 * np.array([[-(1 - eta), (1 - eta), (1 + eta), -(1 + eta)],
                                      [-(1 - xi), -(1 + xi), (1 + xi), (1 - xi)]])
                J = dN @ xe
                dNx = np.linalg.solve(J, dN)
                B = np.zeros((3, 8))
                B[0, 0::2] = dNx[0]
                B[1, 1::2] = dNx[1]
                B[2, 0::2] = dNx[1]
                B[2, 1::2] = dNx[0]
                self.B.append(B)
                self.w.append(np.linalg.det(J))
            if bbar:
                q = slice(len(self.B) - 4, len(self.B))
                Bs, ws = self.B[q], self.w[q]
                vol = sum(w * (B[0] + B[1]) for B, w in zip(Bs, ws)) / sum(ws)
                for B in Bs:
                    corr = 0.5 * (vol - (B[0] + B[1]))
                    B[0] += corr
                    B[1] += corr
        self.dofs = [np.ravel([(2 * n, 2 * n + 1) for n in e]) for e in self.elems]

    def nodes_where(self, pred):
        return [k for k, x in enumerate(self.X) if pred(x)]


def assemble(mesh, sig, D, thickness=1.0):
    F = np.zeros(mesh.ndof)
    K = np.zeros((mesh.ndof, mesh.ndof))
    for e, dofs in enumerate(mesh.dofs):
        for g in range(4):
            q = 4 * e + g
            B, w = mesh.B[q], mesh.w[q] * thickness
            F[dofs] += w * B.T @ sig[q]
            K[np.ix_(dofs, dofs)] += w * B.T @ D[q] @ B
    return F, K


def gp_strains(mesh, du):
    return np.array([mesh.B[4 * e + g] @ du[dofs] for e, dofs in enumerate(mesh.dofs) for g in range(4)])


def write_vtk(path, mesh, u, cell_data):
    with open(path, "w") as f:
        f.write("# vtk DataFile Version 3.0\nfloe FEM x DEM biaxial\nASCII\nDATASET UNSTRUCTURED_GRID\n")
        f.write(f"POINTS {len(mesh.X)} double\n")
        for x, d in zip(mesh.X, u.reshape(-1, 2)):
            f.write(f"{x[0] + d[0]:.9g} {x[1] + d[1]:.9g} 0\n")
        f.write(f"CELLS {len(mesh.elems)} {5 * len(mesh.elems)}\n")
        for e in mesh.elems:
            f.write("4 %d %d %d %d\n" % tuple(e))
        f.write(f"CELL_TYPES {len(mesh.elems)}\n" + "9\n" * len(mesh.elems))
        f.write(f"CELL_DATA {len(mesh.elems)}\n")
        for name, vals in cell_data.items():
            f.write(f"SCALARS {name} double 1\nLOOKUP_TABLE default\n")
            f.write("".join(f"{v:.9g}\n" for v in vals))
        f.write(f"POINT_DATA {len(mesh.X)}\nVECTORS displacement double\n")
        for d in u.reshape(-1, 2):
            f.write(f"{d[0]:.9g} {d[1]:.9g} 0\n")


def parse_args(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--nx", type=int, default=3, help="elements across (default 3)")
    ap.add_argument("--ny", type=int, default=6, help="elements up (default 6)")
    ap.add_argument("--width", type=float, default=0.05, help="sample width, m (height: 2x)")
    ap.add_argument("--discs", type=int, default=120, help="discs per RVE (default 120)")
    ap.add_argument("--packings", type=int, default=4, help="independent packings spread over the Gauss points")
    ap.add_argument("--seed", type=int, default=7, help="which packing each Gauss point gets")
    ap.add_argument("--steps", type=int, default=40, help="load steps")
    ap.add_argument("--dstrain", type=float, default=2.5e-3, help="axial strain per load step")
    ap.add_argument("--p0", type=float, default=1e5, help="confining pressure, Pa")
    ap.add_argument("--kn", type=float, default=5e7, help="contact normal stiffness, N/m (ks = kn/2)")
    ap.add_argument("--mu", type=float, default=0.5, help="friction coefficient")
    ap.add_argument("--rmin", type=float, default=0.7e-3)
    ap.add_argument("--rmax", type=float, default=1.3e-3)
    ap.add_argument("--inertial", type=float, default=2e-3, help="inertial number of the RVE increments")
    ap.add_argument("--dt-factor", type=float, default=0.4, help="time step / critical estimate")
    ap.add_argument("--tol", type=float, default=1e-2, help="Newton: |residual| / |reaction| to stop")
    ap.add_argument("--maxit", type=int, default=8, help="Newton iterations per step at most")
    ap.add_argument("--hold", type=int, default=3000, help="steps of the RVEs under the stress servo after the "
                    "preparation (the shear stress to 0), then as many with the cell fixed")
    ap.add_argument("--no-bbar", action="store_true", help="plain full integration (locks under dilatancy)")
    ap.add_argument("--smooth", action="store_true", help="smooth platens (default: rough)")
    ap.add_argument("--vtk-every", type=int, default=5, help="write the field every k steps (0: end only)")
    ap.add_argument("--element", action="store_true", help="only the element test: one RVE (packing 0) in "
                    "drained biaxial compression under the cell's servo, to element.csv")
    ap.add_argument("--servo-steps", type=float, default=10, help="element test: the servo's time in steps")
    ap.add_argument("--quick", action="store_true", help="1 x 2 elements, 100 discs, 2 packings, 4 steps")
    ap.add_argument("--solver", choices=("broyden", "newton"), default="broyden",
                    help="iterations: Newton with each iterate's eq 29 tangent, or Broyden's updates of the "
                         "last converged tangent (default)")
    ap.add_argument("-v", "--verbose", action="store_true", help="print every Newton iteration")
    ap.add_argument("-o", "--out", default="out/fem-dem")
    a = ap.parse_args(argv)
    if a.quick:
        a.nx, a.ny, a.discs, a.packings, a.steps = 1, 2, 100, 2, 4
    return a


def main(argv=None):
    a = parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    t_start = time.time()

    # the packings
    packs = []
    for k in range(a.packings):
        t0 = time.time()
        packs.append(Packing(a, 101 + k))
        p = packs[-1]
        print(f"packing {k}: {a.discs} discs, porosity {p.porosity:.4f}, coordination {p.coordination:.2f}, "
              f"sigma ({p.sigma[0]:.4g}, {p.sigma[1]:.4g}, {p.sigma[2]:.3g}) Pa, rate {p.rate:.3g} 1/s "
              f"({time.time() - t0:.1f} s)", flush=True)

    if a.element:
        rows = element_test(packs[0], a, os.path.join(a.out, "element.csv"))
        print(" step  axial   sigma_yy/p0  sin(phi)  e_vol   (one RVE, sigma_xx servo-held)")
        for k, (ey, syy, sxx, ev) in enumerate(rows):
            print(f"{k + 1:5d}  {ey:.4f}  {syy / -a.p0:10.4f}  {(sxx - syy) / -(sxx + syy):8.4f}  {ev:+.4f}"
                  f"  sigma_xx/p0 {sxx / -a.p0:.4f}")
        return 0

    run_fem(a, packs)
    print(f"done in {time.time() - t_start:.0f} s; {os.path.join(a.out, 'curve.csv')}, field_*.vtk")
    return 0


def run_fem(a, packs):
    """The biaxial test on the mesh, each Gauss point's material one of `packs` (objects with
    .state, .sigma, .D and evaluate(state, de) -> (sigma, D, state, steps)). Returns the rows
    written to curve.csv and the accumulated Gauss-point strains."""
    H = 2 * a.width
    mesh = Mesh(a.nx, a.ny, a.width, H, bbar=not a.no_bbar)
    ngp = 4 * len(mesh.elems)
    rng = np.random.default_rng(a.seed)
    which = rng.integers(0, a.packings, ngp)
    state = [packs[k].state for k in which]
    sig = np.array([packs[k].sigma for k in which])
    D = np.array([packs[k].D for k in which])
    eps = np.zeros((ngp, 3))  # accumulated strain (small strain)

    bottom = mesh.nodes_where(lambda x: abs(x[1]) < 1e-12)
    top = mesh.nodes_where(lambda x: abs(x[1] - H) < 1e-12)
    left = mesh.nodes_where(lambda x: abs(x[0]) < 1e-12)
    right = mesh.nodes_where(lambda x: abs(x[0] - a.width) < 1e-12)
    fixed = {}  # dof -> increment per step
    for n in bottom:
        fixed[2 * n + 1] = 0.0
        if not a.smooth:
            fixed[2 * n] = 0.0
    for n in top:
        fixed[2 * n + 1] = -a.dstrain * H
        if not a.smooth:
            fixed[2 * n] = 0.0
    if a.smooth:
        fixed[2 * bottom[0]] = 0.0  # one node pinned against rigid motion
    pdofs = np.array(sorted(fixed))
    fdofs = np.array([d for d in range(mesh.ndof) if d not in fixed])
    # the confining pressure on the sides: consistent nodal forces of a uniform traction
    Fext = np.zeros(mesh.ndof)
    for side, sgn in ((left, 1.0), (right, -1.0)):
        ys = sorted(side, key=lambda n: mesh.X[n, 1])
        for n0, n1 in zip(ys[:-1], ys[1:]):
            h = mesh.X[n1, 1] - mesh.X[n0, 1]
            Fext[2 * n0] += sgn * a.p0 * h / 2
            Fext[2 * n1] += sgn * a.p0 * h / 2

    u = np.zeros(mesh.ndof)
    du_last = Kb = None
    rows = []
    curve = open(os.path.join(a.out, "curve.csv"), "w")
    curve.write("step,axial_strain,sigma_axial,sigma_lateral,sin_phi,volumetric_strain,newton_iterations,"
                "residual,dem_steps,seconds\n")
    print(f"mesh {a.nx} x {a.ny} quads, {ngp} RVEs of {a.discs} discs ({ngp * a.discs} discs), "
          f"{'smooth' if a.smooth else 'rough'} platens, p0 = {a.p0:g} Pa", flush=True)
    print(" step  axial   sigma_yy/p0  sin(phi)  e_vol    it  residual   dem-steps  s", flush=True)
    A0 = a.width * H
    frame = 0
    for step in range(1, a.steps + 1):
        t0 = time.time()
        du = np.zeros(mesh.ndof)
        for d, v in fixed.items():
            du[d] = v
        # the predictor: the last step's increment (the same platen increment), else a linear
        # solve with the tangent of the last converged state
        F, K = assemble(mesh, sig, D)
        if du_last is not None:
            du[fdofs] = du_last[fdofs]
        else:
            R = Fext - F - K @ du
            du[fdofs] += np.linalg.solve(K[np.ix_(fdofs, fdofs)], R[fdofs])
        it, res, dem_steps = 0, float("inf"), 0
        # Broyden starts from the stiffness its updates reached in the last step (a secant of
        # the material as it is now), Newton from the converged eq 29 tangent
        if Kb is None or a.solver == "newton":
            Kb = K[np.ix_(fdofs, fdofs)]
        Kf = Kb
        R_prev = s_prev = None
        res_prev = float("inf")
        best, back = None, 0
        cap = 0.5 * a.dstrain * H  # the largest move of a node per iteration
        while True:
            it += 1
            de = gp_strains(mesh, du)
            trial = [packs[k].evaluate(state[q], de[q]) for q, k in enumerate(which)]
            sig_t = np.array([t[0] for t in trial])
            D_t = np.array([t[1] for t in trial])
            dem_steps += sum(t[3] for t in trial)
            F, K = assemble(mesh, sig_t, D_t)
            R = Fext - F
            scale = np.linalg.norm(F[pdofs]) + np.linalg.norm(Fext)
            res = np.linalg.norm(R[fdofs]) / scale
            if a.verbose:
                print(f"      iteration {it}: residual {res:.3e}, sliding contacts "
                      f"{sum(getattr(p, 'sliding', 0) for p in packs)} (last RVE of each packing)", flush=True)
            if best is None or res < best[0]:
                best = (res, du.copy(), de, trial, sig_t, D_t, F)
            if res < a.tol or it >= a.maxit:
                break
            if R_prev is not None and res > res_prev and back < 2:
                # the residual grew: back halfway along the last step, no update from here
                back += 1
                s_prev = 0.5 * s_prev
                du[fdofs] -= s_prev
                continue
            back = 0
            if a.solver == "newton":
                Kf = K[np.ix_(fdofs, fdofs)]
            elif R_prev is not None:
                # Broyden's update: the stiffness seen between the last two iterates
                y = R_prev - R[fdofs]
                Kf = Kf + np.outer(y - Kf @ s_prev, s_prev) / (s_prev @ s_prev)
            s_prev = np.linalg.solve(Kf, R[fdofs])
            m = np.abs(s_prev).max()
            if m > cap:  # a softening secant can ask for a huge step: cap it
                s_prev *= cap / m
            R_prev, res_prev = R[fdofs].copy(), res
            du[fdofs] += s_prev
        # the best iterate (the last one unless the iterations stopped at the cap)
        res, du, de, trial, sig_t, D_t, F = best
        # keep the states (and Broyden's stiffness only when it led to convergence)
        du_last, Kb = du.copy(), (Kf if res < a.tol else None)
        u += du
        eps += de
        state = [t[2] for t in trial]
        sig, D = sig_t, D_t
        ey = step * a.dstrain
        Ftop = sum(F[2 * n + 1] for n in top)
        s_ax = Ftop / a.width  # the platen's stress (tension positive)
        s_lat = -a.p0
        sinphi = (s_lat - s_ax) / -(s_lat + s_ax)
        # volumetric strain from the deformed area
        xd = (mesh.X + u.reshape(-1, 2))
        area = 0.0
        for e in mesh.elems:
            p = xd[e]
            area += 0.5 * abs(np.dot(p[:, 0], np.roll(p[:, 1], -1)) - np.dot(p[:, 1], np.roll(p[:, 0], -1)))
        ev = area / A0 - 1
        dt_s = time.time() - t0
        flag = "" if res < a.tol else "  (not converged)"
        print(f"{step:5d}  {ey:.4f}  {s_ax / -a.p0:10.4f}  {sinphi:8.4f}  {ev:+.4f}  {it:3d}  {res:.2e}  "
              f"{dem_steps:10d}  {dt_s:.1f}{flag}", flush=True)
        curve.write(f"{step},{ey:.6g},{s_ax:.9g},{s_lat:.9g},{sinphi:.6g},{ev:.6g},{it},{res:.4g},{dem_steps},"
                    f"{dt_s:.3f}\n")
        curve.flush()
        rows.append(dict(step=step, axial=ey, sigma_axial=s_ax, sin_phi=sinphi, ev=ev, iterations=it,
                         residual=res, converged=res < a.tol))
        if (a.vtk_every > 0 and step % a.vtk_every == 0) or step == a.steps:
            write_field(os.path.join(a.out, f"field_{frame:03d}.vtk"), mesh, u, eps, sig)
            frame += 1
    curve.close()
    gq = shear_strain(eps).reshape(-1, 4).mean(axis=1)
    print_map(mesh, gq)
    print(f"shear strain: max {gq.max():.4f}, mean {gq.mean():.4f}, max/mean {gq.max() / gq.mean():.2f}")
    return rows, eps


def shear_strain(eps):
    """The deviatoric (shear) strain sqrt((exx - eyy)^2 + gxy^2) at each Gauss point."""
    return np.sqrt((eps[:, 0] - eps[:, 1]) ** 2 + eps[:, 2] ** 2)


def write_field(path, mesh, u, eps, sig):
    el = lambda v: v.reshape(-1, 4).mean(axis=1)  # noqa: E731
    write_vtk(path, mesh, u, {
        "shear_strain": el(shear_strain(eps)),
        "volumetric_strain": el(eps[:, 0] + eps[:, 1]),
        "sigma_xx": el(sig[:, 0]), "sigma_yy": el(sig[:, 1]), "sigma_xy": el(sig[:, 2]),
    })


def print_map(mesh, gq):
    """The elements' shear strain, top row first, as digits 0-9 of the range."""
    lo, hi = gq.min(), gq.max()
    print("shear strain by element (top row first; 0 = %.4f .. 9 = %.4f):" % (lo, hi))
    for j in reversed(range(mesh.ny)):
        row = gq[j * mesh.nx:(j + 1) * mesh.nx]
        print("  " + " ".join(str(int(9.999 * (v - lo) / (hi - lo + 1e-300))) for v in row))


if __name__ == "__main__":
    sys.exit(main())
