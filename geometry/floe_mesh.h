/* floe_mesh.h - triangle meshes as particle shapes: import with assimp (CMake option
 * FLOE_WITH_ASSIMP), convex hull and convex decomposition with CGAL (FLOE_WITH_CGAL).
 * The CGAL code lives in geometry/mesh_cgal.cpp behind this C header. Built without an
 * option, the functions that need it return FLOE_ENOTSUP (or NULL) with a message that
 * names the option. Every error message names the file (when there is one) and the defect. */
#ifndef FLOE_MESH_H
#define FLOE_MESH_H

#include "floe_geometry.h"

typedef struct floe_mesh {
    int nv, nt;
    double *v;   /* 3 nv vertex coordinates */
    int *tri;    /* 3 nt vertex indices */
} floe_mesh;

enum { FLOE_MESH_HAVE_ASSIMP = 1, FLOE_MESH_HAVE_CGAL = 2 };
/* which optional components this build has (FLOE_MESH_HAVE_* bits) */
int floe_mesh_features(void);

/* Read a triangle mesh (STL, OBJ, PLY and whatever else assimp reads), all meshes of the
 * file merged, coincident vertices joined, coordinates multiplied by scale. Errors:
 * unreadable file, no triangles, non-finite coordinates. */
int floe_mesh_load(const char *path, double scale, floe_mesh *out, char *err, size_t errlen);
void floe_mesh_free(floe_mesh *m);

/* Check a mesh is a closed, consistently oriented, non-degenerate 2-manifold without
 * self-intersections (CGAL when built with it; without CGAL only closedness, orientation
 * and degenerate triangles are checked). name is used in the messages (a file path). */
int floe_mesh_validate(const floe_mesh *m, const char *name, char *err, size_t errlen);

/* Convex hull of points (CGAL convex_hull_3) as a triangle mesh. Errors: fewer than 4
 * points, all coplanar (zero volume). */
int floe_mesh_hull(const double *pts, int n, floe_mesh *hull, char *err, size_t errlen);

/* Convex decomposition of a closed mesh (CGAL Nef polyhedron convex_decomposition_3):
 * *pieces is an array of *npieces convex triangle meshes (free each with floe_mesh_free,
 * then free(*pieces)). */
int floe_mesh_decompose(const floe_mesh *m, const char *name, floe_mesh **pieces, int *npieces, char *err,
                        size_t errlen);

/* Convex polyhedron from points: the hull (CGAL convex_hull_3, O(n log n)), its coplanar
 * neighbouring triangles merged into faces (O(n log n), memory linear in n), then
 * floe_polyhedron_from_faces. */
floe_geometry *floe_polyhedron_from_points(const double *pts, int n, char *err, size_t errlen);

/* Convex polyhedron from its faces (geometry/polytope.c): vertices v (nv), face f is the
 * convex polygon fv[fstart[f] .. fstart[f+1]) counter-clockwise seen from outside with the
 * unit outward plane planes[4f .. 4f+3] (n, d: n.X <= d inside). Linear in the size. */
floe_geometry *floe_polyhedron_from_faces(const double *v, int nv, const int *fstart, const int *fv, int nf,
                                          const double *planes, char *err, size_t errlen);

/* A shape from a mesh file: mode "hull" (one convex polyhedron) or "decompose" (a compound
 * of convex polyhedra; a convex mesh gives one piece). dim is the world dimension (3). */
floe_geometry *floe_mesh_shape(const char *path, const char *mode, double scale, char *err, size_t errlen);

/* Exact unsigned distance from p to the mesh surface (CGAL AABB tree), for validation;
 * returns NaN without CGAL. The tree is built per call: for tests, not for inner loops. */
int floe_mesh_distances(const floe_mesh *m, const double *pts, int n, double *dist);

#endif
