#!/usr/bin/env python3
"""make_meshes.py - writes the two mesh files of examples/mesh-grains (standard library only).

  python3 examples/mesh-grains/make_meshes.py [OUTDIR]     (default: this script's folder)

- grain.stl: a rough grain, ASCII STL. An icosahedron subdivided once (42 vertices, 80
  triangles) projected on the unit sphere, each vertex's radius multiplied by
  1 + 0.25 u (u uniform in [-1, 1], random.seed(42)) and the shape stretched to 1.3 x 1.0 x
  0.8 (a flattened, elongated pebble of about unit radius). The perturbed surface is not
  convex; the scene uses it with mode: hull (its convex hull, a polyhedron with up to 80
  triangles), at scale 0.005 (a grain about 1 cm long).
- lshape.obj: a non-convex closed solid, Wavefront OBJ: an L-shaped prism, the L made of
  three unit squares (outline (0,0) (2,0) (2,1) (1,1) (1,2) (0,2)) extruded to z = 0..1:
  12 vertices, 20 triangles (4 per cap, 2 per side face), counter-clockwise seen from
  outside. The scene uses mode: decompose (CGAL splits it into convex pieces) at scale
  0.01 (a 2 x 2 x 1 cm L).
The files are committed, so the scene runs without Python; rerun this to regenerate them
(the output is deterministic).
"""
import math
import os
import random
import sys


def icosphere(levels):
    t = (1 + math.sqrt(5)) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        mid = {}

        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = [(v[a][i] + v[b][i]) / 2 for i in range(3)]
                n = math.sqrt(sum(x * x for x in p))
                v.append(tuple(x / n for x in p))
                mid[key] = len(v) - 1
            return mid[key]

        nf = []
        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return v, f


def write_stl(path, name, v, f):
    with open(path, "w") as out:
        out.write("solid %s\n" % name)
        for a, b, c in f:
            p, q, r = v[a], v[b], v[c]
            u = [q[i] - p[i] for i in range(3)]
            w = [r[i] - p[i] for i in range(3)]
            n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]]
            ln = math.sqrt(sum(x * x for x in n)) or 1.0
            out.write("  facet normal %.6e %.6e %.6e\n    outer loop\n" % tuple(x / ln for x in n))
            for x in (p, q, r):
                out.write("      vertex %.6e %.6e %.6e\n" % x)
            out.write("    endloop\n  endfacet\n")
        out.write("endsolid %s\n" % name)


def grain():
    random.seed(42)
    v, f = icosphere(0)
    stretch = (1.3, 1.0, 0.8)
    out = []
    for p in v:
        s = 1 + 0.25 * random.uniform(-1, 1)
        out.append(tuple(p[i] * s * stretch[i] for i in range(3)))
    return out, f


def lshape():
    xy = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]  # counter-clockwise seen from +z
    n = len(xy)
    v = [(x, y, 0.0) for x, y in xy] + [(x, y, 1.0) for x, y in xy]
    f = []
    # caps: fans from the reflex corner (1, 1), index 3, cover the L exactly
    for i, j in ((4, 5), (5, 0), (0, 1), (1, 2)):
        f.append((3 + n, i + n, j + n))   # top, normal +z
        f.append((3, j, i))               # bottom, normal -z
    for i in range(n):
        j = (i + 1) % n
        f.append((i, j, j + n))
        f.append((i, j + n, i + n))
    return v, f


def write_obj(path, v, f):
    with open(path, "w") as out:
        out.write("# L-shaped prism, examples/mesh-grains/make_meshes.py\n")
        for p in v:
            out.write("v %g %g %g\n" % p)
        for a, b, c in f:
            out.write("f %d %d %d\n" % (a + 1, b + 1, c + 1))


def main():
    outdir = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    v, f = grain()
    write_stl(os.path.join(outdir, "grain.stl"), "grain", v, f)
    v2, f2 = lshape()
    write_obj(os.path.join(outdir, "lshape.obj"), v2, f2)
    print("wrote grain.stl (%d vertices, %d triangles) and lshape.obj (%d vertices, %d triangles)"
          % (len(v), len(f), len(v2), len(f2)))


if __name__ == "__main__":
    main()
