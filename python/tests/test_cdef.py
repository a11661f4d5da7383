"""test_cdef.py - the package's C declarations (python/floe/_cdef.py) are copies of the
public headers: every declaration, struct field for field, reads the same in the header
once comments and spacing are set aside. cffi's ABI mode has no compiler to check a
struct's layout against the library, so a field added to a header must show here."""
import os
import re

from floe._cdef import CDEF

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def normalise(text):
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    text = re.sub(r"//[^\n]*", " ", text)
    text = re.sub(r"^\s*#.*$", " ", text, flags=re.M)
    text = re.sub(r"\s+", " ", text)
    return re.sub(r" ?([(){}\[\];,*]) ?", r"\1", text).strip()


def statements(text):
    """Top-level declarations: up to a ';' outside braces."""
    out, depth, start = [], 0, 0
    for k, ch in enumerate(text):
        depth += ch == "{"
        depth -= ch == "}"
        if ch == ";" and depth == 0:
            out.append(text[start:k + 1].strip())
            start = k + 1
    return [s for s in out if s]


def public_headers():
    names = []
    for folder, _, files in os.walk(ROOT):
        rel = os.path.relpath(folder, ROOT)
        if rel.split(os.sep)[0] in ("build", "python", "tests", "bench", "examples", ".git") or rel.startswith("build"):
            continue
        names += [os.path.join(folder, f) for f in files if f.startswith("floe_") and f.endswith(".h")]
    return names


def test_every_declaration_is_in_a_public_header():
    headers = normalise(" ".join(open(h, encoding="utf-8").read() for h in public_headers()))
    decls = statements(normalise(CDEF))
    assert len(decls) > 30
    missing = [d for d in decls if d not in headers]
    assert not missing, "declarations of python/floe/_cdef.py not found as such in the headers: " + \
        "\n".join(missing)


def test_a_changed_field_would_be_caught():
    # the check itself: a struct with one field renamed is not found
    headers = normalise(open(os.path.join(ROOT, "core", "world", "floe_view.h"), encoding="utf-8").read())
    decl = next(d for d in statements(normalise(CDEF)) if "floe_contact_info{" in d)
    assert decl in headers
    assert decl.replace("double fn;", "float fn;") not in headers
