/* mesh_cgal.h - the CGAL algorithms of the triangle meshes (geometry/mesh_cgal.cpp) on plain
 * arrays, for geometry/mesh.c (not installed). The C++ side knows nothing of floe_mesh.h:
 * mesh.c wraps these in the public functions, so the dependency runs one way, mesh.c ->
 * mesh_cgal.cpp. Every function catches every C++ exception and returns an error code
 * (floe_base.h) with a message in err (when given). */
#ifndef FLOE_MESH_CGAL_H
#define FLOE_MESH_CGAL_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* a triangle mesh: 3 nv coordinates, 3 nt vertex indices (malloc'd when a function here
 * makes one: floe_cgal_mesh_free) */
typedef struct floe_cgal_mesh {
    int nv, nt;
    double *v;
    int *tri;
} floe_cgal_mesh;

void floe_cgal_mesh_free(floe_cgal_mesh *m);
/* convex hull of n points (convex_hull_3); fewer than 4 or coplanar points: FLOE_EINVAL */
int floe_cgal_hull(const double *pts, int n, floe_cgal_mesh *hull, char *err, size_t errlen);
/* closed, 2-manifold, no self-intersection; name (a file) in the messages */
int floe_cgal_validate(const floe_cgal_mesh *m, const char *name, char *err, size_t errlen);
/* convex decomposition (Nef polyhedra): *pieces, an array of *npieces meshes (free each, then
 * the array) */
int floe_cgal_decompose(const floe_cgal_mesh *m, const char *name, floe_cgal_mesh **pieces, int *npieces, char *err,
                        size_t errlen);
/* exact unsigned distance of each point to the surface (AABB tree); NaN on failure */
int floe_cgal_distances(const floe_cgal_mesh *m, const double *pts, int n, double *dist);

#ifdef __cplusplus
}
#endif

#endif
