"""rve.py - a periodic cell as a representative volume element (floe_cell.h, docs/periodic.md).

    import floe
    rve = floe.RVE.from_scene("examples/rve-periodic/scene.yaml")
    rve.world.run(0.3)                          # compact (the scene's stress servo)
    steps = rve.strain(np.diag([-1e-4, 0, 0]), max_rate=0.5)
    m = rve.measures()                          # sigma, fabric, coordination, porosity, ...
    D4, Dv = rve.tangent()                      # ParticLS eq 29: (3,3,3,3) and Voigt 6x6

Strains are displacement gradients (the cell goes from H to (I + de) H); stresses are in Pa,
tension positive; Voigt order xx, yy, zz, yz, xz, xy with engineering shear strains.
"""
import numpy as np

from . import _api
from ._api import FloeError, ffi, lib
from .world import World

RATE, STRESS = 0, 1


def _mat(values, what):
    a = np.asarray(values, dtype=float)
    if a.shape != (3, 3):
        raise ValueError(f"{what}: a 3x3 matrix, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{what}: not finite")
    return a


def _ptr9(a):
    buf = ffi.new("double[9]", [float(v) for v in np.asarray(a, dtype=float).ravel()])
    return buf


class RVE:
    """A World with a periodic cell, its contacts recorded (the tangent and the fabric read them)."""

    def __init__(self, world):
        self.world = world
        if not lib().floe_world_cell(world.ptr, ffi.NULL, ffi.NULL):
            raise FloeError(_api.FLOE_EINVAL, "RVE: the scene has no periodic cell (a `cell` block)")
        world.record_contacts(True)
        world.prepare()
        world.check(lib().floe_world_refresh_forces(world.ptr))  # the loaded state, recorded

    @classmethod
    def from_scene(cls, path, outdir=None, outputs=False):
        return cls(World.from_scene(path, outdir=outdir, outputs=outputs))

    @classmethod
    def from_string(cls, text, path="<string>", outdir=None, outputs=False):
        return cls(World.from_string(text, path=path, outdir=outdir, outputs=outputs))

    # -- the cell --------------------------------------------------------------------------
    def cell(self):
        """(origin (3,), H (3, 3)): the cell x = origin + H s, H's columns the cell vectors."""
        o, H = ffi.new("double[3]"), ffi.new("double[9]")
        lib().floe_world_cell(self.world.ptr, o, H)
        return np.array(list(o)), np.array(list(H)).reshape(3, 3)

    @property
    def volume(self):
        return lib().floe_world_cell_volume(self.world.ptr)

    def velocity_gradient(self):
        L = ffi.new("double[9]")
        self.world.check(lib().floe_world_cell_velocity_gradient(self.world.ptr, L))
        return np.array(list(L)).reshape(3, 3)

    def set_control(self, rate=None, stress=None, max_rate=0.0, servo_time=0.0):
        """Strain rates (3x3, 1/s; None: 0) and stress targets ({(a, b): Pa} or a 3x3 array with
        NaN where not controlled); a component with a stress target is held by the servo."""
        c = ffi.new("floe_cell_control *")
        c[0] = lib().floe_default_cell_control()
        if rate is not None:
            r = _mat(rate, "rate")
            for k in range(9):
                c.rate[k] = r.flat[k]
        if stress is not None:
            if isinstance(stress, dict):
                items = stress.items()
            else:
                st = np.asarray(stress, dtype=float)
                items = [((k // 3, k % 3), st.flat[k]) for k in range(9) if np.isfinite(st.flat[k])]
            for (a, b), v in items:
                c.mode[3 * a + b] = STRESS
                c.stress[3 * a + b] = float(v)
        c.max_rate = float(max_rate)
        c.servo_time = float(servo_time)
        self.world.check(lib().floe_world_cell_set_control(self.world.ptr, c))

    # -- loading -----------------------------------------------------------------------------
    def strain(self, de, max_rate, stress_mask=None):
        """Apply the strain increment de (3x3 displacement gradient) over the steps that keep
        every |L_ab| <= max_rate (1/s); components where stress_mask is true stay under the
        stress servo. Returns the number of steps taken."""
        d = _mat(de, "de")
        steps = ffi.new("long *")
        mask = ffi.NULL
        if stress_mask is not None:
            m = np.asarray(stress_mask, dtype=bool)
            mask = ffi.new("int[9]", [int(v) for v in m.ravel()])
        self.world.check(lib().floe_world_cell_strain(self.world.ptr, _ptr9(d), float(max_rate), mask, steps))
        return int(steps[0])

    # -- what it reports ----------------------------------------------------------------------
    def stress(self):
        """The cell's stress (3x3, Pa, symmetric part; contact + kinetic)."""
        s = ffi.new("double[9]")
        self.world.check(lib().floe_world_cell_stress(self.world.ptr, s, ffi.NULL))
        return np.array(list(s)).reshape(3, 3)

    def measures(self):
        """A Record: sigma, fabric (3x3), coordination, porosity, void_ratio, volume,
        solid_volume, contacts, particles."""
        m = ffi.new("floe_rve_measures *")
        self.world.check(lib().floe_world_cell_measures(self.world.ptr, m))
        r = _api.to_record(m[0])
        r["sigma"] = np.array(r["sigma"]).reshape(3, 3)
        r["fabric"] = np.array(r["fabric"]).reshape(3, 3)
        return r

    def tangent(self, kind="contact", strain=1e-6, max_rate=None, relax_steps=1):
        """The tangent D as (D4 (3,3,3,3), Voigt (6,6)), Pa.
        kind "contact": ParticLS eq 29 over the contacts of the last evaluation;
        kind "perturbation": strain probes of `strain` from the present state (saved and put back
        after; floe_world_tangent_perturb), each applied at max_rate (default: in one step) then
        relax_steps steps with the cell fixed, against the unstrained state run as long."""
        D = ffi.new("double[81]")
        V = ffi.new("double[36]")
        if kind == "contact":
            self.world.check(lib().floe_world_tangent_contact(self.world.ptr, 0.0, D))
            lib().floe_tangent_to_voigt(D, V)
        elif kind == "perturbation":
            if max_rate is None:
                max_rate = strain / self.world.dt
            steps = ffi.new("long *")
            self.world.check(lib().floe_world_tangent_perturb(self.world.ptr, float(strain), float(max_rate),
                                                              int(relax_steps), D, V, steps))
            self.last_probe_steps = int(steps[0])
        else:
            raise ValueError(f"tangent kind {kind!r}: 'contact' or 'perturbation'")
        return np.array(list(D)).reshape(3, 3, 3, 3), np.array(list(V)).reshape(6, 6)

    # -- state ----------------------------------------------------------------------------------
    def save_state(self):
        """The whole state (particles, contacts' history, cell, clock, ledger) as bytes
        (floe_world_state_save; observers excluded)."""
        n = lib().floe_world_state_size(self.world.ptr)
        if n == 0:
            raise FloeError(_api.FLOE_EINVAL, "save_state: the world is not prepared")
        buf = ffi.new("unsigned char[]", n)
        _api.call_err(lib().floe_world_state_save, self.world.ptr, buf, n)
        return bytes(ffi.buffer(buf, n))

    def restore_state(self, state):
        """Put back a state from save_state (of this RVE or one built from the same scene)."""
        buf = ffi.from_buffer(state)
        _api.call_err(lib().floe_world_state_restore, self.world.ptr, buf, len(state))

    def save(self, path, scene_hash=0, name=None):
        """A checkpoint file (floe_world_checkpoint_save): load it into an RVE built from the
        same scene with load()."""
        _api.call_err(lib().floe_world_checkpoint_save, self.world.ptr, _api.cstr(path), int(scene_hash),
                      _api.cstr(name))

    def load(self, path, scene_hash=0, name=None):
        _api.call_err(lib().floe_world_checkpoint_load, self.world.ptr, _api.cstr(path), int(scene_hash),
                      _api.cstr(name))
