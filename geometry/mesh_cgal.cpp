/* mesh_cgal.cpp - the CGAL algorithms of the triangle meshes (mesh_cgal.h, on plain arrays;
 * geometry/mesh.c wraps them in floe_cgal_mesh.h and this file calls nothing back): convex hull
 * (convex_hull_3), convex decomposition (Nef polyhedra, convex_decomposition_3),
 * self-intersection test and the exact point-mesh distance (AABB tree). All CGAL code of floe
 * lives in this one file (CGAL is header-only and slow to compile). Every entry point catches
 * every C++ exception and turns it into an error code and a message: no exception crosses
 * into C. */
#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Nef_polyhedron_3.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>
#include <CGAL/convex_decomposition_3.h>
#include <CGAL/convex_hull_3.h>

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <limits>
#include <new>
#include <vector>

#include "mesh_cgal.h"
extern "C" {
#include "floe_base.h"
}

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel IK;
typedef CGAL::Exact_predicates_exact_constructions_kernel EK;
typedef IK::Point_3 IPoint;
typedef EK::Point_3 EPoint;
typedef CGAL::Surface_mesh<IPoint> IMesh;
typedef CGAL::Surface_mesh<EPoint> EMesh;
typedef CGAL::Nef_polyhedron_3<EK> Nef;

void set_err(char *err, size_t errlen, const char *fmt, ...) {
    if (!err || errlen == 0) return;
    va_list ap;
    va_start(ap, fmt);
    std::vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
}

const char *nm(const char *name) { return name ? name : "mesh"; }

/* the surface mesh of a floe_cgal_mesh; false (and a message) when a triangle cannot be added
 * (non-manifold vertex or edge, or a repeated vertex index) */
template <class Mesh>
bool to_surface_mesh(const floe_cgal_mesh *m, Mesh &sm, const char *name, char *err, size_t errlen) {
    typedef typename boost::graph_traits<Mesh>::vertex_descriptor VD;
    typedef typename Mesh::Point P;
    std::vector<VD> vd((size_t)m->nv);
    for (int i = 0; i < m->nv; i++) vd[(size_t)i] = sm.add_vertex(P(m->v[3 * i], m->v[3 * i + 1], m->v[3 * i + 2]));
    for (int t = 0; t < m->nt; t++) {
        const int *f = m->tri + 3 * t;
        for (int k = 0; k < 3; k++)
            if (f[k] < 0 || f[k] >= m->nv) {
                set_err(err, errlen, "%s: triangle %d has vertex index %d out of range [0, %d)", nm(name), t, f[k],
                        m->nv);
                return false;
            }
        if (sm.add_face(vd[(size_t)f[0]], vd[(size_t)f[1]], vd[(size_t)f[2]]) == Mesh::null_face()) {
            set_err(err, errlen,
                    "%s is not a 2-manifold: triangle %d (vertices %d %d %d) makes a non-manifold edge or vertex",
                    nm(name), t, f[0], f[1], f[2]);
            return false;
        }
    }
    return true;
}

/* triangle mesh of a convex hull held in an IMesh (fan-triangulates any polygon face) */
int hull_to_floe(const IMesh &sm, floe_cgal_mesh *out, char *err, size_t errlen) {
    std::vector<int> index(sm.number_of_vertices() + sm.number_of_removed_vertices(), -1);
    std::vector<double> v;
    std::vector<int> tri;
    int nv = 0;
    for (IMesh::Vertex_index vi : sm.vertices()) {
        const IPoint &p = sm.point(vi);
        index[(size_t)vi] = nv++;
        v.push_back(p.x());
        v.push_back(p.y());
        v.push_back(p.z());
    }
    for (IMesh::Face_index f : sm.faces()) {
        std::vector<int> poly;
        for (IMesh::Vertex_index vi : CGAL::vertices_around_face(sm.halfedge(f), sm)) poly.push_back(index[(size_t)vi]);
        for (size_t k = 1; k + 1 < poly.size(); k++) {
            tri.push_back(poly[0]);
            tri.push_back(poly[k]);
            tri.push_back(poly[k + 1]);
        }
    }
    out->nv = nv;
    out->nt = (int)(tri.size() / 3);
    out->v = (double *)std::malloc(v.size() * sizeof(double));
    out->tri = (int *)std::malloc(tri.size() * sizeof(int));
    if (!out->v || !out->tri) {
        std::free(out->v);
        std::free(out->tri);
        out->v = NULL;
        out->tri = NULL;
        out->nv = out->nt = 0;
        set_err(err, errlen, "convex hull: out of memory");
        return FLOE_ENOMEM;
    }
    std::memcpy(out->v, v.data(), v.size() * sizeof(double));
    std::memcpy(out->tri, tri.data(), tri.size() * sizeof(int));
    return FLOE_OK;
}

/* convex hull of points in double precision; the hull vertices are input points */
int hull_points(const std::vector<IPoint> &pts, floe_cgal_mesh *out, const char *what, char *err, size_t errlen) {
    size_t n = pts.size();
    if (n < 4) {
        set_err(err, errlen, "%s: %zu points, a convex hull needs at least 4 (zero volume)", what, n);
        return FLOE_EINVAL;
    }
    /* dimension with exact predicates: find 4 affinely independent points */
    size_t i1 = 1, i2, i3;
    while (i1 < n && pts[i1] == pts[0]) i1++;
    for (i2 = i1 + 1; i2 < n && i1 < n; i2++)
        if (!CGAL::collinear(pts[0], pts[i1], pts[i2])) break;
    for (i3 = i2 + 1; i3 < n && i2 < n; i3++)
        if (CGAL::orientation(pts[0], pts[i1], pts[i2], pts[i3]) != CGAL::COPLANAR) break;
    if (i1 >= n || i2 >= n || i3 >= n) {
        set_err(err, errlen, "%s: all %zu points are %s: the convex hull is degenerate (zero volume)", what, n,
                i1 >= n ? "coincident" : i2 >= n ? "collinear" : "coplanar");
        return FLOE_EINVAL;
    }
    IMesh sm;
    CGAL::convex_hull_3(pts.begin(), pts.end(), sm);
    return hull_to_floe(sm, out, err, errlen);
}

/* collects the vertices of one shell of a Nef polyhedron */
struct Shell_points {
    std::vector<IPoint> *pts;
    void visit(Nef::Vertex_const_handle v) {
        const EPoint &p = v->point();
        pts->push_back(IPoint(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())));
    }
    void visit(Nef::Halfedge_const_handle) {}
    void visit(Nef::Halffacet_const_handle) {}
    void visit(Nef::SHalfedge_const_handle) {}
    void visit(Nef::SHalfloop_const_handle) {}
    void visit(Nef::SFace_const_handle) {}
};

bool finite_points(const double *p, int n) {
    for (int i = 0; i < 3 * n; i++)
        if (!std::isfinite(p[i])) return false;
    return true;
}

} // namespace

extern "C" void floe_cgal_mesh_free(floe_cgal_mesh *m) {
    if (!m) return;
    std::free(m->v);
    std::free(m->tri);
    m->v = NULL;
    m->tri = NULL;
    m->nv = m->nt = 0;
}

extern "C" int floe_cgal_hull(const double *pts, int n, floe_cgal_mesh *hull, char *err, size_t errlen) {
    if (!hull) return FLOE_EINVAL;
    hull->nv = hull->nt = 0;
    hull->v = NULL;
    hull->tri = NULL;
    if (!pts || n < 0) {
        set_err(err, errlen, "convex hull: no points");
        return FLOE_EINVAL;
    }
    if (!finite_points(pts, n)) {
        set_err(err, errlen, "convex hull: a point coordinate is not finite");
        return FLOE_EINVAL;
    }
    try {
        std::vector<IPoint> p;
        p.reserve((size_t)n);
        for (int i = 0; i < n; i++) p.push_back(IPoint(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]));
        return hull_points(p, hull, "convex hull", err, errlen);
    } catch (const std::bad_alloc &) {
        set_err(err, errlen, "convex hull: out of memory");
        return FLOE_ENOMEM;
    } catch (const std::exception &e) {
        set_err(err, errlen, "convex hull: CGAL failed: %s", e.what());
        return FLOE_EINVAL;
    } catch (...) {
        set_err(err, errlen, "convex hull: CGAL failed");
        return FLOE_EINVAL;
    }
}

extern "C" int floe_cgal_validate(const floe_cgal_mesh *m, const char *name, char *err, size_t errlen) {
    try {
        IMesh sm;
        if (!to_surface_mesh(m, sm, name, err, errlen)) return FLOE_EINVAL;
        if (!CGAL::is_closed(sm)) {
            set_err(err, errlen, "%s is open (not closed): it has boundary edges", nm(name));
            return FLOE_EINVAL;
        }
        if (CGAL::Polygon_mesh_processing::does_self_intersect(sm)) {
            set_err(err, errlen, "%s self-intersects: two of its triangles cross", nm(name));
            return FLOE_EINVAL;
        }
        return FLOE_OK;
    } catch (const std::bad_alloc &) {
        set_err(err, errlen, "%s: out of memory", nm(name));
        return FLOE_ENOMEM;
    } catch (const std::exception &e) {
        set_err(err, errlen, "%s: CGAL mesh check failed: %s", nm(name), e.what());
        return FLOE_EINVAL;
    } catch (...) {
        set_err(err, errlen, "%s: CGAL mesh check failed", nm(name));
        return FLOE_EINVAL;
    }
}

extern "C" int floe_cgal_decompose(const floe_cgal_mesh *m, const char *name, floe_cgal_mesh **pieces, int *npieces,
                                   char *err, size_t errlen) {
    if (!pieces || !npieces) return FLOE_EINVAL;
    *pieces = NULL;
    *npieces = 0;
    if (!m || m->nt <= 0 || m->nv <= 0) {
        set_err(err, errlen, "%s is empty: no triangles to decompose", nm(name));
        return FLOE_EINVAL;
    }
    std::vector<floe_cgal_mesh> out;
    try {
        EMesh sm;
        if (!to_surface_mesh(m, sm, name, err, errlen)) return FLOE_EINVAL;
        if (!CGAL::is_closed(sm)) {
            set_err(err, errlen, "%s is open (not closed): a convex decomposition needs a closed mesh", nm(name));
            return FLOE_EINVAL;
        }
        Nef nef(sm);
        if (!nef.is_simple()) {
            set_err(err, errlen, "%s is not a simple solid (non-manifold): cannot decompose it", nm(name));
            return FLOE_EINVAL;
        }
        CGAL::convex_decomposition_3(nef);
        /* the first volume is the unbounded outer one; marked volumes are the convex pieces */
        Nef::Volume_const_iterator ci = nef.volumes_begin();
        for (++ci; ci != nef.volumes_end(); ++ci) {
            if (!ci->mark()) continue;
            std::vector<IPoint> pts;
            Shell_points sp = {&pts};
            nef.visit_shell_objects(Nef::SFace_const_handle(ci->shells_begin()), sp);
            floe_cgal_mesh piece = {0, 0, NULL, NULL};
            char perr[256] = "";
            int rc = hull_points(pts, &piece, "convex piece", perr, sizeof perr);
            if (rc == FLOE_ENOMEM) throw std::bad_alloc();
            if (rc != FLOE_OK) continue; /* a flat sliver (rounding to double): no volume */
            out.push_back(piece);
        }
        if (out.empty()) {
            set_err(err, errlen, "%s: the convex decomposition has no piece with volume (zero volume)", nm(name));
            return FLOE_EINVAL;
        }
        floe_cgal_mesh *arr = (floe_cgal_mesh *)std::malloc(out.size() * sizeof(floe_cgal_mesh));
        if (!arr) throw std::bad_alloc();
        std::memcpy(arr, out.data(), out.size() * sizeof(floe_cgal_mesh));
        *pieces = arr;
        *npieces = (int)out.size();
        return FLOE_OK;
    } catch (const std::bad_alloc &) {
        for (floe_cgal_mesh &p : out) floe_cgal_mesh_free(&p);
        set_err(err, errlen, "%s: out of memory in the convex decomposition", nm(name));
        return FLOE_ENOMEM;
    } catch (const std::exception &e) {
        for (floe_cgal_mesh &p : out) floe_cgal_mesh_free(&p);
        set_err(err, errlen, "%s: CGAL convex decomposition failed: %s", nm(name), e.what());
        return FLOE_EINVAL;
    } catch (...) {
        for (floe_cgal_mesh &p : out) floe_cgal_mesh_free(&p);
        set_err(err, errlen, "%s: CGAL convex decomposition failed", nm(name));
        return FLOE_EINVAL;
    }
}

extern "C" int floe_cgal_distances(const floe_cgal_mesh *m, const double *pts, int n, double *dist) {
    typedef CGAL::AABB_face_graph_triangle_primitive<IMesh> Primitive;
    typedef CGAL::AABB_traits<IK, Primitive> Traits;
    typedef CGAL::AABB_tree<Traits> Tree;
    if (!m || !pts || !dist || n < 0) return FLOE_EINVAL;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    try {
        IMesh sm;
        if (!to_surface_mesh(m, sm, NULL, NULL, 0) || sm.number_of_faces() == 0) {
            for (int i = 0; i < n; i++) dist[i] = nan;
            return FLOE_EINVAL;
        }
        Tree tree(faces(sm).first, faces(sm).second, sm);
        tree.accelerate_distance_queries();
        for (int i = 0; i < n; i++) {
            IPoint p(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]);
            dist[i] = std::sqrt(tree.squared_distance(p));
        }
        return FLOE_OK;
    } catch (const std::bad_alloc &) {
        for (int i = 0; i < n; i++) dist[i] = nan;
        return FLOE_ENOMEM;
    } catch (...) {
        for (int i = 0; i < n; i++) dist[i] = nan;
        return FLOE_EINVAL;
    }
}
