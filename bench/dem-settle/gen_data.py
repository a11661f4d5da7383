#!/usr/bin/env python3
"""Initial state for bench/dem-settle, shared by floe and LIGGGHTS (same file).
20,000 spheres, d = 2 mm, rho = 2500, on a 25 x 25 x 32 lattice of spacing 2.4 mm, each
site jittered by U(-0.15, 0.15) mm per axis (no initial overlaps), random velocities
U(-0.1, 0.1) m/s per component; box 0.062 x 0.062 x 0.100 m. Same recipe as the peer
benchmark (shared/peers/dem-settle), written here for floe."""
import random, sys
random.seed(12345)
nx, ny, nz = 25, 25, 32
a, jit, d, rho = 2.4e-3, 0.15e-3, 2.0e-3, 2500.0
L = (0.062, 0.062, 0.100)
x0 = 1.5e-3
out = sys.argv[1] if len(sys.argv) > 1 else "settle.data"
atoms, vels = [], []
for k in range(nz):
    for j in range(ny):
        for i in range(nx):
            p = [x0 + i * a, x0 + j * a, x0 + k * a]
            atoms.append([c + random.uniform(-jit, jit) for c in p])
            vels.append([random.uniform(-0.1, 0.1) for _ in range(3)])
with open(out, "w") as f:
    f.write("dem-settle: 20000 spheres d=2mm rho=2500, jittered lattice\n\n")
    f.write(f"{len(atoms)} atoms\n1 atom types\n\n")
    f.write(f"0 {L[0]} xlo xhi\n0 {L[1]} ylo yhi\n0 {L[2]} zlo zhi\n\nAtoms\n\n")
    for n, p in enumerate(atoms, 1):
        f.write(f"{n} 1 {d} {rho} {p[0]:.9e} {p[1]:.9e} {p[2]:.9e}\n")
    f.write("\nVelocities\n\n")
    for n, v in enumerate(vels, 1):
        f.write(f"{n} {v[0]:.6e} {v[1]:.6e} {v[2]:.6e} 0 0 0\n")
print(out, len(atoms))
