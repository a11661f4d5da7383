"""test_world.py - floe.World over libfloe.so: loading scenes, stepping, zero-copy particle
arrays, contacts, energy, stress and errors, each checked against the physics it should
reproduce (tolerances stated at each assert)."""
import math
import os

import numpy as np
import pytest

import floe

# one sphere in free fall, nothing to touch: velocity Verlet integrates a constant force
# exactly, so x(t) = x0 + v0 t + g t^2 / 2 up to round-off
FALL = """
name: fall
dimension: 3
time: {duration: 0.05, dt: 1.0e-4}
gravity: [0, 0, -9.81]
materials:
  - {name: m, density: 1000, young: 1.0e7, poisson: 0.3}
laws:
  - {materials: [m, m], model: linear, kn: 1000, ks: 500}
bodies:
  - {shape: {sphere: {radius: 0.01}}, material: m, position: [0.1, 0.2, 1.0],
     velocity: [0.5, -0.25, 2.0]}
"""
X0 = np.array([0.1, 0.2, 1.0])
V0 = np.array([0.5, -0.25, 2.0])
G = np.array([0.0, 0.0, -9.81])

# two spheres of radius R overlapping by D along x, at rest, no gravity, linear law
# without damping or friction: Fn = kn d (contact/laws/linear_law.c)
R, D, KN = 0.01, 1.0e-4, 2000.0
PAIR = f"""
name: pair
dimension: 3
time: {{duration: 0.001, dt: 1.0e-6}}
gravity: [0, 0, 0]
materials:
  - {{name: m, density: 1000, young: 1.0e7, poisson: 0.3}}
laws:
  - {{materials: [m, m], model: linear, kn: {KN}, ks: 1000}}
bodies:
  - {{shape: {{sphere: {{radius: {R}}}}}, material: m, position: [0, 0, 0]}}
  - {{shape: {{sphere: {{radius: {R}}}}}, material: m, position: [{2 * R - D}, 0, 0]}}
"""


def test_free_fall_matches_constant_acceleration(tmp_path):
    w = floe.World.from_string(FALL, outdir=str(tmp_path))
    assert w.n == 1 and w.dim == 3
    assert w.info["name"] == "fall" and w.info["duration"] == pytest.approx(0.05, rel=1e-15)
    w.step(100)
    assert w.step_count == 100
    assert w.dt == pytest.approx(1.0e-4, rel=1e-15)
    t = w.time
    assert t == pytest.approx(0.01, rel=1e-12)
    expect_x = X0 + V0 * t + 0.5 * G * t * t
    # round-off of 100 steps: 1e-12 m on positions of order 1 m
    np.testing.assert_allclose(w.x[0], expect_x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(w.v[0], V0 + G * t, rtol=0, atol=1e-12)
    # the ledger: kinetic = m |v|^2 / 2, gravity's work = m g . (x - x0), to 1e-10 relative
    m = w.mass[0]
    assert m == pytest.approx(1000 * 4 / 3 * math.pi * 0.01 ** 3, rel=1e-12)
    e = w.energy()
    v = V0 + G * t
    assert e.kinetic_trans == pytest.approx(0.5 * m * v.dot(v), rel=1e-10)
    assert e.work_body == pytest.approx(m * G.dot(expect_x - X0), rel=1e-10)
    assert w.energy_balance_error() < 1e-10


def test_run_to_scene_duration(tmp_path):
    w = floe.World.from_string(FALL, outdir=str(tmp_path))
    assert w.run() is True
    t = w.time
    assert t == pytest.approx(0.05, rel=1e-9)
    np.testing.assert_allclose(w.x[0], X0 + V0 * t + 0.5 * G * t * t, rtol=0, atol=1e-12)
    # run to an absolute time, from where it is
    w.run(0.06)
    assert w.time == pytest.approx(0.06, rel=1e-9)


def test_progress_callback_stops_the_run(tmp_path):
    w = floe.World.from_string(FALL, outdir=str(tmp_path))
    seen = []

    def progress(step, nsteps):
        seen.append((step, nsteps))
        return step == 7
    assert w.run(0.05, progress=progress) is False
    assert w.step_count == 7
    assert seen[0] == (1, 500) and seen[-1] == (7, 500)

    def boom(step, nsteps):
        raise KeyError("from the callback")
    with pytest.raises(KeyError, match="from the callback"):
        w.run(0.05, progress=boom)


def test_views_are_zero_copy_and_read_only(tmp_path):
    w = floe.World.from_string(FALL, outdir=str(tmp_path))
    x = w.x
    v = w.v
    before = x.copy()
    assert x.shape == (1, 3) and x.dtype == np.float64
    assert not x.flags.writeable
    with pytest.raises(ValueError):
        x[0, 0] = 1.0
    w.step(10)
    # the same memory: the array taken before the steps sees where the sphere is now
    assert np.shares_memory(x, w.x)
    assert x.__array_interface__["data"][0] == w.x.__array_interface__["data"][0]
    assert x[0, 2] != before[0, 2]
    np.testing.assert_array_equal(x, w.x)
    np.testing.assert_allclose(v[0], V0 + G * w.time, rtol=0, atol=1e-12)
    # an array keeps the world alive after the last Python name of it is gone
    del w
    assert x[0, 2] > 1.0
    p = floe.World.from_string(FALL, outdir=str(tmp_path)).particles()
    assert set(p) == set(floe.PARTICLE_FIELDS)
    assert p.q.shape == (1, 4) and p.mass.shape == (1,) and p.thickness is None
    np.testing.assert_allclose(p.q[0], [1, 0, 0, 0], rtol=0, atol=1e-15)
    assert p.motion[0] == floe.FLOE_FREE and p.radius[0] == pytest.approx(0.01, rel=1e-15)


def test_two_sphere_overlap_follows_the_linear_law(tmp_path):
    w = floe.World.from_string(PAIR, outdir=str(tmp_path))
    w.step()
    with pytest.raises(floe.FloeError, match="record_contacts"):
        w.contacts()
    with pytest.raises(floe.FloeError, match="record_contacts"):
        w.collection_stress()
    assert w.contact_count() == 1   # counted without records
    w.record_contacts()
    w.step()
    c = w.contacts()
    assert len(c) == 1 and w.contact_count() == 1
    assert c.dtype == floe.contact_dtype() and c.dtype.itemsize == floe.ffi.sizeof("floe_contact_info")
    assert not c.flags.writeable
    (i, j) = sorted((int(c["i"][0]), int(c["j"][0])))
    assert (i, j) == (0, 1)
    x = w.x
    dist = np.linalg.norm(x[1] - x[0])
    depth = 2 * R - dist
    # depth of the evaluation at the positions after the step; Fn = kn d to 1e-9 relative
    assert c["depth"][0] == pytest.approx(depth, rel=1e-9)
    assert c["fn"][0] == pytest.approx(KN * depth, rel=1e-9)
    assert c["depth"][0] == pytest.approx(D, rel=1e-3)   # one 1 us step barely moves them
    n = c["n"][0]
    sign = 1.0 if c["i"][0] == 0 else -1.0
    np.testing.assert_allclose(n, sign * (x[1] - x[0]) / dist, rtol=0, atol=1e-12)
    # the force on i pushes it away from j: -Fn n; the particles' forces are it and its opposite
    np.testing.assert_allclose(c["force"][0], -c["fn"][0] * n, rtol=0, atol=1e-12 * KN * D)
    f = w.f
    np.testing.assert_allclose(f[c["i"][0]], c["force"][0], rtol=0, atol=1e-12 * KN * D)
    np.testing.assert_allclose(f[0] + f[1], 0.0, rtol=0, atol=1e-12 * KN * D)
    assert c["energy"][0] == pytest.approx(0.5 * KN * depth ** 2, rel=1e-9)
    assert w.energy().elastic == pytest.approx(0.5 * KN * depth ** 2, rel=1e-9)
    # homogenised stress over a given volume V: sigma_xx = -Fn |d| / V (compression
    # negative), the rest 0 (observers/collection_tracker.c)
    V = 1.0e-6
    s = w.collection_stress(volume=V)
    assert s.particles == 2 and s.contacts == 1 and s.wall_contacts == 0
    assert s.volume == pytest.approx(V, rel=1e-15)
    assert s.sigma[0, 0] == pytest.approx(-KN * depth * dist / V, rel=1e-9)
    assert np.max(np.abs(s.sigma - np.diag([s.sigma[0, 0], 0, 0]))) <= 1e-9 * abs(s.sigma[0, 0])
    np.testing.assert_allclose(s.sigma, s.sigma.T, rtol=0, atol=0)
    assert s.coordination == pytest.approx(1.0, rel=1e-15)
    # the pair flies apart: after 1 ms (about 0.07 of the contact's period) still touching,
    # and the repulsion keeps the momentum at 0 (to round-off)
    w.run(0.001)
    mv = w.mass[:, None] * w.v
    assert abs(mv.sum(axis=0)).max() <= 1e-12 * abs(mv).max()
    assert w.v[1, 0] > 0 > w.v[0, 0]


def test_setters_and_dt(tmp_path):
    w = floe.World.from_string(FALL, outdir=str(tmp_path))
    w.set_velocity(0, v=[0, 0, 0])
    w.set_pose(0, x=[1.0, 2.0, 3.0])
    w.dt = 2.0e-4
    w.step(50)
    t = w.time
    assert t == pytest.approx(0.01, rel=1e-12) and w.dt == pytest.approx(2.0e-4, rel=1e-15)
    np.testing.assert_allclose(w.x[0], np.array([1.0, 2.0, 3.0]) + 0.5 * G * t * t, rtol=0, atol=1e-12)
    with pytest.raises(floe.FloeError) as e:
        w.set_velocity(5, v=[0, 0, 0])
    assert e.value.code == floe.FLOE_EINVAL and e.value.name == "FLOE_EINVAL"
    assert e.value.message   # the world's message, not only the code
    with pytest.raises(ValueError):
        w.set_velocity(0, v=[0, 0])


def test_scene_errors_carry_file_and_line(tmp_path):
    bad = FALL.replace("density: 1000", "densty: 1000")
    with pytest.raises(floe.FloeError) as e:
        floe.World.from_string(bad, path="bad.yaml", outdir=str(tmp_path))
    assert e.value.code == floe.FLOE_EPARSE
    lines = bad.split("\n")
    line = next(k for k, text in enumerate(lines, 1) if "densty" in text)
    col = lines[line - 1].index("densty") + 1
    assert (line, col) == (7, 15)
    assert e.value.message.startswith(f"bad.yaml:{line}:{col}: ")
    assert "density" in e.value.message   # the closest valid key
    path = tmp_path / "broken.yaml"
    path.write_text(bad)
    with pytest.raises(floe.FloeError, match=rf"broken\.yaml:{line}:{col}: "):
        floe.World.from_scene(str(path), outdir=str(tmp_path))
    with pytest.raises(floe.FloeError) as e:
        floe.World.from_scene(str(tmp_path / "missing.yaml"))
    assert e.value.code == floe.FLOE_EIO and "missing.yaml" in e.value.message


def test_scene_file_with_outputs(tmp_path):
    here = os.path.dirname(os.path.abspath(__file__))
    scene = os.path.join(here, "..", "..", "tests", "scenes", "tiny_run.yaml")
    out = tmp_path / "out"
    with floe.World.from_scene(scene, outdir=str(out)) as w:
        assert w.info["nparticles"] == 8 and w.info["nwalls"] == 1 and w.n == 9
        w.run()
        assert w.time == pytest.approx(0.005, rel=1e-9)
        # the spheres (R = 1 mm, from 1.05 mm) fell onto the floor at z = 0: none sank
        # through it (every centre above 0.9 R), and the lowest layer moved down
        spheres = np.isfinite(w.radius)
        assert spheres.sum() == 8 and np.isinf(w.radius[~spheres]).all()
        z = w.x[spheres, 2]
        assert z.min() > 0.0009 and z.min() < 0.00105
    assert (out / "energy.csv").exists() and (out / "particles.csv").exists()
    with pytest.raises(ValueError, match="closed"):
        w.time


def test_default_demo_loads():
    text = floe.default_demo()
    w = floe.World.from_string(text, outputs=False)
    assert w.n > 0 and w.info["duration"] > 0
