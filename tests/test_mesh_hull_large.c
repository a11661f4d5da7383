/* test_mesh_hull_large.c - mesh hull mode on a large closed mesh (geometry/mesh.c, issue 10):
 * a UV sphere of ~41,000 vertices written as OBJ becomes one convex polyhedron in seconds with
 * memory linear in the size (the former face search was quadratic: ~13 GB and minutes). The
 * shape's volume matches the closed mesh's own (1e-6: assimp reads floats) and the sphere's (0.1 %). */
#include "check.h"
#include "floe_mesh.h"
#include "floe.h"
#include "world_read.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* UV sphere of radius r: nu longitudes, nv latitude bands; returns the mesh volume */
static double write_uv_sphere(const char *path, int nu, int nv, double r, int *nverts)
{
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    int n = 2 + (nv - 1) * nu;
    double *v = malloc((size_t)n * 3 * sizeof *v);
    v[0] = 0, v[1] = 0, v[2] = r;
    for (int i = 1; i < nv; i++)
        for (int j = 0; j < nu; j++) {
            double th = M_PI * i / nv, ph = 2 * M_PI * j / nu;
            double *p = v + 3 * (1 + (i - 1) * nu + j);
            p[0] = r * sin(th) * cos(ph), p[1] = r * sin(th) * sin(ph), p[2] = r * cos(th);
        }
    double *s = v + 3 * (n - 1);
    s[0] = 0, s[1] = 0, s[2] = -r;
    for (int i = 0; i < n; i++) fprintf(f, "v %.17g %.17g %.17g\n", v[3 * i], v[3 * i + 1], v[3 * i + 2]);
    double vol6 = 0;
#define TRI(a, b, c)                                                                                  \
    do {                                                                                              \
        fprintf(f, "f %d %d %d\n", (a) + 1, (b) + 1, (c) + 1);                                        \
        const double *A = v + 3 * (a), *B = v + 3 * (b), *C = v + 3 * (c);                            \
        vol6 += A[0] * (B[1] * C[2] - B[2] * C[1]) - A[1] * (B[0] * C[2] - B[2] * C[0]) +             \
                A[2] * (B[0] * C[1] - B[1] * C[0]);                                                   \
    } while (0)
    for (int j = 0; j < nu; j++) TRI(0, 1 + j, 1 + (j + 1) % nu);
    for (int i = 0; i < nv - 2; i++)
        for (int j = 0; j < nu; j++) {
            int a = 1 + i * nu + j, b = 1 + i * nu + (j + 1) % nu, c = a + nu, d = b + nu;
            TRI(a, c, d);
            TRI(a, d, b);
        }
    int base = 1 + (nv - 2) * nu;
    for (int j = 0; j < nu; j++) TRI(n - 1, base + (j + 1) % nu, base + j);
#undef TRI
    fclose(f);
    free(v);
    *nverts = n;
    return vol6 / 6;
}

static double geom_volume(const floe_geometry *g)
{
    floe_mass_properties mp;
    if (g->klass->mass_properties(g, 3, 1.0, &mp) != FLOE_OK) return -1;
    return mp.mass;
}

int main(void)
{
    if ((floe_mesh_features() & (FLOE_MESH_HAVE_ASSIMP | FLOE_MESH_HAVE_CGAL)) !=
        (FLOE_MESH_HAVE_ASSIMP | FLOE_MESH_HAVE_CGAL)) {
        printf("built without assimp or CGAL: skipped\n");
        return check_summary("test_mesh_hull_large");
    }
    char dir[] = "/tmp/floe_uv_sphere_XXXXXX", path[64];
    CHECK(mkdtemp(dir) != NULL, "mkdtemp");
    snprintf(path, sizeof path, "%s/sphere.obj", dir);
    int nverts = 0;
    double r = 0.01, vmesh = write_uv_sphere(path, 286, 144, r, &nverts);
    printf("  UV sphere: %d vertices, mesh volume %.10g m^3\n", nverts, vmesh);
    CHECK(nverts > 40000, "about 41,000 vertices (got %d)", nverts);
    char err[512] = "";
    double t0 = now_s();
    floe_geometry *g = floe_mesh_shape(path, "hull", 1.0, err, sizeof err);
    double el = now_s() - t0;
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    double peak_mb = (double)ru.ru_maxrss / 1024.0;
    CHECK(g != NULL, "hull of the UV sphere: %s", err);
    printf("  hull mode: %.2f s, peak RSS %.0f MB\n", el, peak_mb);
    CHECK(el < 60.0, "hull mode took %.1f s (limit 60 s; the quadratic face search took minutes)", el);
    CHECK(peak_mb < 1500.0, "peak RSS %.0f MB (limit 1500 MB; the quadratic face lists needed ~13 GB)", peak_mb);
    if (g) {
        const floe_polytope *p = (const floe_polytope *)g;
        printf("  polyhedron: %d vertices, %d faces, %d triangles\n", p->nv, p->np, p->nt);
        CHECK(p->nv == nverts, "every vertex of the sphere is a hull vertex (%d of %d)", p->nv, nverts);
        /* assimp reads coordinates as float: 1e-6 */
        CHECK_NEAR(geom_volume(g), vmesh, 1e-6, "hull volume vs the closed mesh's volume");
        CHECK_NEAR(geom_volume(g), 4.0 / 3.0 * M_PI * r * r * r, 1e-3, "hull volume vs the sphere's");
        floe_geometry_destroy(g);
    }
    remove(path);
    rmdir(dir);
    return check_summary("test_mesh_hull_large");
}
