#!/usr/bin/env python3
"""test_reference.py - docs/reference.md is what `floe help --markdown` writes from the
registries' schemas (core/scene/reference.c): a schema changed without regenerating the
reference fails here, with the command that regenerates it.

usage: python3 tests/test_reference.py <floe_cli_path> <tests_dir>
"""
import difflib
import os
import sys

from pycheck import check, finish, run


def main():
    cli, tests = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    ref = os.path.join(os.path.dirname(tests), "docs", "reference.md")
    rc, out, err = run([cli, "help", "--markdown"])
    check(rc == 0, "floe help --markdown: exit %d %s" % (rc, err))
    have = open(ref).read() if os.path.exists(ref) else ""
    if not check(out == have, "docs/reference.md is stale: regenerate it with\n  floe help --markdown > docs/reference.md\n"
                 + "".join(list(difflib.unified_diff(have.splitlines(True), out.splitlines(True), "docs/reference.md",
                                                     "floe help --markdown"))[:60])):
        pass
    for name in ("hertz_mindlin", "sphere", "stress"):
        check("### `%s`" % name in out, "the reference documents %s" % name)
    finish("test_reference")


if __name__ == "__main__":
    main()
