"""floe - Python bindings of the floe particle-mechanics library (DEM, peridynamics).

    import floe
    w = floe.World.from_scene("scene.yaml", outdir="out")
    w.step(10); w.run(0.5)
    w.x, w.v            # particle arrays: numpy, zero-copy, read-only
    w.record_contacts(); w.step(); w.contacts()

cffi's ABI mode over libfloe.so (no compiler needed): docs/python.md says where the library
is looked for (FLOE_LIBRARY) and how to bind another C function.
"""

from ._api import (FLOE_EINVAL, FLOE_EIO, FLOE_ENOMEM, FLOE_ENOTSUP, FLOE_EPARSE, FLOE_ESTOP,
                   FLOE_EUNSTABLE, FLOE_FIXED, FLOE_FREE, FLOE_KINEMATIC, FLOE_OK, FloeError,
                   Record, ffi, lib)
from ._api import call_err as _call_err
from ._api import cstr as _cstr
from .world import PARTICLE_FIELDS, World, contact_dtype
from .rve import RVE

__all__ = ["World", "RVE", "FloeError", "Record", "load", "load_string", "load_plugin", "default_demo",
           "contact_dtype", "PARTICLE_FIELDS", "ffi", "lib"]


def load(path, outdir=None, outputs=True):
    """World.from_scene(path, outdir, outputs)."""
    return World.from_scene(path, outdir=outdir, outputs=outputs)


def load_string(text, path="<string>", outdir=None, outputs=True):
    """World.from_string(text, path, outdir, outputs)."""
    return World.from_string(text, path=path, outdir=outdir, outputs=outputs)


def load_plugin(path):
    """Load a plugin shared library that registers shapes, laws or outputs
    (floe_plugin_load, docs/extending.md)."""
    _call_err(lib().floe_plugin_load, _cstr(path))


def default_demo():
    """The built-in demo scene, YAML text (floe_scene_default_demo)."""
    return ffi.string(lib().floe_scene_default_demo()).decode()
