"""world.py - floe.World, a simulation (a floe_world of the C library) for Python.

Every method is a thin wrapper over one function of the public C API (the name is in its
docstring); particle and contact arrays are numpy arrays over the world's own memory
(zero-copy, read-only), valid until particles are added to the world (docs/python.md).
"""

import numpy as np

from . import _api
from ._api import FloeError, Record, array, call_err, check, cstr, ffi, lib

# particle arrays of floe_particles_view (floe_view.h): Python name -> (C field, numbers
# per particle (0: a 1-D array), dtype)
PARTICLE_FIELDS = {
    "x": ("x", 3, np.float64),          # centre of mass, m
    "v": ("v", 3, np.float64),          # velocity, m/s
    "q": ("q", 4, np.float64),          # orientation body -> world (w, x, y, z)
    "omega": ("w", 3, np.float64),      # angular velocity, world frame, rad/s
    "L": ("L", 3, np.float64),          # angular momentum, world frame, kg m^2/s
    "f": ("f", 3, np.float64),          # force of the last evaluation, N
    "torque": ("t", 3, np.float64),     # torque of the last evaluation, N m
    "mass": ("mass", 0, np.float64),    # kg
    "inertia": ("inertia", 3, np.float64),  # principal moments, body frame, kg m^2
    "radius": ("radius", 0, np.float64),    # bounding radius, m (inf for walls)
    "geometry": ("geometry", 0, np.intc),
    "material": ("material", 0, np.intc),
    "group": ("group", 0, np.intc),
    "motion": ("motion", 0, np.uint8),      # FREE 0, FIXED 1, KINEMATIC 2
    "pieces": ("pieces", 0, np.intc),
    "thickness": ("thickness", 0, np.float64),  # 2D floes, m (None when no particle has one)
}


def _doubles(values, n, what):
    """A double[n] argument from a sequence (NULL for None)."""
    if values is None:
        return ffi.NULL
    a = np.asarray(values, dtype=np.float64).ravel()
    if a.size != n:
        raise ValueError(f"{what}: {n} numbers expected, got {a.size}")
    return ffi.new(f"double[{n}]", a.tolist())


class World:
    """A floe world. Make one with World.from_scene(path) or World.from_string(yaml);
    the world is destroyed with close() (or the with-block, or when garbage collected)."""

    def __init__(self, ptr, info=None):
        """Wraps a floe_world * the caller hands over (it is destroyed with this object)."""
        self._ptr = ffi.gc(ptr, lib().floe_world_destroy)
        self.info = info   # the scene's floe_scene_info as a Record (name, duration, ...)

    # ---- making and closing ----
    @classmethod
    def from_scene(cls, path, outdir=None, outputs=True):
        """Load the scene file at path (floe_scene_load_ex). Observers write into outdir
        (created if missing; None: "out"); outputs=False validates the outputs section
        without creating any file. Either way the scene's `prepare` block runs (compaction,
        then friction: docs/granular.md). FloeError with "file:line:column: message" on error."""
        return cls._load(cstr(path), ffi.NULL, outdir, outputs)

    @classmethod
    def from_string(cls, text, path="<string>", outdir=None, outputs=True):
        """Load a scene from YAML text; path is used in messages and to resolve relative
        file names of the scene (meshes, shapefiles)."""
        return cls._load(cstr(path), cstr(text), outdir, outputs)

    @classmethod
    def _load(cls, path, text, outdir, outputs):
        out = ffi.new("floe_world **")
        info = ffi.new("floe_scene_info *")
        # FLOE_SCENE_RUN (1) or FLOE_SCENE_NO_OUTPUTS (2): the prepare block runs in both
        call_err(lib().floe_scene_load_ex, path, text, cstr(outdir), 1 if outputs else 2, out, info)
        return cls(out[0], _api.to_record(info[0]))

    def close(self):
        """Destroy the world now (floe_world_destroy); arrays taken from it become invalid."""
        if self._ptr is not None:
            ffi.release(self._ptr)
            self._ptr = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @property
    def ptr(self):
        """The floe_world * (cffi cdata) for calling the C API directly: lib().floe_...(w.ptr)."""
        if self._ptr is None:
            raise ValueError("floe: the world is closed")
        return self._ptr

    def check(self, rc):
        """Raise FloeError with the world's last error for a status other than FLOE_OK."""
        return check(rc, self.ptr)

    def __repr__(self):
        if self._ptr is None:
            return "<floe.World closed>"
        name = self.info["name"] if self.info else ""
        return f"<floe.World {name!r} n={self.n} t={self.time:g} s step={self.step_count}>"

    # ---- advancing ----
    def prepare(self):
        """Masses, neighbour structures and the time step (floe_world_prepare); step and
        run do it when needed."""
        self.check(lib().floe_world_prepare(self.ptr))

    def step(self, n=1):
        """Advance n steps (floe_world_step)."""
        for _ in range(int(n)):
            self.check(lib().floe_world_step(self.ptr))

    def run(self, t_end=None, progress=None):
        """Run until the time t_end, s (floe_world_run; None: the scene's duration). The
        observers are flushed at the end (floe_world_finish). progress(step, nsteps) is
        called after every step; a true return stops the run. Returns True when t_end was
        reached, False when progress stopped it."""
        if t_end is None:
            if not self.info:
                raise ValueError("floe: run() needs t_end for a world without a scene")
            t_end = self.info["duration"]
        stopped = []
        cb = ffi.NULL
        if progress is not None:
            def on_step(_w, step, nsteps, _user):
                try:
                    stop = bool(progress(step, nsteps))
                except BaseException as e:  # raised again below, after the run ends
                    stopped.append(e)
                    return 1
                if stop:
                    stopped.append(None)
                return 1 if stop else 0
            cb = ffi.callback("floe_progress_fn", on_step)
        rc = lib().floe_world_run(self.ptr, float(t_end), cb, ffi.NULL)
        if stopped and stopped[0] is not None:
            raise stopped[0]
        if rc == _api.FLOE_ESTOP and stopped:
            return False
        self.check(rc)
        return True

    def finish(self):
        """Call end() of every observer (floe_world_finish; idempotent)."""
        self.check(lib().floe_world_finish(self.ptr))

    # ---- time ----
    @property
    def time(self):
        """Simulated time, s (floe_world_time)."""
        return lib().floe_world_time(self.ptr)

    @property
    def dt(self):
        """The time step, s (floe_world_dt; 0 before the world is prepared). Setting it is
        set_dt(value)."""
        return lib().floe_world_dt(self.ptr)

    @dt.setter
    def dt(self, value):
        self.set_dt(value)

    def set_dt(self, dt, allow_unstable=False):
        """Fixed step dt > 0 (0: automatic), and whether a step above the critical estimate
        is accepted (floe_world_set_dt); the world is prepared again before its next step."""
        self.check(lib().floe_world_set_dt(self.ptr, float(dt), 1 if allow_unstable else 0))

    @property
    def step_count(self):
        """Steps taken (floe_world_step_count)."""
        return lib().floe_world_step_count(self.ptr)

    @property
    def critical_dt(self):
        """The critical time-step estimate, s (floe_world_critical_dt; prepares the world)."""
        self.prepare()
        return lib().floe_world_critical_dt(self.ptr)

    @property
    def prepared(self):
        """Whether the world is prepared (floe_world_is_prepared)."""
        return bool(lib().floe_world_is_prepared(self.ptr))

    # ---- particles ----
    @property
    def n(self):
        """Particles, walls included (floe_world_particle_count)."""
        return lib().floe_world_particle_count(self.ptr)

    @property
    def dim(self):
        """2 or 3 (floe_world_dim)."""
        return lib().floe_world_dim(self.ptr)

    def _view(self):
        view = ffi.new("floe_particles_view *")
        self.check(lib().floe_world_particles(self.ptr, view))
        return view

    def _field(self, view, name):
        cname, width, dtype = PARTICLE_FIELDS[name]
        ptr = getattr(view, cname)
        n = view.n
        if ptr == ffi.NULL and name == "thickness":
            return None
        if width:
            return array(ptr, n * width, dtype, (n, width), keep=self)
        return array(ptr, n, dtype, keep=self)

    def particles(self):
        """Every particle array of one view (floe_world_particles) as a Record: x, v, q,
        omega, L, f, torque, mass, inertia, radius, geometry, material, group, motion,
        pieces, thickness; zero-copy and read-only, valid until particles are added.
        The orientations q of spheres (discs) are integrated only when something reads them
        (floe_world_set_orientation): call track_orientation() before stepping to read them."""
        view = self._view()
        return Record((name, self._field(view, name)) for name in PARTICLE_FIELDS)

    def set_velocity(self, i, v=None, omega=None):
        """Velocity v (m/s) and/or angular velocity omega (rad/s, world frame) of particle i
        (floe_world_set_velocity; None keeps it)."""
        self.check(lib().floe_world_set_velocity(self.ptr, int(i), _doubles(v, 3, "v"),
                                                 _doubles(omega, 3, "omega")))

    def set_pose(self, i, x=None, q=None):
        """Move particle i to centre x (m) and/or orientation q (w, x, y, z)
        (floe_world_set_pose; None keeps it)."""
        self.check(lib().floe_world_set_pose(self.ptr, int(i), _doubles(x, 3, "x"), _doubles(q, 4, "q")))

    def track_orientation(self, always=True):
        """Integrate the orientation of spheres and discs at every step (always=True,
        FLOE_ORIENT_ALWAYS) or only when an observer, a beam bond or an output reads it
        (False, FLOE_ORIENT_AUTO, the default): their motion is the same either way."""
        self.check(lib().floe_world_set_orientation(self.ptr, 1 if always else 0))

    # ---- contacts ----
    def record_contacts(self, on=True):
        """Keep the contact records of every step (floe_world_record_contacts), which
        contacts() reads: switch it on before stepping."""
        self.check(lib().floe_world_record_contacts(self.ptr, 1 if on else 0))

    def contact_count(self):
        """Contacts (penetrating pairs) of the last force evaluation (floe_world_contact_count)."""
        return lib().floe_world_contact_count(self.ptr)

    def contacts(self):
        """The contacts of the last force evaluation (floe_world_contacts) as a read-only
        numpy structured array over the world's records, dtype CONTACT_DTYPE: i, j, point
        (3), n (3, from i to j), depth (m), force (3, on i, N), fn (N), energy (J). Valid
        until the next step. FloeError when they were not recorded (record_contacts())."""
        out = ffi.new("const floe_contact_info **")
        nc = lib().floe_world_contacts(self.ptr, out)
        if nc < 0:
            raise FloeError(-nc, "contacts were not recorded at the last force evaluation: "
                                 "call record_contacts() before stepping")
        return array(out[0], nc, contact_dtype(), keep=self)

    # ---- energy and stress ----
    def energy(self):
        """The energy ledger, J (floe_world_energy): kinetic_trans, kinetic_rot, elastic,
        work_body, work_boundary, dissipated, initial."""
        return _api.to_record(lib().floe_world_energy(self.ptr))

    def energy_balance_error(self):
        """Relative error of initial + work = current + dissipated
        (floe_world_energy_balance_error)."""
        return lib().floe_world_energy_balance_error(self.ptr)

    def collection_stress(self, group=-1, volume=0.0):
        """Homogenised (Love-Weber) Cauchy stress of a group now (floe_collection_stress;
        group -1: every free bounded particle; volume <= 0: their bounding box), tension
        positive. A Record: sigma (3x3, Pa), sigma_voigt (xx, yy, zz, xy, xz, yz), time,
        coordination, particles, contacts, wall_contacts, volume. Needs the contacts
        recorded (record_contacts())."""
        out = ffi.new("floe_collection_stats *")
        rc = lib().floe_collection_stress(self.ptr, int(group), float(volume), out)
        if rc == _api.FLOE_EINVAL and lib().floe_world_contacts(self.ptr, ffi.NULL) < 0:
            raise FloeError(rc, "collection_stress: contacts were not recorded at the last force "
                                "evaluation: call record_contacts() before stepping")
        self.check(rc)
        r = _api.to_record(out[0])
        s = r["sigma"]
        r["sigma_voigt"] = s
        r["sigma"] = np.array([[s[0], s[3], s[4]], [s[3], s[1], s[5]], [s[4], s[5], s[2]]])
        return r


def _particle_property(name):
    def get(self):
        return self._field(self._view(), name)
    get.__doc__ = (f"Particle array {name!r} (floe_particles_view.{PARTICLE_FIELDS[name][0]}), "
                   "zero-copy and read-only; invalid once particles are added.")
    return property(get)


for _name in PARTICLE_FIELDS:
    setattr(World, _name, _particle_property(_name))

_contact_dtype = None


def contact_dtype():
    """The numpy dtype of floe_contact_info (its C layout)."""
    global _contact_dtype
    if _contact_dtype is None:
        _contact_dtype = _api.struct_dtype("floe_contact_info")
    return _contact_dtype
