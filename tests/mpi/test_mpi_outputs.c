/* test_mpi_outputs.c - every rank's own outputs on a split world (floe_world_parallel_add_output,
 * core/parallel, docs/parallel.md) and the vtk writer's pieces through the library (no CLI).
 * Run under mpirun with 1, 2 and 4 ranks (tests/CMakeLists.txt). Every rank builds the same
 * 125 spheres (a fast gas) between 6 walls and splits it; then
 *   - an output that reads contacts is refused with FLOE_ENOTSUP on every rank (and destroyed);
 *   - a counting output every 7 steps and one every 5.5 dt of simulated time are called at the
 *     split (step 0), at the steps where they are due, and at their end (floe_world_parallel_finish)
 *     only when the last step was not observed: 25 steps give steps 0 7 14 21 + end and
 *     0 6 11 17 22 + end (t >= k x 5.5 dt), the same on every rank;
 *   - a vtk piece writer (ASCII) every 10 steps: frames at steps 0, 10, 20 and the end (25),
 *     rank 0's p.pvd lists p_00000F.pvtu for F = 0..3, each .pvtu names the pieces
 *     p_00000F_0..size-1.vtu, every piece exists and the ids of their points (parsed from the
 *     ASCII id arrays) are the 125 spheres' global ids 6..130, each once: no wall, no ghost. */
#include "floe.h"
#include "floe_parallel.h"
#include "../check.h"
#include "../test_files.h"
#include "mpi_common.h"
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const double L = 0.02;
enum { NSIDE = 5, NSTEPS = 25 };

static floe_world *build(void) {
    floe_world_def d = floe_default_world_def();
    d.dim = 3; d.dt = 1e-6;
    floe_world *w = floe_world_create(&d, NULL, 0);
    mpi_test_add_glass(w, 1e7);
    int g = floe_world_add_geometry(w, floe_sphere_create(0.001));
    mpi_test_box_walls(w, L, L, L, 0, 6);
    unsigned s = 4242;
    const double h = L / NSIDE;
    for (int a = 0; a < NSIDE; a++)
        for (int b = 0; b < NSIDE; b++)
            for (int c = 0; c < NSIDE; c++) {
                floe_particle_def p = floe_default_particle_def();
                p.geometry = g;
                double j[3];
                for (int k = 0; k < 3; k++) { s = s * 1103515245u + 12345u; j[k] = (s >> 8) / 16777216.0 - 0.5; }
                floe_v3_set(p.x, (a + 0.5) * h, (b + 0.5) * h, (c + 0.5) * h);
                floe_v3_set(p.v, 20 * j[0], 20 * j[1], 20 * j[2]);
                floe_world_add_particle(w, &p);
            }
    if (floe_world_prepare(w)) { fprintf(stderr, "prepare: %s\n", floe_world_last_error(w)); exit(2); }
    return w;
}

/* a counting output: the steps it was called at, and whether at its end */
typedef struct counter {
    floe_observer base;
    long steps[64];
    int n, ends;
    int *destroyed;
} counter;
static int cnt_observe(floe_observer *o, floe_world *w) {
    counter *c = (counter *)o;
    if (c->n < 64) c->steps[c->n++] = floe_world_step_count(w);
    return FLOE_OK;
}
static int cnt_end(floe_observer *o, floe_world *w) {
    counter *c = (counter *)o;
    /* the end writes the final state only when this step was not observed */
    if (c->n == 0 || c->steps[c->n - 1] != floe_world_step_count(w)) {
        c->ends++;
        return cnt_observe(o, w);
    }
    return FLOE_OK;
}
static void cnt_destroy(floe_observer *o) {
    counter *c = (counter *)o;
    if (c->destroyed) *c->destroyed = 1;
    free(c);
}
static const floe_observer_class cnt_class = {1, "counter", NULL, cnt_observe, cnt_end, cnt_destroy, 0, NULL, NULL, NULL, 0, NULL, NULL};
static const floe_observer_class cnt_contacts_class = {1, "counter_contacts", NULL, cnt_observe, cnt_end, cnt_destroy, 1,
                                                       NULL, NULL, NULL, 0, NULL, NULL};

static counter *counter_new(const floe_observer_class *k, long every, double period) {
    counter *c = calloc(1, sizeof *c);
    c->base.klass = k;
    c->base.period_steps = every;
    c->base.period_time = period;
    return c;
}

static int same_list(const long *got, int n, const long *want, int m) {
    if (n != m) return 0;
    for (int k = 0; k < n; k++)
        if (got[k] != want[k]) return 0;
    return 1;
}

static int count_of(const char *s, const char *what) {
    int n = 0;
    for (const char *p = s; (p = strstr(p, what)); p += strlen(what)) n++;
    return n;
}

/* rank 0: the files of the vtk pieces in dir */
static void check_files(const char *dir, int frames) {
    char path[512];
    snprintf(path, sizeof path, "%s/p.pvd", dir);
    char *pvd = slurp(path);
    CHECK(pvd != NULL, "p.pvd written");
    if (!pvd) return;
    CHECK(count_of(pvd, "<DataSet") == frames && count_of(pvd, ".pvtu\"") == frames && count_of(pvd, ".vtu\"") == 0,
          "p.pvd lists the %d .pvtu frames (%d DataSets)", frames, count_of(pvd, "<DataSet"));
    for (int f = 0; f < frames; f++) {
        char name[64];
        snprintf(name, sizeof name, "file=\"p_%06d.pvtu\"", f);
        CHECK(strstr(pvd, name) != NULL, "p.pvd names p_%06d.pvtu", f);
        snprintf(path, sizeof path, "%s/p_%06d.pvtu", dir, f);
        char *pv = slurp(path);
        CHECK(pv != NULL && count_of(pv, "<Piece Source=") == size_, "frame %d: the .pvtu names %d pieces", f, size_);
        int seen[131] = {0}, bad = 0, total = 0;
        for (int r = 0; r < size_; r++) {
            snprintf(name, sizeof name, "<Piece Source=\"p_%06d_%d.vtu\"/>", f, r);
            CHECK(pv && strstr(pv, name), "frame %d names piece %d", f, r);
            snprintf(path, sizeof path, "%s/p_%06d_%d.vtu", dir, f, r);
            char *pc = slurp(path);
            CHECK(pc != NULL, "frame %d: piece %d exists", f, r);
            if (!pc) continue;
            const char *a = strstr(pc, "Name=\"id\" format=\"ascii\">");
            const char *e = a ? strstr(a, "</DataArray>") : NULL;
            CHECK(a && e, "frame %d piece %d: an ASCII id array", f, r);
            if (a && e) {
                char *p = strchr(a, '>') + 1;
                for (;;) {
                    char *q;
                    long id = strtol(p, &q, 10);
                    if (q == p || q > e) break;
                    total++;
                    if (id < 6 || id > 130 || seen[id]++) bad++;
                    p = q;
                }
            }
            free(pc);
        }
        int missing = 0;
        for (int id = 6; id <= 130; id++) missing += !seen[id];
        CHECK(total == 125 && !bad && !missing, "frame %d: the pieces hold ids 6..130 once each (%d points, %d bad, %d "
              "missing)", f, total, bad, missing);
        free(pv);
    }
    free(pvd);
}

int main(int argc, char **argv) {
    mpi_test_init(&argc, &argv);
    char dir[256] = "";
    if (rank_ == 0) {
        snprintf(dir, sizeof dir, "%s/floe_mpi_outputs_XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
        if (!mkdtemp(dir)) { perror("mkdtemp"); MPI_Abort(MPI_COMM_WORLD, 2); }
    }
    MPI_Bcast(dir, sizeof dir, MPI_CHAR, 0, MPI_COMM_WORLD);
    floe_world *w = build();
    int rc = floe_world_parallel_init(w, NULL);
    CHECK(rc == 0, "split: %s", rc ? floe_world_last_error(w) : "");
    if (rc == 0) {
        int destroyed = 0;
        counter *cc = counter_new(&cnt_contacts_class, 1, 0);
        cc->destroyed = &destroyed;
        rc = floe_world_parallel_add_output(w, &cc->base);
        CHECK(rc == FLOE_ENOTSUP && destroyed, "an output that reads contacts: refused (%d) and destroyed (%d)", rc,
              destroyed);
        counter *c7 = counter_new(&cnt_class, 7, 0), *ct = counter_new(&cnt_class, 0, 5.5e-6);
        CHECK(floe_world_parallel_add_output(w, &c7->base) == 0, "add a counting output: %s", floe_world_last_error(w));
        CHECK(floe_world_parallel_add_output(w, &ct->base) == 0, "add a timed output: %s", floe_world_last_error(w));
        char err[256] = "";
        floe_observer *v = floe_vtk_writer_create_piece(dir, "p", rank_, size_, err, sizeof err);
        CHECK(v != NULL, "piece writer: %s", err);
        if (v) {
            floe_vtk_writer_set_ascii(v, 1);
            v->period_steps = 10;
            CHECK(floe_world_parallel_add_output(w, v) == 0, "add the piece writer: %s", floe_world_last_error(w));
        }
        rc = 0;
        for (int s = 0; s < NSTEPS && rc == 0; s++) rc = floe_world_step(w);
        CHECK(rc == 0, "steps: %s", rc ? floe_world_last_error(w) : "");
        rc = floe_world_parallel_finish(w);
        CHECK(rc == 0, "finish: %s", rc ? floe_world_last_error(w) : "");
        static const long want7[] = {0, 7, 14, 21, 25}, wantt[] = {0, 6, 11, 17, 22, 25};
        CHECK(same_list(c7->steps, c7->n, want7, 5) && c7->ends == 1, "every 7 steps: called at 0 7 14 21 and its end "
              "(%d calls, %d ends)", c7->n, c7->ends);
        CHECK(same_list(ct->steps, ct->n, wantt, 6) && ct->ends == 1, "every 5.5 dt: called at 0 6 11 17 22 and its end "
              "(%d calls, %d ends)", ct->n, ct->ends);
        int n[2] = {c7->n, ct->n}, lo[2], hi[2];
        MPI_Allreduce(n, lo, 2, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
        MPI_Allreduce(n, hi, 2, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
        CHECK(lo[0] == hi[0] && lo[1] == hi[1], "the same calls on every rank");
        MPI_Barrier(MPI_COMM_WORLD);
        if (rank_ == 0) check_files(dir, 4);
    }
    int fails = check_fail_, all;
    MPI_Allreduce(&fails, &all, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    if (rank_ == 0) {
        printf("test_mpi_outputs (%d ranks): %d passed on rank 0, %d failed checks over all ranks\n", size_, check_pass_,
               all);
        char cmd[300];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
        if (!all && system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
    }
    floe_world_destroy(w);
    MPI_Finalize();
    return all ? 1 : 0;
}
