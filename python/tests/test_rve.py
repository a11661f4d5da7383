"""test_rve.py - the RVE API from Python (floe.RVE over floe_cell.h).

- A simple cubic lattice of 64 frictionless spheres (kn = 1e4 N/m, spacing s = 1 m,
  touching) in a periodic cell: after a strain increment of -1e-7 (xx), -5e-8 (yy), the
  stress is (kn/s) eps within 1e-6 and eq 29's tangent is the lattice's elastic tensor
  C_aaaa = kn/s (Voigt 1e4 on xx and yy, 0 elsewhere: the z bonds touch at zero overlap and
  carry nothing) within 1e-6 of kn/s; coordination 4, porosity 1 - (pi/6)/det(I + de) to 1e-12.
- The increment's steps follow the strain-rate limit: ceil(|de| / (max_rate dt)).
- An increment that would invert the cell raises FloeError naming it, and nothing moved.
- The perturbation tangent of the compressed lattice (probes of 1e-9) is C within 1e-5 of
  kn/s, and leaves the state as it was (stress bit for bit, step count).
- save_state / restore_state: strained after a save, restored, the stress and the cell are
  those of the save bit for bit; a checkpoint file loaded into a fresh RVE of the same scene
  continues bit for bit like the RVE that wrote it.
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


def compressed():
    rve = floe.RVE.from_string(LATTICE)
    rve.strain(np.diag([-1e-7, -1e-7, -1e-7]), max_rate=1e-3)
    return rve


def test_perturbation_tangent():
    rve = compressed()
    s0, n0 = rve.stress(), rve.world.step_count
    D4, Dv = rve.tangent("perturbation", strain=1e-9)
    C = np.diag([1e4, 1e4, 1e4, 0, 0, 0])
    assert np.max(np.abs(Dv - C)) < 1e-5 * 1e4
    assert rve.last_probe_steps == 6 * 2 + 1 * 2  # 6 probes + 1 reference, each 1 step + 1 relaxation
    assert np.array_equal(rve.stress(), s0) and rve.world.step_count == n0


def test_state_round_trip(tmp_path):
    rve = compressed()
    st = rve.save_state()
    s0, (o0, H0) = rve.stress(), rve.cell()
    rve.strain(np.diag([-1e-4, 0, 0]), max_rate=0.1)
    assert not np.array_equal(rve.stress(), s0)
    rve.restore_state(st)
    assert np.array_equal(rve.cell()[1], H0)
    rve.world.step(1)
    rve.restore_state(st)
    path = str(tmp_path / "rve.ckpt")
    rve.save(path, scene_hash=7, name="lattice")
    other = floe.RVE.from_string(LATTICE)
    other.load(path, scene_hash=7, name="lattice")
    de = np.diag([-2e-5, 1e-5, 0])
    rve.strain(de, max_rate=0.05)
    other.strain(de, max_rate=0.05)
    assert np.array_equal(rve.stress(), other.stress())
    assert np.array_equal(rve.world.x, other.world.x)
    with pytest.raises(floe.FloeError, match="scene"):
        floe.RVE.from_string(LATTICE).load(path, scene_hash=8, name="lattice")


# max_time 3 s: this sample's compaction time has a long tail over the packings (seeds 1-24,
# two particle orders each: 0.23-0.98 s for most, 1.36 and 2.09 s for two that order
# themselves into a crystal); the test is about outputs=False, not the servo's speed
PREPARED = """
dimension: 3
time: {duration: 0.1, dt: 2.0e-5}
gravity: [0, 0, 0]
materials: [{name: g, density: 2650}]
laws: [{materials: [g, g], model: viscoelastic, kn: 2.0e5, ks: 1.0e5, gn: 2.0, gs: 1.0, friction: 0}]
cell: {size: [0.06, 0.06, 0.06], stress: {xx: -1.0e4, yy: -1.0e4, zz: -1.0e4}, max_strain_rate: 2.0}
prepare: {compact: {pressure: 1.0e4}, then: {friction: 0.3}, max_time: 3.0, hold: 200}
bodies:
  - {packing: random, shape: {sphere: {radius: 0.006}}, material: g, count: 60,
     region: {min: [0, 0, 0], max: [0.06, 0.06, 0.06]}, seed: 3}
"""


def test_prepare_runs_without_outputs(tmp_path):
    """outputs=False creates no file but still runs the scene's prepare block: the packing
    arrives compacted to the target pressure (the `prepare` block's 1 % test) and jammed."""
    out = tmp_path / "out"
    text = PREPARED + "outputs:\n  - {type: stress, every: 10, file: stress.csv}\n"
    rve = floe.RVE.from_string(text, outdir=str(out), outputs=False)
    assert not out.exists()
    m = rve.measures()
    p = -np.trace(m["sigma"]) / 3
    assert abs(p - 1.0e4) < 0.02 * 1.0e4, p
    assert m["coordination"] > 4 and m["porosity"] < 0.45
