"""test_library.py - where the package looks for libfloe.so (python/floe/_api.py,
docs/python.md "Finding the library"), in fresh interpreters: the library is opened once
per process."""
import os
import subprocess
import sys

PYTHON_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REPO = os.path.dirname(PYTHON_DIR)


def run(code, **env):
    e = {k: v for k, v in os.environ.items() if k != "FLOE_LIBRARY"}
    e.update(env, PYTHONPATH=PYTHON_DIR, PYTHONDONTWRITEBYTECODE="1")
    return subprocess.run([sys.executable, "-c", code], env=e, capture_output=True, text=True, timeout=60)


def test_missing_library_names_the_variable_and_the_path():
    r = run("import floe\ntry:\n    floe.lib()\nexcept OSError as e:\n    print('ERR', e)\n",
            FLOE_LIBRARY="/nonexistent/libfloe.so")
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("ERR ") and "FLOE_LIBRARY" in r.stdout
    assert "/nonexistent/libfloe.so (no such file)" in r.stdout


def test_without_the_variable_the_build_folder_comes_first():
    r = run("import floe._api as a; print(a.library_candidates())")
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == repr([os.path.join(REPO, "build", "libfloe.so"), "libfloe.so"])


def test_the_library_in_use_answers():
    # the one ctest points at (or the default): its error names come from C
    import floe
    assert floe.ffi.string(floe.lib().floe_strerror(floe.FLOE_EPARSE)) == b"FLOE_EPARSE"
    assert floe.ffi.string(floe.lib().floe_strerror(99)) == b"FLOE_E?"
