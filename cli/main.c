/* main.c - the `floe` command: run a scene file (or the built-in demo), check a scene,
 * print build information. Scene format: docs/scene-format.md. */
#include "floe_scene.h"
#include "floe_observer.h"
#include "floe_registry.h"
#include "floe_view.h"
#include "floe_detect.h"
#include "floe_mesh.h"
#include "floe_newmark.h"
#include "floe_checkpoint.h"
#ifdef _OPENMP
#include <omp.h>
#endif
#include "floe_parallel.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#ifdef FLOE_HAVE_MPI
#include <mpi.h>
#endif

static const char *prog = "floe";

static void usage(FILE *f)
{
    fprintf(f,
            "usage: %s run [SCENE] [-o OUTDIR] [-q] [-t N] [--checkpoint-every T] [--checkpoint FILE] [--restart FILE]\n"
            "                [--balance weights|time]\n"
            "                                        run a scene (no SCENE: the built-in demo)\n"
            "       %s check SCENE                   load and prepare a scene, print its summary\n"
            "       %s info                          version, build and the registered components\n"
            "       %s help [KIND [NAME]]            the components of a kind (floe info lists the kinds)\n"
            "                                        and the parameters of one, e.g. help law hertz_mindlin\n"
            "       %s help --markdown               the reference of every component (docs/reference.md)\n"
            "       %s --help\n"
            "\n"
            "  -o OUTDIR   directory for the scene's outputs (default ./out)\n"
            "  -q          quiet: no summary and no progress line, only errors\n"
            "  -t N, --threads N  threads (OpenMP; default OMP_NUM_THREADS or every core): the\n"
            "              results are the same to the last bit for any N (docs/parallel.md)\n"
            "  --checkpoint-every T  write a checkpoint every T seconds of simulated time (at the first\n"
            "              step boundary at or after each multiple of T), replacing the previous one\n"
            "  --checkpoint FILE     the checkpoint file (default OUTDIR/checkpoint.bin)\n"
            "  --restart FILE        continue the run saved in FILE: the same SCENE and OUTDIR as the run\n"
            "              that wrote it; the outputs go on as if the run had not stopped\n"
            "              (docs/checkpoints.md). Under mpirun too: the file is the serial one, written\n"
            "              by rank 0, and continues under any number of ranks (docs/parallel.md)\n"
            "  --balance weights|time  under mpirun: the ranks' shares of the bisection (docs/parallel.md):\n"
            "              equal shares of the estimated work (weights, the default: a run repeats to\n"
            "              the last bit) or sized by each rank's measured speed (time: a slower or\n"
            "              busier core gets less; runs agree within round-off). Serial runs: no effect\n"
            "  --plugin F  load the plugin F (a shared library registering shapes, laws, normal and\n"
            "              tangential parts, outputs, PD materials, force providers, integrators and\n"
            "              packings) before the command; repeatable; scenes can list theirs under plugins:\n"
            "\n"
            "Ctrl-C (SIGINT), SIGTERM or SIGUSR1 stops a run after the current step with every\n"
            "output complete and a checkpoint written (exit 130 / 143 / 138; continue with\n"
            "--restart); a second signal kills at once. Under mpirun: signal mpirun with SIGUSR1\n"
            "(it forwards it to every rank; SIGTERM is followed by SIGKILL after 1 s); the ranks\n"
            "stop together within about 20 ms of steps.\n"
            "Scene files are YAML, described in docs/scene-format.md.\n",
            prog, prog, prog, prog, prog, prog);
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void fmt_duration(char *buf, size_t len, double s)
{
    if (!(s >= 0) || s > 1e8) { snprintf(buf, len, "--:--"); return; }
    long t = (long)(s + 0.5);
    if (t >= 3600) snprintf(buf, len, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
    else snprintf(buf, len, "%ld:%02ld", t / 60, t % 60);
}

/* SIGINT / SIGTERM / SIGUSR1 during a run: the handler only records the signal; the progress
 * callback (called after every step) sees it and stops the run cleanly, so the observers
 * finish the frame they are writing and close their files. A second signal kills at once
 * (SA_RESETHAND). Under MPI the ranks agree every ~20 ms of steps on whether any has one
 * (on_progress; mpirun forwards SIGUSR1 to every rank; SIGTERM it forwards too, then kills
 * the ranks after odls_base_sigkill_timeout, 1 s by default), so that all stop at the same
 * step. */
static volatile sig_atomic_t stop_signal = 0;

static void on_stop_signal(int sig) { stop_signal = sig; }

static void install_stop_handlers(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESETHAND | SA_RESTART;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGUSR1, &sa, NULL);
}

static const char *signal_name(int sig) {
    return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : sig == SIGUSR1 ? "SIGUSR1" : "a signal";
}

typedef struct progress {
    int show;
    double t0, last;
    long last_step;
    int printed;
    /* checkpoints: the file, the scene's hash and name, the interval and the next time */
    const char *ckpt;
    uint64_t hash;
    const char *scene;
    double every, next;
    int written;         /* checkpoints written */
    int failed;          /* a checkpoint could not be written (reported once) */
    int mpi;             /* under MPI: the checkpoint is collective (every rank calls it) */
    floe_world *full;    /* under MPI, rank 0: the unsplit world the state is gathered into */
    int stopped;         /* under MPI: the signal the ranks agreed to stop on (0: none) */
    long agree_at;       /* under MPI: the next step of the stop agreement (0: the first) */
    double agree_t;      /* and the wall time of the last one */
    long last_agreed;    /* the step of the last one */
    int loud;            /* prints its warning (rank 0 under MPI) */
} progress;

static void write_checkpoint(progress *p, const floe_world *w)
{
    char err[1024];
    const int rc = p->mpi ? floe_world_parallel_checkpoint_save(w, p->full, p->ckpt, p->hash, p->scene, err, sizeof err)
                          : floe_world_checkpoint_save(w, p->ckpt, p->hash, p->scene, err, sizeof err);
    if (rc == FLOE_OK) {
        p->written++;
        return;
    }
    if (!p->failed && p->loud) {
        if (p->printed) fprintf(stderr, "\n");
        fprintf(stderr, "%s: warning: %s (the run goes on)\n", prog, err);
    }
    p->failed = 1;
}

static int on_progress(const floe_world *w, long step, long nsteps, void *user)
{
    progress *p = user;
    /* under MPI every rank takes part in the agreement (one int, a collective), every k
     * steps: k about 20 ms of steps (from 1 to 1024), the least that any rank proposes,
     * agreed in the same word (the signal in the high bits, 1024 - k below: the largest word
     * carries any signal and the smallest k), and at the last step, so that a signal stops
     * the run within about 20 ms without a collective at every step of a fast run (each is a
     * synchronisation of every rank: docs/parallel.md, "Collectives a step") */
    int sig = p->mpi ? 0 : (int)stop_signal;
    if (p->mpi && (step >= p->agree_at || step == nsteps)) { /* (the last step too: a late signal) */
        const double t = now_s();
        const double per = p->agree_at > 0 && step > p->last_agreed ? (t - p->agree_t) / (double)(step - p->last_agreed) : 0;
        const double kd = per > 0 ? 0.02 / per : 1;
        const long k = kd < 1 ? 1 : kd > 1024 ? 1024 : (long)kd;
        const int word = floe_parallel_agree(NULL, (int)stop_signal * 2048 + (int)(1024 - k));
        sig = word / 2048;
        p->agree_t = t;
        p->last_agreed = step;
        p->agree_at = step + (1024 - word % 2048);
    }
    if (sig) {
        p->stopped = sig;
        write_checkpoint(p, w); /* collective under MPI */
        return 1;
    }
    if (p->every > 0 && floe_world_time(w) >= p->next && step < nsteps) {
        write_checkpoint(p, w);
        while (p->next <= floe_world_time(w)) p->next += p->every;
    }
    if (!p->show) return 0;
    /* clock_gettime is cheap, but skip it on most steps of large runs anyway */
    if (step != nsteps && (step & 7)) return 0;
    double t = now_s();
    if (t - p->last < 0.25 && step != nsteps) return 0;
    double el = t - p->t0;
    double rate = el > 0 ? (double)step / el : 0;
    char eta[32], elapsed[32];
    fmt_duration(eta, sizeof eta, rate > 0 ? (double)(nsteps - step) / rate : -1);
    fmt_duration(elapsed, sizeof elapsed, el);
    fprintf(stderr, "\r%6.1f%%  step %ld/%ld  %.0f steps/s  elapsed %s  ETA %s   ",
            nsteps > 0 ? 100.0 * (double)step / (double)nsteps : 100.0, step, nsteps, rate, elapsed,
            eta);
    fflush(stderr);
    p->last = t;
    p->last_step = step;
    p->printed = 1;
    return 0;
}

/* the scene's hash for checkpoints: its text (the file's bytes, or the demo's) */
static int scene_hash(const char *scene, uint64_t *h)
{
    *h = FLOE_CHECKPOINT_HASH0;
    if (!scene) {
        *h = floe_checkpoint_hash(*h, floe_scene_default_demo(), strlen(floe_scene_default_demo()));
        return 0;
    }
    FILE *f = fopen(scene, "rb");
    if (!f) return -1;
    unsigned char buf[65536];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0) *h = floe_checkpoint_hash(*h, buf, n);
    fclose(f);
    return 0;
}

typedef struct run_opts {
    const char *outdir;
    int quiet;
    double ckpt_every;      /* > 0: seconds of simulated time between checkpoints */
    const char *ckpt;       /* the checkpoint file (NULL: OUTDIR/checkpoint.bin) */
    const char *restart;    /* continue from this checkpoint */
    int threads;            /* -t N (0: OpenMP's default) */
    int balance;            /* --balance: FLOE_BALANCE_WEIGHTS or _TIME (under mpirun) */
} run_opts;

#ifdef FLOE_HAVE_MPI
/* the scene's vtk outputs of this rank (floe_scene_set_vtk_mode), until the split world takes them */
typedef struct vtk_pieces {
    floe_observer **o;
    int n;
} vtk_pieces;

static int take_piece(void *ctx, floe_observer *obs)
{
    vtk_pieces *vp = ctx;
    floe_observer **no = realloc(vp->o, (size_t)(vp->n + 1) * sizeof *no);
    if (!no) {
        floe_observer_destroy(obs);
        return 1;
    }
    vp->o = no;
    vp->o[vp->n++] = obs;
    return 0;
}

static void free_pieces(vtk_pieces *vp, int from)
{
    for (int k = from; k < vp->n; k++) floe_observer_destroy(vp->o[k]);
    free(vp->o);
    vp->o = NULL;
    vp->n = 0;
}

/* `floe run` under mpirun with more than one rank (docs/parallel.md): every rank loads the
 * scene with only its vtk outputs, as the writers of its pieces, and keeps its subdomain
 * (floe_world_parallel_init), which the pieces then write (floe_world_parallel_add_output);
 * when the scene has other outputs, rank 0 also loads it with them (its vtk outputs left
 * out), an unsplit mirror that writes the gathered state. An error inside the run that every
 * rank returned (floe_world_parallel_error_agreed: a contact too deep, a particle's checks,
 * the watchdog) ends the outputs on every rank and returns 1, as one process does; an error
 * on one rank alone stops all (MPI_Abort): the others would wait for it in a collective. */
static int cmd_run_mpi(const char *scene, const run_opts *o, int rank, int size)
{
    char err[1024];
    floe_scene_info info;
    floe_world *w = NULL, *mirror = NULL;
    vtk_pieces vp = {NULL, 0};
    const char *label = scene ? scene : "<demo>";
    /* checkpoints (docs/parallel.md): the serial file, written by rank 0 from the state gathered
     * into an unsplit world it holds (the mirror), read by every rank at a restart. Always on:
     * a signal (SIGINT, SIGTERM, SIGUSR1) writes one too, so rank 0 holds the mirror and the
     * scene's hash in every run */
    char ckpt_default[1200];
    snprintf(ckpt_default, sizeof ckpt_default, "%s/checkpoint.bin", o->outdir);
    /* from now on a signal is a request to stop (mpirun may forward one while the ranks load
     * and split the scene: the run then stops after its first step, with a checkpoint) */
    install_stop_handlers();
    uint64_t hash = 0;
    int rc = scene_hash(scene, &hash) ? FLOE_EIO : FLOE_OK;
    if (rc != FLOE_OK) snprintf(err, sizeof err, "cannot read %s: %s", scene, strerror(errno));
    const char *text = scene ? NULL : floe_scene_default_demo();
    /* a restart: the outputs keep what the stopped run wrote (the pieces' series are created
     * held; the mirror's load cuts its files back) */
    floe_outputs_keep_existing(o->restart != NULL);
    floe_scene_set_vtk_mode(FLOE_SCENE_VTK_PIECES, rank, size, take_piece, &vp);
    if (rc == FLOE_OK)
        rc = floe_scene_load_ex(scene ? scene : "<demo>", text, o->outdir, FLOE_SCENE_RUN, &w, &info, err, sizeof err);
    /* the other outputs go through rank 0's mirror (the same count on every rank); checkpoints
     * need rank 0's unsplit world even without them */
    const int need_mirror = rc == FLOE_OK && info.nobservers > vp.n;
    floe_scene_set_vtk_mode(FLOE_SCENE_VTK_SKIP, 0, 0, NULL, NULL);
    if (rc == FLOE_OK && rank == 0)
        rc = scene ? floe_scene_load(scene, o->outdir, &mirror, &info, err, sizeof err)
                   : floe_scene_load_string(text, "<demo>", o->outdir, &mirror, &info, err, sizeof err);
    floe_outputs_keep_existing(0);
    floe_scene_set_vtk_mode(FLOE_SCENE_VTK_SERIAL, 0, 0, NULL, NULL);
    int any;
    MPI_Allreduce(&rc, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    if (any != FLOE_OK) {
        if (rc != FLOE_OK) fprintf(stderr, "%s: error (rank %d): %s\n", prog, rank, err);
        free_pieces(&vp, 0);
        floe_world_destroy(w);
        floe_world_destroy(mirror);
        return 1;
    }
    /* a restart: the vtk pieces' series on every rank (their state is in the file, written by
     * rank 0), then rank 0's mirror (its outputs continue), every rank agreeing on each */
    if (o->restart) {
        if (vp.n > 0) {
            rc = floe_world_checkpoint_restore_split_outputs(w, vp.o, vp.n, o->restart, hash, label, err, sizeof err);
            int r0 = rc; /* rank 0 says why; another rank only when it failed alone */
            MPI_Bcast(&r0, 1, MPI_INT, 0, MPI_COMM_WORLD);
            if (rc != FLOE_OK && rank == 0) fprintf(stderr, "%s: error: %s: cannot restart: %s\n", prog, label, err);
            else if (rc != FLOE_OK && r0 == FLOE_OK)
                fprintf(stderr, "%s: error (rank %d): %s: cannot restart: %s\n", prog, rank, label, err);
        }
        if (floe_parallel_agree(NULL, rc) != FLOE_OK) {
            free_pieces(&vp, 0);
            floe_world_destroy(w);
            floe_world_destroy(mirror);
            return 1;
        }
        if (rank == 0) {
            rc = floe_world_checkpoint_load(mirror, o->restart, hash, label, err, sizeof err);
            if (rc != FLOE_OK) fprintf(stderr, "%s: error: %s: cannot restart: %s\n", prog, label, err);
        }
        if (floe_parallel_agree(NULL, rc) != FLOE_OK) {
            free_pieces(&vp, 0);
            floe_world_destroy(w);
            floe_world_destroy(mirror);
            return 1;
        }
    }
    /* threads per rank: -t N, else OMP_NUM_THREADS, else one (ranks usually fill the cores) */
    rc = floe_world_set_threads(w, o->threads > 0 ? o->threads : getenv("OMP_NUM_THREADS") ? 0 : 1);
    if (o->restart) {
        /* every rank reads the file into its (whole) world and the ranks agree before the
         * split: a rank that failed alone leaves none waiting; rank 0 (or, when rank 0 read
         * it, the rank that failed) says why */
        int mine = rc;
        if (rc == FLOE_OK) mine = rc = floe_world_checkpoint_load_state(w, o->restart, hash, label, err, sizeof err);
        else snprintf(err, sizeof err, "%s", floe_world_last_error(w));
        int r0 = mine;
        MPI_Bcast(&r0, 1, MPI_INT, 0, MPI_COMM_WORLD);
        if (floe_parallel_agree(NULL, mine) != FLOE_OK) {
            if (mine != FLOE_OK && rank == 0)
                fprintf(stderr, "%s: error: %s: cannot restart: %s\n", prog, label, err);
            else if (mine != FLOE_OK && r0 == FLOE_OK)
                fprintf(stderr, "%s: error (rank %d): %s: cannot restart: %s\n", prog, rank, label, err);
            else if (rank == 0)
                fprintf(stderr, "%s: error: %s: cannot restart: another rank could not read %s\n", prog, label, o->restart);
            free_pieces(&vp, 0);
            floe_world_destroy(w);
            floe_world_destroy(mirror);
            return 1;
        }
    } else if (rc == FLOE_OK) {
        rc = floe_world_prepare(w);
    }
    if (rc == FLOE_OK) rc = floe_world_parallel_init(w, NULL);
    if (rc == FLOE_OK) rc = floe_world_parallel_set_balance(w, (floe_balance)o->balance);
    /* rank 0's mirror: a failed prepare is reported here and refused by every rank below */
    if (rc == FLOE_OK && mirror && !o->restart && floe_world_prepare(mirror) != FLOE_OK)
        fprintf(stderr, "%s: error: %s: %s\n", prog, label, floe_world_last_error(mirror));
    /* the mirror writes the outputs only when the scene has some besides vtk */
    if (rc == FLOE_OK) rc = floe_world_parallel_outputs(w, need_mirror ? mirror : NULL);
    /* the vtk pieces: the split world takes them (and writes the state at the split) */
    int taken = 0;
    const int npieces = vp.n;
    while (rc == FLOE_OK && taken < vp.n) rc = floe_world_parallel_add_output(w, vp.o[taken++]);
    free_pieces(&vp, rc == FLOE_OK ? vp.n : taken);
    if (rc != FLOE_OK) { /* the same on every rank: the checks are collective */
        if (rank == 0) fprintf(stderr, "%s: error: %s: %s\n", prog, label, floe_world_last_error(w));
        floe_world_destroy(w);
        floe_world_destroy(mirror);
        return 1;
    }
    progress pr = {0};
    pr.mpi = 1;
    pr.loud = rank == 0;
    pr.full = rank == 0 ? mirror : NULL;
    pr.ckpt = o->ckpt ? o->ckpt : ckpt_default;
    pr.hash = hash;
    pr.scene = label;
    pr.every = o->ckpt_every;
    if (pr.every > 0) pr.next = (floor(floe_world_time(w) / pr.every + 1e-9) + 1) * pr.every;
    if (rank == 0 && !o->quiet) {
        printf("%s", info.summary);
        printf("output:     %s\n", o->outdir);
        printf("mpi:        %d ranks (recursive coordinate bisection, %s)\n", size,
               o->balance == FLOE_BALANCE_TIME ? "shares by measured speed" : "equal shares of the estimated work");
        if (o->restart)
            printf("restart:    %s at t = %g s, step %ld\n", o->restart, floe_world_time(w), floe_world_step_count(w));
        if (pr.every > 0) printf("checkpoint: %s every %g s (written by rank 0)\n", pr.ckpt, pr.every);
        fflush(stdout);
    }
    floe_world_parallel_comm_reset(w); /* the run's traffic, the split's left out */
    pr.show = rank == 0 && !o->quiet && isatty(STDERR_FILENO);
    pr.t0 = pr.last = now_s();
    long step0 = floe_world_step_count(w);
    rc = floe_world_run(w, info.duration, on_progress, &pr);
    double wall = now_s() - pr.t0;
    if (pr.printed) fprintf(stderr, "\r%*s\r", 100, "");
    if (rc != FLOE_OK && !(pr.stopped && rc == FLOE_ESTOP)) {
        const int agreed = floe_world_parallel_error_agreed(w);
        if (!agreed) { /* this rank alone: the others may wait in a collective */
            fprintf(stderr, "%s: error (rank %d): %s: %s (t = %g s, step %ld)\n", prog, rank, label,
                    floe_world_last_error(w), floe_world_time(w), floe_world_step_count(w));
            MPI_Abort(MPI_COMM_WORLD, 1);
        }
        /* every rank returned it: the outputs end together, as in one process (floe_world_run
         * wrote the state at the failure), unless the split state is not whole (agreed 2: out of
         * memory, a failed decomposition) and is not written */
        char msg[1024];
        snprintf(msg, sizeof msg, "%s", floe_world_last_error(w));
        const int frc = agreed == 1 ? floe_world_parallel_finish(w) : FLOE_OK;
        if (agreed != 1 && rank == 0)
            fprintf(stderr, "%s: %s: the outputs were not ended (the split state is not whole)\n", prog, label);
        if (rank == 0) {
            fprintf(stderr, "%s: error: %s: %s (t = %g s, step %ld)\n", prog, label, msg, floe_world_time(w),
                    floe_world_step_count(w));
            if (frc != FLOE_OK) fprintf(stderr, "%s: error: %s: %s\n", prog, label, floe_world_last_error(w));
            fprintf(stderr, "%s: outputs written so far are in %s\n", prog, o->outdir);
        }
        floe_world_destroy(w);
        floe_world_destroy(mirror);
        return 1;
    }
    rc = floe_world_parallel_finish(w);
    if (pr.stopped && rc == FLOE_OK) { /* every rank stopped at the same step: outputs closed */
        if (rank == 0) {
            fprintf(stderr, "%s: %s: stopped by %s at t = %g s, step %ld\n", prog, label, signal_name(pr.stopped),
                    floe_world_time(w), floe_world_step_count(w));
            fprintf(stderr, "%s: outputs written so far are complete and in %s\n", prog, o->outdir);
            if (!pr.failed)
                fprintf(stderr, "%s: checkpoint written to %s; continue with: mpirun -np N %s run %s -o %s --restart %s\n",
                        prog, pr.ckpt, prog, scene ? scene : "", o->outdir, pr.ckpt);
        }
        floe_world_destroy(w);
        floe_world_destroy(mirror);
        return 128 + pr.stopped;
    }
    if (rc != FLOE_OK) {
        if (rank == 0) fprintf(stderr, "%s: error: %s: %s\n", prog, label, floe_world_last_error(w));
        floe_world_destroy(w);
        floe_world_destroy(mirror);
        return 1;
    }
    floe_energy e;
    floe_world_parallel_energy(w, &e);
    int own, gh;
    floe_world_parallel_counts(w, &own, &gh);
    double red[3] = {floe_world_contact_count(w), own, gh};
    floe_world_parallel_sum(w, red, 3);
    /* the traffic per step and rank (floe_comm_stats): the mean and the largest over the ranks,
     * by kind, and the mean loads */
    floe_comm_stats cs;
    floe_world_parallel_comm(w, &cs);
    const double st = cs.steps > 0 ? (double)cs.steps : 1.0;
    double mine[FLOE_COMM_KINDS + 5], sum[FLOE_COMM_KINDS + 5], mx = 0;
    double ft[2] = {cs.force_seconds, -cs.force_seconds}, ftx[2] = {0, 0}, ftsum = 0;
    mine[FLOE_COMM_KINDS] = 0;
    mine[FLOE_COMM_KINDS + 1] = 0;
    for (int k = 0; k < FLOE_COMM_KINDS; k++) {
        mine[k] = (double)cs.bytes[k] / st;
        mine[FLOE_COMM_KINDS] += mine[k];
        mine[FLOE_COMM_KINDS + 1] += (double)cs.messages[k] / st;
    }
    mine[FLOE_COMM_KINDS + 2] = cs.ghost_steps / st;
    mine[FLOE_COMM_KINDS + 3] = cs.owned_steps / st;
    mine[FLOE_COMM_KINDS + 4] = cs.refreshed_steps / st;
    MPI_Reduce(mine, sum, FLOE_COMM_KINDS + 5, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
    MPI_Reduce(mine + FLOE_COMM_KINDS, &mx, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
    /* the ranks' own work: their seconds in force evaluations, largest, smallest and mean */
    MPI_Reduce(ft, ftx, 2, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
    MPI_Reduce(ft, &ftsum, 1, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
    if (rank == 0 && !o->quiet) {
        long steps = floe_world_step_count(w) - step0;
        const double cur = e.kinetic_trans + e.kinetic_rot + e.elastic;
        const double scale = fmax(fabs(e.initial) + fabs(e.work_body) + fabs(e.work_boundary), 1e-300);
        printf("\nrun finished\n");
        printf("  steps:              %ld (dt %.4g s, %s)\n", steps, floe_world_dt(w),
               floe_integrator_name(floe_world_definition(w)->integrator));
        printf("  simulated time:     %.6g s\n", floe_world_time(w));
        printf("  wall time:          %.3f s\n", wall);
        printf("  particle-steps/s:   %.3g (%d particles, %d ranks)\n",
               wall > 0 ? red[1] * (double)steps / wall : 0, (int)red[1], size);
        printf("  ghosts (all ranks): %d\n", (int)red[2]);
        printf("  comm/step/rank:     %.0f B mean, %.0f B max, %.2f messages (ghost %.0f, reverse %.0f, migrate %.0f, "
               "reduce %.0f, output %.0f B); ghosts/rank %.1f, particles/rank %.1f; %ld rebuilds; "
               "refreshed ghosts/rank %.1f\n",
               sum[FLOE_COMM_KINDS] / size, mx, sum[FLOE_COMM_KINDS + 1] / size, sum[FLOE_COMM_GHOST] / size,
               sum[FLOE_COMM_REVERSE] / size, sum[FLOE_COMM_MIGRATE] / size, sum[FLOE_COMM_REDUCE] / size,
               sum[FLOE_COMM_OUTPUT] / size, sum[FLOE_COMM_KINDS + 2] / size, sum[FLOE_COMM_KINDS + 3] / size,
               cs.rebuilds, sum[FLOE_COMM_KINDS + 4] / size);
        printf("  force time/rank:    %.3f s mean, %.3f s max, %.3f s min (max/mean %.3f: the load imbalance)\n",
               ftsum / size, ftx[0], -ftx[1], ftsum > 0 ? ftx[0] * size / ftsum : 1.0);
        printf("  contacts (current): %d\n", (int)red[0]);
        printf("  energy balance err: %.3g (relative)\n",
               (cur + e.dissipated - e.initial - e.work_body - e.work_boundary) / scale);
        if (pr.written) printf("  checkpoints:        %d written, the last in %s\n", pr.written, pr.ckpt);
        printf("  outputs in:         %s (%s)\n", o->outdir,
               !npieces ? "written by rank 0"
               : need_mirror ? "vtk: a piece per rank and a .pvtu; the others written by rank 0"
                        : "vtk: a piece per rank and a .pvtu");
    }
    floe_world_destroy(w);
    floe_world_destroy(mirror);
    return 0;
}
#endif

static int cmd_run(const char *scene, const run_opts *o)
{
#ifdef FLOE_HAVE_MPI
    int mpi_on = 0;
    MPI_Initialized(&mpi_on);
    if (mpi_on) {
        int rank, size;
        MPI_Comm_rank(MPI_COMM_WORLD, &rank);
        MPI_Comm_size(MPI_COMM_WORLD, &size);
        if (size > 1) return cmd_run_mpi(scene, o, rank, size);
    }
#endif
    char err[1024];
    floe_scene_info info;
    floe_world *w = NULL;
    const char *label = scene ? scene : "<demo>", *outdir = o->outdir;
    const int quiet = o->quiet;
    char ckpt_default[1200];
    snprintf(ckpt_default, sizeof ckpt_default, "%s/checkpoint.bin", outdir);
    progress pr = {0};
    pr.loud = 1;
    pr.ckpt = o->ckpt ? o->ckpt : ckpt_default;
    pr.scene = label;
    pr.every = o->ckpt_every;
    if (scene_hash(scene, &pr.hash)) {
        fprintf(stderr, "%s: error: cannot read %s: %s\n", prog, scene, strerror(errno));
        return 1;
    }
    /* a restart: the outputs keep what the stopped run wrote (the load cuts them back to
     * the checkpoint) */
    floe_outputs_keep_existing(o->restart != NULL);
    int rc = scene ? floe_scene_load(scene, outdir, &w, &info, err, sizeof err)
                   : floe_scene_load_string(floe_scene_default_demo(), "<demo>", outdir, &w, &info,
                                            err, sizeof err);
    floe_outputs_keep_existing(0);
    if (rc != FLOE_OK) {
        fprintf(stderr, "%s: error: %s\n", prog, err);
        return 1;
    }
    if (o->threads > 0 && (rc = floe_world_set_threads(w, o->threads)) != FLOE_OK) {
        fprintf(stderr, "%s: error: %s\n", prog, floe_world_last_error(w));
        floe_world_destroy(w);
        return 1;
    }
    if (o->restart) {
        rc = floe_world_checkpoint_load(w, o->restart, pr.hash, label, err, sizeof err);
        if (rc != FLOE_OK) {
            fprintf(stderr, "%s: error: %s: cannot restart: %s\n", prog, label, err);
            floe_world_destroy(w);
            return 1;
        }
    }
    if (pr.every > 0) pr.next = (floor(floe_world_time(w) / pr.every + 1e-9) + 1) * pr.every;
    if (!quiet) {
        printf("%s", info.summary);
        printf("output:     %s\n", outdir);
        if (floe_world_threads(w) > 1) printf("threads:    %d (OpenMP)\n", floe_world_threads(w));
        if (o->restart)
            printf("restart:    %s at t = %g s, step %ld\n", o->restart, floe_world_time(w), floe_world_step_count(w));
        if (pr.every > 0) printf("checkpoint: %s every %g s\n", pr.ckpt, pr.every);
        fflush(stdout);
    }
    pr.show = !quiet && isatty(STDERR_FILENO);
    long step0 = floe_world_step_count(w);
    double t_start = now_s();
    pr.t0 = pr.last = t_start;
    install_stop_handlers();
    rc = floe_world_run(w, info.duration, on_progress, &pr);
    double wall = now_s() - t_start;
    if (pr.printed) fprintf(stderr, "\r%*s\r", 100, "");
    long steps = floe_world_step_count(w) - step0;
    if (stop_signal && rc != FLOE_OK) { /* a signal after the last step: the run is complete */
        int sig = (int)stop_signal;
        fprintf(stderr, "%s: %s: stopped by %s at t = %g s, step %ld%s%s\n", prog, label,
                signal_name(sig), floe_world_time(w), floe_world_step_count(w),
                rc != FLOE_OK && rc != FLOE_ESTOP ? ": " : "",
                rc != FLOE_OK && rc != FLOE_ESTOP ? floe_world_last_error(w) : "");
        fprintf(stderr, "%s: outputs written so far are complete and in %s\n", prog, outdir);
        if (!pr.failed)
            fprintf(stderr, "%s: checkpoint written to %s; continue with: %s run %s -o %s --restart %s\n", prog,
                    pr.ckpt, prog, scene ? scene : "", outdir, pr.ckpt);
        floe_world_destroy(w);
        return 128 + sig;
    }
    if (rc != FLOE_OK) {
        fprintf(stderr, "%s: error: %s: %s (t = %g s, step %ld)\n", prog, label,
                floe_world_last_error(w), floe_world_time(w), floe_world_step_count(w));
        fprintf(stderr, "%s: outputs written so far are in %s\n", prog, outdir);
        floe_world_destroy(w);
        return 1;
    }
    {
        floe_detect_stats ds;
        floe_world_detect_stats(w, &ds);
        if (ds.nonconverged > 0) /* a counted warning, also with -q */
            fprintf(stderr,
                    "%s: warning: ADMM contact detection stopped at max_iterations in %ld of %ld evaluations "
                    "(first: particles %d and %d at step %ld); raise contact_detection.max_iterations or "
                    "the tolerance\n",
                    prog, ds.nonconverged, ds.admm, ds.first_bad_i, ds.first_bad_j, ds.first_bad_step);
    }
    if (!quiet) {
        int n = info.nparticles;
        double ps = wall > 0 ? (double)n * (double)steps / wall : 0;
        printf("\nrun finished\n");
        floe_step_stats st;
        floe_world_step_stats(w, &st);
        const floe_world_def *def = floe_world_definition(w);
        if (def->adaptive)
            printf("  steps:              %ld accepted, %ld rejected (dt %.4g ... %.4g s)\n", st.accepted,
                   st.rejected, st.dt_min_used, st.dt_max_used);
        else printf("  steps:              %ld (dt %.4g s, %s)\n", steps, floe_world_dt(w),
                    floe_integrator_name(def->integrator));
        if (def->pd_dem == FLOE_PD_DEM_STAGGERED && floe_world_pd_body_count(w) > 0)
            printf("  staggered PD-DEM:   %ld contact and %ld PD force evaluations (PD %s %d)\n",
                   st.force_evaluations, st.pd_evaluations, st.pd_every > 1 ? "every" : "substeps",
                   st.pd_every > 1 ? st.pd_every : st.pd_substeps);
        printf("  simulated time:     %.6g s\n", floe_world_time(w));
        printf("  wall time:          %.3f s\n", wall);
        printf("  particle-steps/s:   %.3g (%d particles)\n", ps, n);
        floe_neighbor_stats ns;
        floe_world_neighbor_stats(w, &ns);
        printf("  contacts (current): %d\n", floe_world_contact_count(w));
        printf("  neighbour rebuilds: %ld\n", ns.rebuilds);
        floe_detect_stats ds;
        floe_world_detect_stats(w, &ds);
        if (ds.evaluations > 0)
            printf("  convex detection:   %ld pair evaluations (%ld LP, %ld ADMM), iterations median %d, "
                   "99th percentile %d%s\n",
                   ds.evaluations, ds.lp, ds.admm, ds.iterations_median, ds.iterations_p99,
                   ds.iterations_p99 >= FLOE_DETECT_HIST - 1 ? "+" : "");
        printf("  energy balance err: %.3g (relative)\n", floe_world_energy_balance_error(w));
        floe_dt_estimates dte;
        if (floe_world_dt_estimates(w, &dte) == FLOE_OK && (dte.err1 > 0 || dte.err2 > 0))
            printf("  restitution error:  %.2g predicted at dt %.4g s%s\n", dte.predicted_error, floe_world_dt(w),
                   def->accuracy > 0 ? " (time.accuracy)" : "");
        floe_energy_check_state ec;
        floe_world_energy_check(w, &ec);
        if (ec.mode == FLOE_CHECK_OFF) printf("  energy watchdog:    off\n");
        else printf("  energy watchdog:    %s (tolerance %.3g of the energy scale), largest creation %.2g%s\n",
                    floe_energy_check_name(ec.mode), ec.tolerance, ec.created,
                    ec.tripped_step >= 0 ? ", TRIPPED (warning above)" : "");
        if (pr.written) printf("  checkpoints:        %d written, the last in %s\n", pr.written, pr.ckpt);
        printf("  outputs in:         %s\n", outdir);
    }
    floe_world_destroy(w);
    return 0;
}

/* every critical time-step estimate, and which one limits (docs/models.md) */
static void print_dt_estimates(floe_world *w)
{
    static const char *const what[FLOE_DT_NKINDS] = {
        "caged particle, spring-dashpot limit (Gershgorin)", "one contact, impact at the expected speed",
        "no move over half a radius per step", "PD nodal sqrt(2 rho / sum V c/|xi|)", "PD CFL dx / c (000 eqs 41-42)",
        "sqrt(m/k) (000 eq 43; 004 eq 28 is 2x)", "Rayleigh wave (Hertz materials)",
        "Hertz contact duration at the expected speed", "beam bonds, largest eigenvalue bound",
        "force providers' own limit (critical_dt)"};
    floe_dt_estimates e;
    if (floe_world_dt_estimates(w, &e) != FLOE_OK) return;
    printf("time-step estimates (expected relative speed %.3g m/s):\n", e.v_expected);
    for (int k = 0; k < FLOE_DT_NKINDS; k++) {
        if (!isfinite(e.dt[k])) continue;
        printf("  %-16s %10.4g s  particle %-7d %-9s %s%s\n", floe_dt_kind_name(k), e.dt[k], e.particle[k],
               e.limits[k] ? "limit" : "reference", what[k], k == e.limiting ? "  <- limits" : "");
    }
    if (e.limiting < 0) printf("  (none applies: no contact law or PD body limits the step)\n");
}

static int cmd_check(const char *scene)
{
    char err[1024];
    floe_scene_info info;
    floe_world *w = NULL;
    int rc = floe_scene_load_ex(scene, NULL, NULL, 0, &w, &info, err, sizeof err);
    if (rc != FLOE_OK) {
        fprintf(stderr, "%s: error: %s\n", prog, err);
        return 1;
    }
    printf("%s", info.summary);
    print_dt_estimates(w);
    printf("ok: %s\n", scene);
    floe_world_destroy(w);
    return 0;
}

static int cmd_info(void)
{
    printf("floe %s - particle mechanics (DEM)\n", FLOE_VERSION_STRING);
#if defined(FLOE_BUILD_TYPE)
    printf("build type:  %s\n", FLOE_BUILD_TYPE);
#else
    printf("build type:  %s%s\n",
#if defined(__OPTIMIZE__)
           "optimised",
#else
           "not optimised (debug)",
#endif
#if defined(NDEBUG)
           ", assertions off"
#else
           ", assertions on"
#endif
    );
#endif
#if defined(__VERSION__)
    printf("compiler:    %s\n", __VERSION__);
#endif
    int feat = floe_mesh_features();
    char omp[64] = "no";
#ifdef _OPENMP
    snprintf(omp, sizeof omp, "yes (%d threads by default)", omp_get_max_threads());
#endif
    printf("features:    CGAL: %s, assimp: %s, CHOLMOD (implicit Newmark): %s, OpenMP: %s\n",
           feat & FLOE_MESH_HAVE_CGAL ? "yes" : "no", feat & FLOE_MESH_HAVE_ASSIMP ? "yes" : "no",
           floe_newmark_implicit_available() ? "yes" : "no", omp);
    char err[512];
    if (floe_register_builtins(err, sizeof err) != FLOE_OK) {
        fprintf(stderr, "%s: error: %s\n", prog, err);
        return 1;
    }
    for (int q = 0; q < floe_help_kind_count(); q++) {
        const char *kind = floe_help_kind(q);
        char label[32];
        snprintf(label, sizeof label, "%s:", kind);
        printf("%-13s", label);
        for (int k = 0; k < floe_registry_count(kind); k++) {
            const floe_registry_entry *e = floe_registry_at(kind, k);
            printf("%s%s%s", k ? ", " : " ", e->name, strcmp(e->origin, FLOE_ORIGIN_BUILTIN) ? " (plugin)" : "");
        }
        printf("\n");
    }
    printf("also:         plane (walls), user SDF callback (C API)\n");
    for (int k = 0; k < floe_plugin_count(); k++) printf("plugin:       %s\n", floe_plugin_path(k));
    printf("help:         floe help KIND [NAME] (kinds:");
    for (int q = 0; q < floe_help_kind_count(); q++) printf("%s%s", q ? ", " : " ", floe_help_kind(q));
    printf(")\n");
    return 0;
}

static int cli_main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    /* --plugin F (anywhere, repeatable): load before the command, then drop from argv */
    {
        int o = 1;
        for (int i = 1; i < argc; i++) {
            const char *a = argv[i], *file = NULL;
            if (!strcmp(a, "--plugin")) {
                if (i + 1 >= argc) {
                    fprintf(stderr, "%s: --plugin needs a shared-library path\n", prog);
                    return 2;
                }
                file = argv[++i];
            } else if (!strncmp(a, "--plugin=", 9)) {
                file = a + 9;
            }
            if (!file) {
                argv[o++] = argv[i];
                continue;
            }
            char path[1024], err[1024];
            snprintf(path, sizeof path, "%s%s", strchr(file, '/') ? "" : "./", file);
            if (floe_plugin_load(path, err, sizeof err) != FLOE_OK) {
                fprintf(stderr, "%s: error: %s\n", prog, err);
                return 1;
            }
        }
        argc = o;
        argv[argc] = NULL;
    }
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    const char *cmd = argv[1];
    if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || (!strcmp(cmd, "help") && argc == 2)) {
        usage(stdout);
        return 0;
    }
    if (!strcmp(cmd, "help")) {
        char err[512];
        int md = argc == 3 && !strcmp(argv[2], "--markdown");
        if (!md && (argc > 4 || argv[2][0] == '-')) {
            fprintf(stderr, "%s: help takes KIND [NAME], or --markdown\n", prog);
            usage(stderr);
            return 2;
        }
        int rc = floe_reference_write(stdout, md ? NULL : argv[2], !md && argc == 4 ? argv[3] : NULL, md, err,
                                      sizeof err);
        if (rc != FLOE_OK) {
            fprintf(stderr, "%s: %s\n", prog, err);
            return 2;
        }
        return 0;
    }
    if (!strcmp(cmd, "--version")) {
        printf("floe %s\n", FLOE_VERSION_STRING);
        return 0;
    }
    if (!strcmp(cmd, "info")) {
        if (argc != 2) {
            fprintf(stderr, "%s: info takes no arguments\n", prog);
            usage(stderr);
            return 2;
        }
        return cmd_info();
    }
    if (!strcmp(cmd, "check")) {
        if (argc != 3 || argv[2][0] == '-') {
            if (argc == 3 && (!strcmp(argv[2], "-h") || !strcmp(argv[2], "--help"))) {
                usage(stdout);
                return 0;
            }
            fprintf(stderr, "%s: check needs exactly one SCENE\n", prog);
            usage(stderr);
            return 2;
        }
        return cmd_check(argv[2]);
    }
    if (!strcmp(cmd, "run")) {
        const char *scene = NULL, *outdir = "out";
        int quiet = 0;
        run_opts ro = {0};
        for (int i = 2; i < argc; i++) {
            const char *a = argv[i];
            if (!strcmp(a, "--checkpoint-every") || !strcmp(a, "--checkpoint") || !strcmp(a, "--restart")) {
                if (i + 1 >= argc) {
                    fprintf(stderr, "%s: %s needs %s\n", prog, a,
                            strcmp(a, "--checkpoint-every") ? "a file" : "seconds of simulated time");
                    usage(stderr);
                    return 2;
                }
                const char *v = argv[++i];
                if (!strcmp(a, "--checkpoint")) ro.ckpt = v;
                else if (!strcmp(a, "--restart")) ro.restart = v;
                else {
                    char *end = NULL;
                    ro.ckpt_every = strtod(v, &end);
                    if (!end || *end || !(ro.ckpt_every > 0) || !isfinite(ro.ckpt_every)) {
                        fprintf(stderr, "%s: --checkpoint-every takes seconds of simulated time > 0 (got '%s')\n",
                                prog, v);
                        return 2;
                    }
                }
            } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
                if (i + 1 >= argc) {
                    fprintf(stderr, "%s: %s needs a directory\n", prog, a);
                    usage(stderr);
                    return 2;
                }
                outdir = argv[++i];
            } else if (!strncmp(a, "-o", 2) && a[2]) {
                outdir = a + 2;
            } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
                quiet = 1;
            } else if (!strcmp(a, "-t") || !strcmp(a, "--threads")) {
                char *end = NULL;
                long v = i + 1 < argc ? strtol(argv[i + 1], &end, 10) : 0;
                if (i + 1 >= argc || !end || *end || v < 1 || v > 4096) {
                    fprintf(stderr, "%s: %s takes a number of threads >= 1 (got '%s')\n", prog, a,
                            i + 1 < argc ? argv[i + 1] : "");
                    return 2;
                }
                ro.threads = (int)v;
                i++;
            } else if (!strcmp(a, "--balance")) {
                const char *v = i + 1 < argc ? argv[i + 1] : "";
                if (strcmp(v, "weights") && strcmp(v, "time")) {
                    fprintf(stderr, "%s: --balance takes 'weights' or 'time' (got '%s')\n", prog, v);
                    return 2;
                }
                ro.balance = !strcmp(v, "time") ? FLOE_BALANCE_TIME : FLOE_BALANCE_WEIGHTS;
                i++;
            } else if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
                usage(stdout);
                return 0;
            } else if (a[0] == '-' && a[1]) {
                fprintf(stderr, "%s: unknown option '%s'\n", prog, a);
                usage(stderr);
                return 2;
            } else if (!scene) {
                scene = a;
            } else {
                fprintf(stderr, "%s: run takes one SCENE (got '%s' and '%s')\n", prog, scene, a);
                usage(stderr);
                return 2;
            }
        }
        if (!outdir[0]) {
            fprintf(stderr, "%s: empty output directory\n", prog);
            return 2;
        }
        ro.outdir = outdir;
        ro.quiet = quiet;
        return cmd_run(scene, &ro);
    }
    fprintf(stderr, "%s: unknown command '%s'\n", prog, cmd);
    usage(stderr);
    return 2;
}

/* built with MPI (FLOE_WITH_MPI): MPI is started when a launcher started this process
 * (mpirun, mpiexec, srun: their environment), so that a plain `floe` stays the serial
 * program, without MPI's start-up time and memory; `floe run` with several ranks splits the
 * world (cmd_run_mpi) */
int main(int argc, char **argv)
{
#ifdef FLOE_HAVE_MPI
    if (getenv("OMPI_COMM_WORLD_SIZE") || getenv("PMI_SIZE") || getenv("PMIX_RANK")) {
        MPI_Init(&argc, &argv);
        int rc = cli_main(argc, argv);
        MPI_Finalize();
        return rc;
    }
#endif
    return cli_main(argc, argv);
}
