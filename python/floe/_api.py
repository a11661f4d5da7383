"""_api.py - the C library behind the package: where libfloe.so is found, the cffi handle,
floe's error convention as Python exceptions, and zero-copy numpy arrays over C memory.

The library (docs/python.md, "Finding the library"):
  1. $FLOE_LIBRARY, the path of libfloe.so (ctest sets it to the one it built);
  2. else libfloe.so in the build folder of the source tree this package sits in
     (<repo>/build/libfloe.so, what scripts/test.sh and the README's build make);
  3. else the dynamic loader's search (LD_LIBRARY_PATH, ldconfig) for libfloe.so.
It is opened once, on first use, with RTLD_GLOBAL so that scene plugins (docs/extending.md)
resolve floe's functions in it as they do in the CLI.
"""

import os

import numpy as np
from cffi import FFI

from ._cdef import CDEF

ffi = FFI()
ffi.cdef(CDEF)

# floe_base.h error codes (cffi reads no macros or anonymous enums of the headers)
FLOE_OK = 0
FLOE_EINVAL = 1
FLOE_ENOMEM = 2
FLOE_EIO = 3
FLOE_EPARSE = 4
FLOE_EUNSTABLE = 5
FLOE_ENOTSUP = 6
FLOE_ESTOP = 7

# floe_motion (floe_base.h)
FLOE_FREE = 0
FLOE_FIXED = 1
FLOE_KINEMATIC = 2

ERRLEN = 4096   # the err buffers given to functions that take (char *err, size_t errlen)

_lib = None


class FloeError(RuntimeError):
    """An error of the floe library: code (FLOE_EINVAL, ...), name ("FLOE_EINVAL") and the
    library's message (for scenes "file:line:column: message")."""

    def __init__(self, code, message):
        self.code = int(code)
        self.name = ffi.string(lib().floe_strerror(self.code)).decode() if _lib else "FLOE_E?"
        self.message = message
        super().__init__(f"{message} ({self.name})" if message else self.name)


def library_candidates():
    """The paths tried for libfloe.so, in order (see the module's docstring)."""
    env = os.environ.get("FLOE_LIBRARY")
    if env:
        return [env]
    repo = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    return [os.path.join(repo, "build", "libfloe.so"), "libfloe.so"]


def lib():
    """The opened library (opened on the first call)."""
    global _lib
    if _lib is None:
        tried = []
        for path in library_candidates():
            if os.sep in path and not os.path.exists(path):
                tried.append(f"{path} (no such file)")
                continue
            try:
                _lib = ffi.dlopen(path, ffi.RTLD_NOW | ffi.RTLD_GLOBAL)
                break
            except OSError as e:
                tried.append(f"{path} ({e})")
        if _lib is None:
            raise OSError("floe: cannot open libfloe.so; build it (cmake target floe_shared, "
                          "FLOE_BUILD_PYTHON=ON) and set FLOE_LIBRARY to its path. Tried: "
                          + "; ".join(tried))
    return _lib


def check(rc, world=None):
    """Raise FloeError for a status rc other than FLOE_OK (a code, or -code from the
    functions that return a count or an index), with the world's last error as message
    when a world is given; returns rc otherwise."""
    if rc == FLOE_OK:
        return rc
    msg = ""
    if world is not None:
        msg = ffi.string(lib().floe_world_last_error(world)).decode(errors="replace")
    raise FloeError(abs(rc), msg)


def check_count(rc, world=None):
    """For functions that return a count or an index >= 0, or -code."""
    return rc if rc >= 0 else check(rc, world)


def call_err(fn, *args):
    """Call fn(*args, err, errlen), the form of the functions that write their message to
    a buffer; raise FloeError with that message when it fails."""
    err = ffi.new("char[]", ERRLEN)
    rc = fn(*args, err, ERRLEN)
    if rc != FLOE_OK:
        raise FloeError(rc, ffi.string(err).decode(errors="replace"))
    return rc


def cstr(s):
    """A Python str (or None) as a char* argument (bytes, or NULL)."""
    if s is None:
        return ffi.NULL
    return os.fsencode(s) if isinstance(s, os.PathLike) else str(s).encode()


def struct_dtype(ctype):
    """The numpy dtype of a cffi struct type (name or ctype): its fields at their C offsets,
    arrays as subarrays, itemsize the C sizeof. For zero-copy structured arrays."""
    t = ffi.typeof(ctype) if isinstance(ctype, str) else ctype
    names, formats, offsets = [], [], []
    for name, field in t.fields:
        names.append(name)
        formats.append(_field_dtype(field.type))
        offsets.append(field.offset)
    return np.dtype({"names": names, "formats": formats, "offsets": offsets,
                     "itemsize": ffi.sizeof(t)})


_SCALARS = {"double": np.float64, "float": np.float32, "int": np.intc, "long": np.int_,
            "unsigned char": np.uint8, "char": np.int8, "size_t": np.uintp}


def _field_dtype(t):
    if t.kind == "array":
        return (_field_dtype(t.item), (t.length,))
    if t.kind == "primitive" and t.cname in _SCALARS:
        return np.dtype(_SCALARS[t.cname])
    if t.kind == "struct":
        return struct_dtype(t)
    raise TypeError(f"floe: no numpy type for the C field type {t.cname}")


class _Memory:
    """The owner of a zero-copy array: exposes C memory through __array_interface__ and
    keeps `keep` (the World) alive as long as any array made from it."""

    def __init__(self, address, nbytes, keep):
        self.keep = keep
        self.__array_interface__ = {"shape": (nbytes,), "typestr": "|u1",
                                    "data": (address, True), "version": 3}


def array(ptr, count, dtype, shape=None, keep=None):
    """A read-only numpy array of `count` elements of dtype over the C memory at ptr,
    without copying, reshaped to shape; keep is held by the array (the World whose memory
    it is). An empty array when count is 0 or ptr is NULL."""
    dtype = np.dtype(dtype)
    shape = (count,) if shape is None else shape
    if count == 0 or ptr == ffi.NULL:
        a = np.zeros(shape if count == 0 else (0,), dtype)
        a.flags.writeable = False
        return a
    address = int(ffi.cast("uintptr_t", ptr))
    raw = np.asarray(_Memory(address, count * dtype.itemsize, keep))
    return raw.view(dtype).reshape(shape)


class Record(dict):
    """A dict whose keys read as attributes too (energy.kinetic_trans)."""

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError:
            raise AttributeError(name) from None


def to_record(cdata):
    """A C struct (cdata) as a Record of Python values: numbers, char arrays as str, other
    arrays as numpy arrays (copies)."""
    out = Record()
    for name, field in ffi.typeof(cdata).fields:
        value = getattr(cdata, name)
        t = field.type
        if t.kind == "array" and t.item.cname == "char":
            value = ffi.string(value).decode(errors="replace")
        elif t.kind == "array":
            value = np.array(list(value), dtype=_field_dtype(t.item))
        out[name] = value
    return out
