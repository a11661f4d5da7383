"""test_rve.py - the RVE API from Python (floe.RVE over floe_cell.h).

- A simple cubic lattice of 64 frictionless spheres (kn = 1e4 N/m, spacing s = 1 m,
  touching) in a periodic cell: after a strain increment of -1e-7 (xx), -5e-8 (yy), the
  stress is (kn/s) eps within 1e-6 and eq 29's tangent is the lattice's elastic tensor
  C_aaaa = kn/s (Voigt 1e4 on xx and yy, 0 elsewhere: the z bonds touch at zero overlap and
  carry nothing) within 1e-6 of kn/s; coordination 4, porosity 1 - (pi/6)/det(I + de) to 1e-12.
- The increment's steps follow the strain-rate limit: ceil(|de| / (max_rate dt)).
- An increment that would invert the cell raises FloeError naming it, and nothing moved.
"""
import math

import numpy as np
import pytest

import floe

LATTICE = """
dimension: 3
time: {duration: 1, dt: 1.0e-4}
gravity: [0, 0, 0]
materials: [{name: m, density: 1000}]
laws: [{materials: [m, m], model: linear, kn: 1.0e4, ks: 0}]
cell: {size: [4, 4, 4]}
bodies:
  - {packing: lattice, shape: {sphere: {radius: 0.5}}, material: m, spacing: 1.0, counts: [4, 4, 4], origin: [0.5, 0.5, 0.5]}
"""


def test_lattice_stress_and_tangent():
    rve = floe.RVE.from_string(LATTICE)
    m0 = rve.measures()
    assert m0.contacts == 0 or np.allclose(m0.sigma, 0, atol=1e-12)
    de = np.diag([-1e-7, -5e-8, 0.0])
    steps = rve.strain(de, max_rate=1e-3)
    assert steps == 1
    sig = rve.stress()
    assert sig[0, 0] == pytest.approx(1e4 * -1e-7, rel=1e-6)
    assert sig[1, 1] == pytest.approx(1e4 * -5e-8, rel=1e-6)
    assert abs(sig[0, 1]) < 1e-12 and abs(sig[2, 2]) < 1e-12
    D4, Dv = rve.tangent()
    C = np.zeros((6, 6))
    C[0, 0] = C[1, 1] = 1e4
    # only the x and y bonds are compressed: z bonds touch at zero overlap (no contact)
    assert np.max(np.abs(Dv - C)) < 1e-6 * 1e4
    assert D4[0, 0, 0, 0] == pytest.approx(1e4, rel=1e-6)
    m = rve.measures()
    assert m.coordination == pytest.approx(4.0)  # the x and y neighbours
    assert m.porosity == pytest.approx(1 - math.pi / 6 / (1 - 1e-7) / (1 - 5e-8), rel=1e-12)


def test_steps_follow_the_rate_limit():
    rve = floe.RVE.from_string(LATTICE)
    steps = rve.strain(np.diag([-1e-3, 0, 0]), max_rate=0.5)
    assert steps == math.ceil(1e-3 / (0.5 * 1e-4) - 1e-9)
    o, H = rve.cell()
    assert H[0, 0] == pytest.approx(4 * (1 - 1e-3), rel=1e-14)


def test_inverting_increment_refused():
    rve = floe.RVE.from_string(LATTICE)
    with pytest.raises(floe.FloeError, match="invert"):
        rve.strain(np.diag([-1.5, 0, 0]), max_rate=1.0)
    assert rve.world.step_count == 0
