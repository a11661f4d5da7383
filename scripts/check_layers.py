#!/usr/bin/env python3
"""check_layers.py - the library's folders form layers without cycles (docs/architecture.md).

The layers, bottom first, are the FLOE_LAYERS list of CMakeLists.txt (one source of truth),
then cli/. A source or header in a layer may include ("...") only headers of its own layer
or of a layer below it; an include of a header from a higher layer, or of a header that no
layer holds, is an error. Also checked: the quoted includes between headers have no cycle.

Usage: scripts/check_layers.py [repo root]. Exit status 0 when clean, 1 with one line per
offending include (file:line: what is wrong).

Also checked: the sources of each layer folder call each other without a circle. A source
uses another when it calls (or takes the address of) a function that only that other source
of the folder defines at file scope (not static); the uses must form a DAG, so each folder
reads bottom to top (docs/architecture.md, "Files"). This is read from the text (comments
and strings removed), not compiled: a call through a function pointer stored elsewhere, or
through a macro that builds the name, is not seen; a local variable named like another
file's function is not counted (only name( and initialiser or argument positions are).
"""
import os
import re
import sys


def layers_of(root):
    text = open(os.path.join(root, "CMakeLists.txt"), encoding="utf-8").read()
    m = re.search(r"set\(FLOE_LAYERS\s+([^)]*)\)", text)
    if not m:
        sys.exit("check_layers: no set(FLOE_LAYERS ...) in CMakeLists.txt")
    return m.group(1).split() + ["cli"]


def _strip(src):
    src = re.sub(r"/\*.*?\*/", " ", src, flags=re.S)
    src = re.sub(r"//[^\n]*", " ", src)
    src = re.sub(r'"(\\.|[^"\\\n])*"', '""', src)
    return re.sub(r"'(\\.|[^'\\\n])*'", "''", src)


_DEF = re.compile(r"^(?!static\b)(?:[A-Za-z_][\w \t*]*?[\s*])(\w+)\s*\([^;{]*\)\s*\{", re.M | re.S)
_SDEF = re.compile(r"^static\b[^;{(]*?[\s*](\w+)\s*\([^;{]*\)\s*\{", re.M | re.S)
_CALL = re.compile(r"\b(\w+)\s*\(")
_REF = re.compile(r"[=,(]\s*&?(\w+)\s*[,)};]")


def call_cycles(root, layers):
    """Circles of calls among the sources (.c, .cpp) of each layer folder."""
    out = []
    for layer in layers:
        d = os.path.join(root, layer)
        if not os.path.isdir(d):
            continue
        srcs = [n for n in sorted(os.listdir(d)) if n.endswith((".c", ".cpp"))]
        text = {f: _strip(open(os.path.join(d, f), encoding="utf-8", errors="replace").read()) for f in srcs}
        defs = {f: {m.group(1) for m in _DEF.finditer(text[f])} for f in srcs}
        owner = {}
        for f in srcs:
            for name in defs[f]:
                owner.setdefault(name, []).append(f)
        edges = {}
        for f in srcs:
            own = defs[f] | {m.group(1) for m in _SDEF.finditer(text[f])}
            for name in set(_CALL.findall(text[f])) | set(_REF.findall(text[f])):
                o = owner.get(name)
                if name not in own and o and len(o) == 1:
                    edges.setdefault(f, {}).setdefault(o[0], set()).add(name)
        state = {}

        def visit(u, stack):
            state[u] = 1
            for t in sorted(edges.get(u, {})):
                if state.get(t) == 1:
                    cyc = stack[stack.index(t):] + [t]
                    out.append(f"{layer}: call circle: " + " -> ".join(
                        f"{a} ({', '.join(sorted(edges[a][b])[:4])})" for a, b in zip(cyc, cyc[1:])) + f" -> {t}")
                elif not state.get(t):
                    visit(t, stack + [t])
            state[u] = 2

        for u in sorted(edges):
            if not state.get(u):
                visit(u, [u])
    return out


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), ".."))
    layers = layers_of(root)
    rank = {layer: k for k, layer in enumerate(layers)}
    # every header and source in a layer folder (only that folder, not below it)
    where = {}      # header basename -> layer
    files = []      # (path, layer)
    errors = []
    for layer in layers:
        d = os.path.join(root, layer)
        if not os.path.isdir(d):
            errors.append(f"{layer}: layer folder missing")
            continue
        for name in sorted(os.listdir(d)):
            path = os.path.join(d, name)
            if not os.path.isfile(path) or not name.endswith((".c", ".h", ".cpp")):
                continue
            files.append((path, layer))
            if name.endswith(".h"):
                if name in where:
                    errors.append(f"{layer}/{name}: header name also in {where[name]} (names must be unique)")
                where[name] = layer
    # the umbrella header at the root sits above the library, beside the CLI
    inc = re.compile(r'^\s*#\s*include\s+"([^"]+)"')
    edges = {}
    for path, layer in files:
        rel = os.path.relpath(path, root)
        for lineno, line in enumerate(open(path, encoding="utf-8", errors="replace"), 1):
            m = inc.match(line)
            if not m:
                continue
            name = os.path.basename(m.group(1))
            target = where.get(name)
            if target is None:
                errors.append(f"{rel}:{lineno}: includes \"{m.group(1)}\", which no layer holds")
            elif rank[target] > rank[layer]:
                errors.append(f"{rel}:{lineno}: {layer} includes \"{name}\" from {target}, a layer above it")
            if path.endswith(".h") and target is not None:
                edges.setdefault(os.path.basename(path), set()).add(name)
    # cycles among headers (depth-first search)
    state = {}

    def visit(h, stack):
        state[h] = 1
        for t in sorted(edges.get(h, ())):
            if state.get(t) == 1:
                errors.append("header include cycle: " + " -> ".join(stack[stack.index(t):] + [t]))
            elif not state.get(t):
                visit(t, stack + [t])
        state[h] = 2

    for h in sorted(edges):
        if not state.get(h):
            visit(h, [h])
    errors.extend(call_cycles(root, layers))
    for e in errors:
        print(e)
    if errors:
        print(f"check_layers: {len(errors)} problem(s); layers bottom first: {' < '.join(layers)}")
        return 1
    print(f"check_layers: {len(files)} files in {len(layers)} layers, no include from above, no header cycle, "
          "no call circle among the files of a folder")
    return 0


if __name__ == "__main__":
    sys.exit(main())
