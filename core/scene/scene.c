/* scene.c - YAML scene files -> a prepared floe_world (format: docs/scene-format.md).
 *
 * Parsed with libfyaml's document API. Every mapping is checked against the keys valid at
 * that place (unknown keys name the closest valid one by edit distance); every value is
 * type-checked and range-checked, and every message is "file:line:column: message" with
 * 1-based line and column. Packings (lattice, hexagonal, random) are expanded here; the
 * world does the physics. ParticLS §5.2 (growing radius) and §5.3 (RVE) are the examples. */
#include "scene_read.h"
#include "floe_cell.h"
#include "floe_integrator.h"

/* ------------------------------------------------------------------------------------ */
/* Summary                                                                               */

typedef struct sc_buf { char *p; size_t len, n; } sc_buf;

static void sc_cat(sc_buf *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static void sc_cat(sc_buf *b, const char *fmt, ...)
{
    if (b->n + 1 >= b->len) return;
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(b->p + b->n, b->len - b->n, fmt, ap);
    va_end(ap);
    if (k < 0) return;
    b->n += (size_t)k;
    if (b->n >= b->len) {
        b->n = b->len - 1;
        if (b->len > 5) memcpy(b->p + b->len - 5, "...\n", 5);
    }
}

/* "key value unit, ..." of a component's parameters (given ones and defaults) */
static void sc_params_text(char *buf, size_t len, const floe_registry_entry *ent, const void *params)
{
    size_t k = 0;
    buf[0] = 0;
    for (int q = 0; q < ent->nparams && k < len; q++) {
        const floe_param *p = &ent->params[q];
        const char *at = (const char *)params + p->offset;
        if ((p->flags & FLOE_PARAM_REQUIRED) == 0 && !floe_params_given(ent, params, p->key) &&
            p->type != FLOE_PARAM_REAL)
            continue; /* defaults of flags and names are not news */
        if (!floe_params_given(ent, params, p->key) && p->type == FLOE_PARAM_REAL && p->def == 0) continue;
        const char *sep = k ? ", " : "", *u = p->unit && p->unit[0] ? " " : "", *un = p->unit ? p->unit : "";
        int iv;
        double x, v3[3];
        switch (p->type) {
        case FLOE_PARAM_REAL:
            memcpy(&x, at, sizeof x);
            k += (size_t)snprintf(buf + k, len - k, "%s%s %g%s%s", sep, p->key, x, u, un);
            break;
        case FLOE_PARAM_VEC3:
            memcpy(v3, at, sizeof v3);
            k += (size_t)snprintf(buf + k, len - k, "%s%s [%g, %g, %g]%s%s", sep, p->key, v3[0], v3[1], v3[2], u, un);
            break;
        case FLOE_PARAM_STRING:
            k += (size_t)snprintf(buf + k, len - k, "%s%s %s", sep, p->key, at);
            break;
        default:
            memcpy(&iv, at, sizeof iv);
            if (p->type == FLOE_PARAM_BOOL) k += (size_t)snprintf(buf + k, len - k, "%s%s %s", sep, p->key, iv ? "true" : "false");
            else k += (size_t)snprintf(buf + k, len - k, "%s%s %d%s%s", sep, p->key, iv, u, un);
        }
    }
}

static void sc_summary(sc *s, const char *name, const char *outdir, int with_outputs,
                       floe_scene_info *info)
{
    sc_buf b = {info->summary, sizeof info->summary, 0};
    info->summary[0] = '\0';
    floe_world *w = s->w;
    if (name[0]) sc_cat(&b, "scene:      %s (%s)\n", name, s->path);
    else sc_cat(&b, "scene:      %s\n", s->path);
    sc_cat(&b, "dimension:  %d%s\n", s->dim,
           s->dim == 2 ? (w->def.mass_2d_area ? " (motion in x-y; masses from area, per metre)"
                                               : " (motion in x-y; masses of the 3D shapes)")
                       : "");
    sc_cat(&b, "particles:  %d (%d spheres, %d other shapes) in %d body entr%s; walls: %d\n",
           s->nparticles, s->nspheres, s->nboxes, s->nbody_entries,
           s->nbody_entries == 1 ? "y" : "ies", s->nwalls);
    for (int e = 0; e < s->nbody_entries && e < 12; e++)
        sc_cat(&b, "  body %d: particles %d..%d\n", e, s->entry_first[e],
               s->entry_first[e] + s->entry_count[e] - 1);
    if (s->nbody_entries > 12) sc_cat(&b, "  ... %d more body entries\n", s->nbody_entries - 12);
    for (int k = 0; k < floe_world_pd_body_count(w); k++) {
        int f0;
        const floe_pd_body *pb = floe_world_pd_body(w, k, &f0);
        sc_cat(&b, "  peridynamics %d: particles %d..%d (body %d in outputs), %s, %lld bonds (%.1f per point), "
               "horizon %g m, critical stretch %g, nodal dt %.3g s\n",
               k, f0, f0 + pb->n - 1, -2 - k, pb->ops->name, (long long)pb->nbond, 2.0 * (double)pb->nbond / pb->n,
               pb->delta, pb->s_c, floe_pd_dt_nodal(pb));
        if (pb->ncut > 0) sc_cat(&b, "    cracks cut %lld bonds\n", (long long)pb->ncut);
        if (pb->nbridge > 0)
            sc_cat(&b, "    WARNING: %lld bonds bridge a removed region (region.remove narrower than the horizon "
                   "%g m, e.g. at (%g, %g, %g)): it does not separate the material; cut them with cracks\n",
                   (long long)pb->nbridge, pb->delta, pb->bridge_at[0], pb->bridge_at[1], pb->bridge_at[2]);
    }
    for (int q = 0; q < w->npd_bc; q++) { /* PD boundary regions */
        static const char *const kinds[] = {"?", "fixed", "velocity", "displacement", "body force"};
        static const char *const ramps[] = {"", ", linear ramp", ", exponential ramp"};
        const floe_pd_bc_rec *r = w->pd_bc[q];
        int k = r->def.kind >= 1 && r->def.kind <= 4 ? r->def.kind : 0;
        int rp = r->def.ramp >= 0 && r->def.ramp <= 2 ? r->def.ramp : 0;
        sc_cat(&b, "  boundary %d: peridynamics %d, %d points, %s", q, r->body, r->n, kinds[k]);
        if (k >= 2 && !r->def.force_fn)
            sc_cat(&b, " (%g, %g, %g)", r->def.value[0], r->def.value[1], r->def.value[2]);
        if (k == 4 && r->def.force_fn) sc_cat(&b, " (callback)");
        if (k >= 2) sc_cat(&b, "%s", ramps[rp]);
        if (rp) sc_cat(&b, " over %g s", r->def.ramp_time);
        sc_cat(&b, "\n");
    }
    if (floe_world_beam_bond_count(w) > 0)
        sc_cat(&b, "  beam bonds: %d (%d broken), critical dt %.3g s\n", floe_world_beam_bond_count(w),
               floe_world_beam_broken_count(w), floe_world_beam_critical_dt(w));
    sc_cat(&b, "materials:\n");
    for (int i = 0; i < s->nmats && i < 16; i++) {
        const floe_material *m = &s->mats[i].m;
        if (s->mats[i].has_young)
            sc_cat(&b, "  %s: density %g kg/m^3, E %g Pa, nu %g\n", m->name, m->density, m->young,
                   m->poisson);
        else
            sc_cat(&b, "  %s: density %g kg/m^3\n", m->name, m->density);
    }
    sc_cat(&b, "laws:\n");
    for (int i = 0; i < s->nlaws && i < 32; i++) {
        const sc_law *L = &s->laws[i];
        char line[512];
        sc_params_text(line, sizeof line, L->ent, L->params);
        sc_cat(&b, "  %s-%s: %s%s%s%s", s->mats[L->a].m.name, s->mats[L->b].m.name, L->composed ? "normal " : "",
               L->ent->title ? L->ent->title : L->ent->name, line[0] ? ", " : "", line);
        if (L->composed && L->ent_t) {
            sc_params_text(line, sizeof line, L->ent_t, L->params_t);
            sc_cat(&b, "; tangential %s%s%s", L->ent_t->title ? L->ent_t->title : L->ent_t->name,
                   line[0] ? ", " : "", line);
        } else if (L->composed) sc_cat(&b, "; frictionless");
        sc_cat(&b, "\n");
    }
    sc_cat(&b, "detectors:  ");
    int first = 1;
    const char *pairs[6];
    int np = 0;
    if (s->nspheres >= 2) pairs[np++] = "sphere-sphere analytic";
    if (s->nspheres && s->nwalls) pairs[np++] = "sphere-wall analytic";
    if (s->nspheres && s->nboxes) pairs[np++] = "sphere-other by the other shape's SDF at the centre";
    if (s->nboxes && s->nwalls) pairs[np++] = "shape-wall by vertices or support point";
    if (s->nboxes >= 2) pairs[np++] = "shape-shape by the polytope LP or ADMM";
    for (int i = 0; i < np; i++, first = 0) sc_cat(&b, "%s%s", first ? "" : ", ", pairs[i]);
    sc_cat(&b, "%s\n", first ? "none (no pair of particles can touch)" : "");
    sc_cat(&b, "gravity:    (%g, %g, %g) m/s^2\n", w->def.gravity[0], w->def.gravity[1],
           w->def.gravity[2]);
    double cH[9];
    if (floe_world_cell(w, NULL, cH)) {
        floe_cell_control cc;
        floe_world_cell_get_control(w, &cc);
        static const char *const cn[] = {"xx", "xy", "xz", "yx", "yy", "yz", "zx", "zy", "zz"};
        sc_cat(&b, "cell:       periodic, a = (%g, %g, %g), b = (%g, %g, %g), c = (%g, %g, %g) m; volume %g m^3\n",
               cH[0], cH[3], cH[6], cH[1], cH[4], cH[7], cH[2], cH[5], cH[8], floe_world_cell_volume(w));
        int first_c = 1;
        for (int k = 0; k < 9; k++) {
            if (cc.mode[k] == FLOE_CELL_STRESS)
                sc_cat(&b, "%s%s stress %g Pa", first_c ? "            control: " : ", ", cn[k], cc.stress[k]);
            else if (cc.rate[k] != 0)
                sc_cat(&b, "%s%s rate %g 1/s", first_c ? "            control: " : ", ", cn[k], cc.rate[k]);
            else continue;
            first_c = 0;
        }
        if (!first_c && cc.max_rate > 0) sc_cat(&b, "; servo at most %g 1/s\n", cc.max_rate);
        else if (!first_c) sc_cat(&b, "\n");
    }
    double dtc = floe_world_critical_dt(w), dt = floe_world_dt(w);
    floe_dt_estimates est;
    floe_world_dt_estimates(w, &est);
    sc_cat(&b, "time step:  critical dt estimate %.4g s (%s, particle %d); dt %.4g s (%s)\n", dtc,
           est.limiting >= 0 ? floe_dt_kind_name(est.limiting) : "none", est.limiting_particle, dt,
           s->dt_auto ? "automatic" : "given");
    if (s->dt_auto && w->def.accuracy > 0 && est.accuracy_dt <= dt)
        sc_cat(&b, "            = the step for time.accuracy %g (safety %g x critical would be %.4g s)\n",
               w->def.accuracy, s->safety, s->safety * dtc);
    else if (s->dt_auto) sc_cat(&b, "            = safety %g x critical\n", s->safety);
    else if (dt > dtc) sc_cat(&b, "            WARNING: dt is above the critical estimate "
                               "(allow_unstable_dt: true)\n");
    if (est.err1 > 0 || est.err2 > 0)
        sc_cat(&b, "            predicted restitution error %.2g (relative, the laws' error model)%s\n",
               est.predicted_error, w->def.accuracy > 0 ? "" : "; time.accuracy sets a target");
    sc_cat(&b, "integrator: %s", floe_integrator_name(w->def.integrator));
    if (w->def.adaptive)
        sc_cat(&b, ", adaptive steps in [%.4g, %.4g] s (velocity tolerance %g, penetration tolerance %g)",
               w->dt_lo, w->dt_hi, w->def.adapt_velocity_tol, w->def.adapt_depth_tol);
    if (w->def.pd_dem == FLOE_PD_DEM_STAGGERED && floe_world_pd_body_count(w) > 0)
        sc_cat(&b, ", staggered PD-DEM: PD step %.4g s (%s %d)", w->pd_every > 1 ? w->pd_every * dt : dt / w->pd_sub,
               w->pd_every > 1 ? "every" : "substeps", w->pd_every > 1 ? w->pd_every : w->pd_sub);
    sc_cat(&b, "\n");
    for (int k = 0; k < w->nuprov; k++) /* registered force providers (forces:) */
        sc_cat(&b, "%s%s", k ? ", " : "forces:     ", w->uprov[k]->klass->name);
    if (w->nuprov) sc_cat(&b, "\n");
    double nsteps = dt > 0 ? ceil(s->duration / dt - 1e-9) : 0;
    sc_cat(&b, "duration:   %g s = %s%.0f steps\n", s->duration, w->def.adaptive ? "at most " : "",
           w->def.adaptive && w->dt_lo > 0 ? ceil(s->duration / w->dt_lo - 1e-9) : nsteps);
    sc_cat(&b, "memory:     about %.3g MB (estimate; this machine has %.3g GB)\n", sc_mem_estimate(s, 0) / 1e6,
           sc_phys_mem() / 1e9);
    if (s->nstates) {
        sc_cat(&b, "states:     %d growing radi%s (particle", s->nstates, s->nstates == 1 ? "us" : "i");
        for (int i = 0; i < s->ngrow_listed; i++) sc_cat(&b, "%s%d", i ? ", " : " ", s->grow_particle[i]);
        sc_cat(&b, "%s)\n", s->nstates > s->ngrow_listed ? ", ..." : "");
    }
    if (s->nouts) {
        sc_cat(&b, "outputs%s:\n", with_outputs ? "" : " (not opened)");
        for (int i = 0; i < s->nouts; i++) {
            const sc_output *o = &s->outs[i];
            if (o->every) sc_cat(&b, "  %s every %ld steps -> %s%s\n", o->type, o->every, o->target,
                                 !strcmp(o->type, "vtk") ? "_NNNNNN.vtu" : "");
            else sc_cat(&b, "  %s every %g s -> %s%s\n", o->type, o->interval, o->target,
                        !strcmp(o->type, "vtk") ? "_NNNNNN.vtu" : "");
        }
    } else {
        sc_cat(&b, "outputs:    none (output directory %s unused)\n", outdir);
    }
}

/* ------------------------------------------------------------------------------------ */
/* Loading                                                                               */

static const char *const sc_root_keys[] = {"name", "description", "dimension", "time", "gravity",
                                           "neighbor", "contact_detection", "mass_2d", "materials", "laws",
                                           "walls", "bodies", "peridynamics", "outputs", "bonds", "checks", "plugins",
                                           "forces", "cell", "prepare", NULL};

/* checks: {energy: stop | warn | off, energy_tolerance} (the energy watchdog, floe_world.h) */
static int sc_checks(sc *s, const sc_map *r, floe_world_def *def)
{
    static const char *const ck_keys[] = {"energy", "energy_tolerance", NULL};
    static const char *const modes[] = {"stop", "warn", "off", NULL};
    struct fy_node *ck, *cv = sc_get(r, "checks", &ck);
    if (!cv) return FLOE_OK;
    sc_map cm;
    FLOE_TRY(sc_map_open(s, cv == ck ? NULL : cv, ck, "checks", ck_keys, &cm));
    FLOE_TRY(sc_enum(s, &cm, "energy", modes, FLOE_CHECK_STOP, &def->energy_check));
    FLOE_TRY(sc_num(s, &cm, "energy_tolerance", 0, def->energy_check_tol, &def->energy_check_tol));
    if (!(def->energy_check_tol > 0 && def->energy_check_tol < 1))
        return sc_range(s, &cm, "energy_tolerance", "in (0, 1) (fraction of the energy scale)", def->energy_check_tol);
    return FLOE_OK;
}

/* time.integrator, time.adaptive, time.pd_dem (docs/scene-format.md, docs/integrators.md) */
static int sc_time_integration(sc *s, const sc_map *tm, floe_world_def *def)
{
    static const char *const schemes[] = {"monolithic", "staggered", NULL};
    static const char *const ad_keys[] = {"dt_min", "dt_max", "velocity_tolerance", "penetration_tolerance", NULL};
    static const char *const pd_keys[] = {"scheme", "substeps", "every", NULL};
    /* the integrators are the registry's (kind "integrator", floe_integrator.h): every
     * class a world can step, in registration order */
    const char *integ[17];
    int ids[16], ni = 0, vv = 0;
    for (int k = 0, n = floe_registry_count(FLOE_KIND_INTEGRATOR); k < n && ni < 16; k++) {
        const floe_registry_entry *e = floe_registry_at(FLOE_KIND_INTEGRATOR, k);
        const floe_integrator_class *c = ((floe_integrator_class_fn)e->create)();
        if (!c || !c->step) continue; /* documented only (the Newmark solvers) */
        if (c->id == FLOE_VELOCITY_VERLET) vv = ni;
        ids[ni] = c->id;
        integ[ni++] = e->name;
    }
    integ[ni] = NULL;
    int ik = vv;
    FLOE_TRY(sc_enum(s, tm, "integrator", integ, vv, &ik));
    def->integrator = ni ? ids[ik] : FLOE_VELOCITY_VERLET;
    struct fy_node *ak, *av = sc_get(tm, "adaptive", &ak);
    if (av && av != ak && fy_node_is_mapping(av)) {
        sc_map am;
        FLOE_TRY(sc_map_open(s, av, ak, "time.adaptive", ad_keys, &am));
        def->adaptive = 1;
        FLOE_TRY(sc_num(s, &am, "dt_min", 0, 0.0, &def->dt_min));
        if (!(def->dt_min >= 0)) return sc_range(s, &am, "dt_min", ">= 0 s (0 = 1e-3 x dt_max)", def->dt_min);
        FLOE_TRY(sc_num(s, &am, "dt_max", 0, 0.0, &def->dt_max));
        if (!(def->dt_max >= 0)) return sc_range(s, &am, "dt_max", ">= 0 s (0 = the critical estimate)", def->dt_max);
        if (def->dt_min > 0 && def->dt_max > 0 && def->dt_min > def->dt_max)
            return sc_range(s, &am, "dt_min", "<= dt_max", def->dt_min);
        FLOE_TRY(sc_num(s, &am, "velocity_tolerance", 0, def->adapt_velocity_tol, &def->adapt_velocity_tol));
        if (!(def->adapt_velocity_tol > 0 && def->adapt_velocity_tol < 1))
            return sc_range(s, &am, "velocity_tolerance", "in (0, 1)", def->adapt_velocity_tol);
        FLOE_TRY(sc_num(s, &am, "penetration_tolerance", 0, def->adapt_depth_tol, &def->adapt_depth_tol));
        if (!(def->adapt_depth_tol > 0 && def->adapt_depth_tol < 1))
            return sc_range(s, &am, "penetration_tolerance", "in (0, 1)", def->adapt_depth_tol);
    } else {
        FLOE_TRY(sc_bool(s, tm, "adaptive", 0, &def->adaptive));
    }
    struct fy_node *pk, *pv = sc_get(tm, "pd_dem", &pk);
    if (pv) {
        sc_map pm;
        FLOE_TRY(sc_map_open(s, pv == pk ? NULL : pv, pk, "time.pd_dem", pd_keys, &pm));
        FLOE_TRY(sc_enum(s, &pm, "scheme", schemes, FLOE_PD_DEM_MONOLITHIC, &def->pd_dem));
        struct fy_node *sk, *sv = sc_get(&pm, "substeps", &sk);
        long sub = 1, every = 1;
        if (sv && sv != sk && sc_text(sv) && !strcmp(sc_text(sv), "auto")) sub = 0;
        else FLOE_TRY(sc_long(s, &pm, "substeps", 0, 1, &sub));
        if (sub < 0 || sub > 100000) return sc_range(s, &pm, "substeps", "in [1, 100000] or auto", (double)sub);
        FLOE_TRY(sc_long(s, &pm, "every", 0, 1, &every));
        if (every < 1 || every > 100000) return sc_range(s, &pm, "every", "in [1, 100000]", (double)every);
        if (sub != 1 && every > 1)
            return sc_fail(s, FLOE_EINVAL, pv, "time.pd_dem: give substeps (PD sub-cycled, dt_PD = dt / m) or every "
                           "(PD every k-th step, dt_PD = k dt), not both");
        if ((sub != 1 || every > 1) && def->pd_dem != FLOE_PD_DEM_STAGGERED)
            return sc_fail(s, FLOE_EINVAL, pv, "time.pd_dem: substeps and every need scheme: staggered");
        def->pd_substeps = (int)sub;
        def->pd_every = (int)every;
    }
    return FLOE_OK;
}

/* Every free particle needs a normal positive mass and inertia whose inverses are finite: a
 * density of 1e-300 gives a subnormal mass, an infinite inverse and NaN at the first step. */
static int sc_check_masses(sc *s)
{
    const floe_particles *p = &s->w->p;
    for (int i = 0; i < p->n; i++) {
        if (p->motion[i] != FLOE_FREE || !isfinite(p->radius[i])) continue;
        double m = p->mass[i];
        int bad = !(m > 0) || !isnormal(m) || !isfinite(1.0 / m) || !isfinite(m);
        for (int a = 0; a < 3 && !bad; a++) {
            double I = p->inertia[3 * i + a];
            bad = !(I > 0) || !isnormal(I) || !isfinite(1.0 / I) || !isfinite(I);
        }
        if (!bad) continue;
        int mat = p->material[i], entry = -1;
        for (int e = 0; e < s->nbody_entries && entry < 0; e++)
            if (i >= s->entry_first[e] && i < s->entry_first[e] + s->entry_count[e]) entry = e;
        char where[64] = "";
        if (entry >= 0) snprintf(where, sizeof where, " (bodies[%d])", entry);
        return sc_fail(s, FLOE_EINVAL, mat >= 0 && mat < s->nmats ? s->mats[mat].at : NULL,
                       "particle %d%s of material '%s' (density %g kg/m^3) has mass %g kg and inertia "
                       "(%g, %g, %g) kg m^2: not a usable number (its inverse is not finite); check "
                       "the density and the size", i, where, mat >= 0 && mat < s->nmats ? s->mats[mat].m.name : "?", mat >= 0 && mat < s->nmats ? s->mats[mat].m.density : 0.0,
                       m, p->inertia[3 * i], p->inertia[3 * i + 1], p->inertia[3 * i + 2]);
    }
    return FLOE_OK;
}

/* duration / dt must be a step count a run can reach (1e30 s would overflow the count) */
static int sc_check_steps(sc *s, const sc_map *tm, double dt, const char *which)
{
    double n = s->duration / dt;
    if (dt > 0 && !(n <= SC_MAX_STEPS))
        return sc_fail(s, FLOE_EINVAL, sc_get(tm, "duration", NULL),
                       "time.duration %g s is %.3g steps of %g s (%s): more than 1e12 steps", s->duration,
                       n, dt, which);
    return FLOE_OK;
}

/* plugins: [path.so, ...] (relative to the scene file): shared libraries whose init
 * registers shapes, laws or outputs that the rest of the scene names (core/scene/plugin.c) */
static int sc_parse_plugins(sc *s, const sc_map *r)
{
    struct fy_node *pk, *pv = sc_get(r, "plugins", &pk);
    if (!pv) return FLOE_OK;
    if (pv == pk || !fy_node_is_sequence(pv))
        return sc_fail(s, FLOE_EPARSE, pv == pk ? pk : pv, "plugins must be a list of shared-library paths "
                       "([./my_plugin.so, ...]), got %s", pv == pk ? "nothing" : sc_type_name(pv));
#if defined(FLOE_SCENE_NO_PLUGINS)
    /* the fuzzer's build: a scene must not make the loader run code from arbitrary files */
    return sc_fail(s, FLOE_ENOTSUP, pk, "plugins are disabled in this build (FLOE_SCENE_NO_PLUGINS)");
#endif
    void *it = NULL;
    struct fy_node *e;
    int i = 0;
    while ((e = fy_node_sequence_iterate(pv, &it))) {
        const char *file = sc_text(e);
        if (!file || !file[0] || !fy_node_is_scalar(e))
            return sc_fail(s, FLOE_EPARSE, e, "plugins[%d]: expected a path to a shared library", i);
        char path[1024];
        const char *slash = s->path ? strrchr(s->path, '/') : NULL;
        if (file[0] != '/' && slash)
            snprintf(path, sizeof path, "%.*s/%s", (int)(slash - s->path), s->path, file);
        else if (file[0] != '/' && !strchr(file, '/'))
            snprintf(path, sizeof path, "./%s", file); /* dlopen searches the library path otherwise */
        else
            snprintf(path, sizeof path, "%s", file);
        char err[768];
        int rc = floe_plugin_load(path, err, sizeof err);
        if (rc) return sc_fail(s, rc, e, "plugins[%d]: %s", i, err);
        i++;
    }
    return FLOE_OK;
}

static int sc_build(sc *s, struct fy_node *root, const char *outdir, int with_outputs,
                    floe_scene_info *info)
{
    static const char *const time_keys[] = {"duration", "dt", "safety", "allow_unstable_dt", "integrator",
                                            "adaptive", "pd_dem", "accuracy", NULL};
    static const char *const nb_keys[] = {"skin", "leaf_size", NULL};
    static const char *const mass2d[] = {"volume", "area", NULL};
    sc_map r;
    FLOE_TRY(sc_map_open(s, root, root, "", sc_root_keys, &r));
    FLOE_TRY(sc_parse_plugins(s, &r));

    const char *name;
    FLOE_TRY(sc_str(s, &r, "name", 0, "", &name, NULL));
    snprintf(info->name, sizeof info->name, "%s", name);
    const char *descr;
    FLOE_TRY(sc_str(s, &r, "description", 0, "", &descr, NULL));

    long dim;
    FLOE_TRY(sc_long(s, &r, "dimension", 0, 3, &dim));
    if (dim != 2 && dim != 3) return sc_range(s, &r, "dimension", "2 or 3", (double)dim);
    s->dim = (int)dim;

    floe_world_def def = floe_default_world_def();
    def.dim = s->dim;

    struct fy_node *tk;
    struct fy_node *tv = sc_get(&r, "time", &tk);
    if (!tv) return sc_fail(s, FLOE_EPARSE, root, "time is required ({duration: seconds})");
    sc_map tm;
    FLOE_TRY(sc_map_open(s, tv == tk ? NULL : tv, tk, "time", time_keys, &tm));
    FLOE_TRY(sc_num(s, &tm, "duration", 1, 0, &s->duration));
    if (!(s->duration > 0)) return sc_range(s, &tm, "duration", "> 0 (s)", s->duration);
    {
        struct fy_node *dk;
        struct fy_node *dv = sc_get(&tm, "dt", &dk);
        s->dt_given = 0;
        if (dv && dv != dk && sc_text(dv) && !strcmp(sc_text(dv), "auto")) {
            s->dt_given = 0;
        } else {
            FLOE_TRY(sc_num(s, &tm, "dt", 0, 0.0, &s->dt_given));
            if (dv && !(s->dt_given > 0))
                return sc_range(s, &tm, "dt", "> 0 s (write dt: auto, or omit dt, for the automatic step)",
                                s->dt_given);
        }
        s->dt_auto = s->dt_given == 0;
    }
    FLOE_TRY(sc_num(s, &tm, "safety", 0, def.dt_safety > 0 ? def.dt_safety : 0.2, &s->safety));
    if (!(s->safety > 0 && s->safety <= 1)) return sc_range(s, &tm, "safety", "in (0, 1]", s->safety);
    FLOE_TRY(sc_bool(s, &tm, "allow_unstable_dt", 0, &def.allow_unstable_dt));
    FLOE_TRY(sc_num(s, &tm, "accuracy", 0, 0.0, &def.accuracy));
    if (sc_has(&tm, "accuracy") && !(def.accuracy > 0 && def.accuracy < 0.5))
        return sc_range(s, &tm, "accuracy", "in (0, 0.5) (relative error of the restitution)", def.accuracy);
    def.dt = s->dt_given;
    def.dt_safety = s->safety;
    FLOE_TRY(sc_time_integration(s, &tm, &def));
    FLOE_TRY(sc_check_steps(s, &tm, def.adaptive ? def.dt_min : s->dt_given,
                            def.adaptive ? "time.adaptive.dt_min" : "time.dt"));

    double g[3];
    FLOE_TRY(sc_vec(s, &r, "gravity", 0, NULL, g));
    FLOE_TRY(sc_check_planar(s, &r, "gravity", g));
    floe_v3_copy(def.gravity, g);

    struct fy_node *nk;
    struct fy_node *nv = sc_get(&r, "neighbor", &nk);
    if (nv) {
        sc_map nm;
        FLOE_TRY(sc_map_open(s, nv == nk ? NULL : nv, nk, "neighbor", nb_keys, &nm));
        FLOE_TRY(sc_num(s, &nm, "skin", 0, 0.0, &def.skin));
        if (!(def.skin >= 0)) return sc_range(s, &nm, "skin", ">= 0 (m; 0 = automatic)", def.skin);
        long leaf;
        FLOE_TRY(sc_long(s, &nm, "leaf_size", 0, def.leaf_size > 0 ? def.leaf_size : 16, &leaf));
        if (leaf < 1 || leaf > 1024) return sc_range(s, &nm, "leaf_size", "in [1, 1024]", (double)leaf);
        def.leaf_size = (int)leaf;
    }
    FLOE_TRY(sc_checks(s, &r, &def));
    if (sc_has(&r, "mass_2d")) {
        if (s->dim != 2)
            return sc_fail(s, FLOE_EINVAL, sc_get(&r, "mass_2d", NULL),
                           "mass_2d is only valid with dimension: 2");
        int mm;
        FLOE_TRY(sc_enum(s, &r, "mass_2d", mass2d, 0, &mm));
        def.mass_2d_area = mm;
    }

    struct fy_node *mk;
    struct fy_node *mv = sc_get(&r, "materials", &mk);
    if (!mv) return sc_fail(s, FLOE_EPARSE, root, "materials is required (a list of {name, density, ...})");
    FLOE_TRY(sc_parse_materials(s, mv == mk ? NULL : mv, mk));
    struct fy_node *lk;
    struct fy_node *lv = sc_get(&r, "laws", &lk);
    FLOE_TRY(sc_parse_laws(s, lv == lk ? NULL : lv, lk));

    char werr[512] = "";
    s->w = floe_world_create(&def, werr, sizeof werr);
    if (!s->w) return sc_fail(s, FLOE_EINVAL, NULL, "%s", werr[0] ? werr : "invalid world definition");
    for (int i = 0; i < s->nmats; i++) {
        /* young is only used by hertz_mindlin laws (checked above); the world wants one */
        floe_material wm = s->mats[i].m;
        if (!s->mats[i].has_young) wm.young = 1.0;
        int rc = floe_world_add_material(s->w, &wm);
        if (rc < 0) return sc_fail(s, -rc, s->mats[i].at, "materials[%d]: %s", i,
                                   floe_world_last_error(s->w));
    }
    FLOE_TRY(sc_build_laws(s));
    {
        /* ADMM options (pairs of convex shapes other than polytopes and spheres) */
        static const char *const cd_keys[] = {"tolerance", "max_iterations", NULL};
        struct fy_node *ck, *cv = sc_get(&r, "contact_detection", &ck);
        if (cv) {
            sc_map cm;
            FLOE_TRY(sc_map_open(s, cv == ck ? NULL : cv, ck, "contact_detection", cd_keys, &cm));
            floe_admm_options *o = &s->w->det.admm;
            FLOE_TRY(sc_num(s, &cm, "tolerance", 0, o->tol, &o->tol));
            if (!(o->tol > 0 && o->tol < 1))
                return sc_range(s, &cm, "tolerance", "in (0, 1) (relative to the smaller particle size)", o->tol);
            long mi;
            FLOE_TRY(sc_long(s, &cm, "max_iterations", 0, o->max_iter, &mi));
            if (mi < 1 || mi > 100000) return sc_range(s, &cm, "max_iterations", "in [1, 100000]", (double)mi);
            o->max_iter = (int)mi;
        }
    }

    /* bodies first: body particle i is world particle i (ids in outputs and trackers) */
    struct fy_node *bk;
    struct fy_node *bv = sc_get(&r, "bodies", &bk);
    struct fy_node *pdk;
    struct fy_node *pdv = sc_get(&r, "peridynamics", &pdk);
    if (!bv && !pdv)
        return sc_fail(s, FLOE_EPARSE, root, "bodies is required (a list of bodies or packings; or peridynamics)");
    if (bv) FLOE_TRY(sc_parse_bodies(s, bv == bk ? NULL : bv, bk));
    FLOE_TRY(sc_parse_pd(s, pdv == pdk ? NULL : pdv, pdk));
    struct fy_node *wk;
    struct fy_node *wv = sc_get(&r, "walls", &wk);
    FLOE_TRY(sc_parse_walls(s, wv == wk ? NULL : wv, wk));
    { struct fy_node *bok, *bov = sc_get(&r, "bonds", &bok); FLOE_TRY(sc_parse_bonds(s, bov == bok ? NULL : bov, bok)); } /* beam bonds */
    { struct fy_node *fk, *fv = sc_get(&r, "forces", &fk); FLOE_TRY(sc_parse_forces(s, fv == fk ? NULL : fv, fk)); }
    { struct fy_node *ck, *cv = sc_get(&r, "cell", &ck); if (cv) FLOE_TRY(sc_parse_cell(s, cv == ck ? NULL : cv, ck)); } /* periodic cell */
    FLOE_TRY(sc_check_pairs(s));
    FLOE_TRY(sc_check_memory(s, NULL, "the scene", 0));
    /* the preparation (scene_prepare.c): run before the outputs exist, only for a run */
    char prepared[512] = "";
    {
        struct fy_node *pk, *pv = sc_get(&r, "prepare", &pk);
        if (pv) FLOE_TRY(sc_parse_prepare(s, pv, pk, with_outputs != FLOE_SCENE_CHECK, prepared, sizeof prepared));
    }
    struct fy_node *ok;
    struct fy_node *ov = sc_get(&r, "outputs", &ok);
    FLOE_TRY(sc_parse_outputs(s, ov == ok ? NULL : ov, ok, outdir,
                              with_outputs != FLOE_SCENE_CHECK && with_outputs != FLOE_SCENE_NO_OUTPUTS));

    int rc = floe_world_prepare(s->w);
    if (rc != FLOE_OK)
        return sc_fail(s, rc, rc == FLOE_EUNSTABLE && !s->dt_auto ? sc_get(&tm, "dt", NULL) : NULL,
                       "%s", floe_world_last_error(s->w));
    FLOE_TRY(sc_check_steps(s, &tm, s->w->def.adaptive ? s->w->dt_lo : s->w->dt,
                            s->w->def.adaptive ? "the smallest adaptive step" : "the time step"));
    FLOE_TRY(sc_check_masses(s));
    /* an output interval not longer than a fixed step writes every step: say so to the
     * world, which then need not count intervals one by one */
    for (int k = 0; k < s->w->nobs && !s->w->def.adaptive; k++) {
        floe_observer *o = s->w->obs[k];
        if (o->period_steps <= 0 && o->period_time > 0 && o->period_time <= s->w->dt) o->period_steps = 1;
    }

    info->duration = s->duration;
    info->nparticles = s->nparticles;
    info->nwalls = s->nwalls;
    info->nmaterials = s->nmats;
    info->nlaws = s->nlaws;
    info->nobservers = s->nobservers;
    info->nstates = s->nstates;
    sc_summary(s, info->name, outdir, with_outputs != FLOE_SCENE_CHECK && with_outputs != FLOE_SCENE_NO_OUTPUTS, info);
    if (prepared[0]) {
        size_t L = strlen(info->summary);
        snprintf(info->summary + L, sizeof info->summary - L, "%s%s\n", L && info->summary[L - 1] != '\n' ? "\n" : "",
                 prepared);
    }
    return FLOE_OK;
}

/* Position of the innermost bracket `open` ('[' or '{') still open at the end of the text:
 * libfyaml reports an unclosed flow collection at the end of the input, the user wants to
 * know where it was opened. A light scanner: flow indicators count inside flow collections
 * and at the start of a block value; quoted scalars and comments are skipped. */
static int sc_find_unclosed(const char *text, char open, int *line_out, int *col_out)
{
    struct { char c; int line, col; } st[256];
    int n = 0, line = 1, col = 1, value_start = 1;
    for (const char *p = text; *p; p++, col++) {
        char c = *p;
        if (c == '\n') { line++; col = 0; value_start = 1; continue; }
        if (c == ' ' || c == '\t') continue;
        if (c == '#' && (p == text || p[-1] == ' ' || p[-1] == '\t' || p[-1] == '\n')) {
            while (p[1] && p[1] != '\n') { p++; col++; }
            continue;
        }
        if ((c == '"' || c == '\'') && (n > 0 || value_start)) {
            char q = c;
            while (p[1]) {
                p++;
                col++;
                if (*p == '\n') { line++; col = 0; continue; }
                if (q == '"' && *p == '\\' && p[1]) { p++; col++; continue; }
                if (*p == q) {
                    if (q == '\'' && p[1] == '\'') { p++; col++; continue; }
                    break;
                }
            }
            value_start = 0;
            continue;
        }
        if ((c == '[' || c == '{') && (n > 0 || value_start)) {
            if (n < 256) { st[n].c = c; st[n].line = line; st[n].col = col; }
            n++;
            value_start = 1;
            continue;
        }
        if ((c == ']' || c == '}') && n > 0) { n--; value_start = 0; continue; }
        if (c == ',' && n > 0) { value_start = 1; continue; }
        if ((c == ':' || c == '-' || c == '?') && (p[1] == ' ' || p[1] == '\n' || p[1] == '\t' ||
                                                   (n > 0 && (p[1] == ',' || p[1] == ']' || p[1] == '}')))) {
            value_start = 1;
            continue;
        }
        value_start = 0;
    }
    for (int i = (n < 256 ? n : 256) - 1; i >= 0; i--)
        if (st[i].c == open) { *line_out = st[i].line; *col_out = st[i].col; return 1; }
    return 0;
}

/* Collected libfyaml diagnostics -> "path:line:col: message" (first error). */
static int sc_parse_error(sc *s, struct fy_diag *diag, const char *text)
{
    void *it = NULL;
    struct fy_diag_error *e;
    while ((e = fy_diag_errors_iterate(diag, &it))) {
        if (e->type < FYET_ERROR) continue;
        char msg[512];
        snprintf(msg, sizeof msg, "%s", e->msg ? e->msg : "malformed YAML");
        size_t n = strlen(msg);
        while (n && (msg[n - 1] == '\n' || msg[n - 1] == ' ')) msg[--n] = '\0';
        int el = e->line > 0 ? e->line : 0, ec = e->column > 0 ? e->column : 1;
        /* libfyaml reports an unclosed flow collection where it noticed (often the end of
         * the input); the user wants the bracket that was opened */
        int l1 = 0, c1 = 0, l2 = 0, c2 = 0;
        int h1 = sc_find_unclosed(text, '[', &l1, &c1), h2 = sc_find_unclosed(text, '{', &l2, &c2);
        char open = 0;
        int ol = 0, oc = 0;
        if (h1 && (!h2 || l1 > l2 || (l1 == l2 && c1 > c2))) { open = '['; ol = l1; oc = c1; }
        else if (h2) { open = '{'; ol = l2; oc = c2; }
        if (open && (ol > el || (ol == el && oc >= ec))) open = 0;
        if (open)
            snprintf(s->err, s->errlen, "%s:%d:%d: YAML syntax error: '%c' is never closed (%s "
                     "at line %d, column %d)", s->path, ol, oc, open, msg, el, ec);
        else if (el > 0)
            snprintf(s->err, s->errlen, "%s:%d:%d: YAML syntax error: %s", s->path, el, ec, msg);
        else
            snprintf(s->err, s->errlen, "%s: YAML syntax error: %s", s->path, msg);
        return FLOE_EPARSE;
    }
    snprintf(s->err, s->errlen, "%s: empty scene or malformed YAML (no document)", s->path);
    return FLOE_EPARSE;
}

/* Offset of the first byte that is not part of well-formed UTF-8 (RFC 3629: no overlong
 * forms, no surrogates, at most U+10FFFF), -1 if the text is valid. */
static long sc_bad_utf8(const char *text, long len)
{
    const unsigned char *u = (const unsigned char *)text;
    long i = 0;
    while (i < len) {
        unsigned c = u[i];
        if (c < 0x80) { i++; continue; }
        int n;
        unsigned lo = 0x80, hi = 0xBF;
        if (c >= 0xC2 && c <= 0xDF) n = 1;
        else if (c >= 0xE0 && c <= 0xEF) {
            n = 2;
            if (c == 0xE0) lo = 0xA0;
            if (c == 0xED) hi = 0x9F;
        } else if (c >= 0xF0 && c <= 0xF4) {
            n = 3;
            if (c == 0xF0) lo = 0x90;
            if (c == 0xF4) hi = 0x8F;
        } else return i;
        for (int k = 1; k <= n; k++) {
            if (i + k >= len) return i;
            unsigned d = u[i + k];
            if (d < (k == 1 ? lo : 0x80) || d > (k == 1 ? hi : 0xBF)) return i;
        }
        i += n + 1;
    }
    return -1;
}

/* Nodes of the document once its aliases are expanded, counted without expanding them: a
 * 1 KB "billion laughs" alias bomb would otherwise take gigabytes. The walk stops as soon as
 * the count passes limit (so it costs at most limit visits) or aliases nest deeper than
 * SC_MAX_ALIAS_DEPTH. *bad receives the alias where it stopped. Returns the count (> limit:
 * too large; -1: too deep or an unresolvable alias). */
#define SC_MAX_NODES 2000000L
#define SC_MAX_ALIAS_DEPTH 64
static long sc_count_nodes(struct fy_node *n, long count, long limit, int alias_depth, struct fy_node **bad)
{
    if (!n || count > limit) return count;
    if (fy_node_is_alias(n)) {
        if (alias_depth >= SC_MAX_ALIAS_DEPTH) { *bad = n; return -1; }
        struct fy_node *t = fy_node_resolve_alias(n);
        if (!t) { *bad = n; return -1; }
        long c = sc_count_nodes(t, count, limit, alias_depth + 1, bad);
        if (c > limit) *bad = n; /* the outermost alias on the way */
        return c;
    }
    count++;
    void *it = NULL;
    if (fy_node_is_mapping(n)) {
        struct fy_node_pair *p;
        while ((p = fy_node_mapping_iterate(n, &it)) && count >= 0 && count <= limit) {
            count = sc_count_nodes(fy_node_pair_key(p), count, limit, alias_depth, bad);
            if (count >= 0) count = sc_count_nodes(fy_node_pair_value(p), count, limit, alias_depth, bad);
        }
    } else if (fy_node_is_sequence(n)) {
        struct fy_node *c;
        while ((c = fy_node_sequence_iterate(n, &it)) && count >= 0 && count <= limit)
            count = sc_count_nodes(c, count, limit, alias_depth, bad);
    }
    return count;
}

/* Nodes written in the text (aliases not expanded), counted from the parser's events before
 * a document is built: a 16 MiB list of numbers would take gigabytes as a document. Stops
 * past limit; a syntax error ends the count (the document build reports it). */
static long sc_count_events(const char *text, size_t len, long limit, struct fy_diag *diag)
{
    struct fy_parse_cfg cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.flags = FYPCF_QUIET;
    cfg.diag = diag;
    struct fy_parser *fyp = fy_parser_create(&cfg);
    if (!fyp) return 0;
    long n = 0;
    if (fy_parser_set_string(fyp, text, len) == 0) {
        struct fy_event *ev;
        while (n <= limit && (ev = fy_parser_parse(fyp))) {
            enum fy_event_type t = ev->type;
            n += t == FYET_SCALAR || t == FYET_ALIAS || t == FYET_MAPPING_START || t == FYET_SEQUENCE_START;
            fy_parser_event_free(fyp, ev);
        }
    }
    fy_parser_destroy(fyp);
    return n;
}

static void sc_diag_discard(struct fy_diag *diag, void *user, const char *buf, size_t len)
{
    (void)diag;
    (void)user;
    (void)buf;
    (void)len;
}

int floe_scene_load_ex(const char *path, const char *text, const char *outdir, int with_outputs,
                       floe_world **out_world, floe_scene_info *info, char *err, size_t errlen)
{
    char dummy_err[8];
    floe_scene_info dummy_info;
    if (!err || !errlen) { err = dummy_err; errlen = sizeof dummy_err; }
    if (!info) info = &dummy_info;
    err[0] = '\0';
    memset(info, 0, sizeof *info);
    if (out_world) *out_world = NULL;
    if (!path) path = "<scene>";
    if (!outdir) outdir = "out";

    {
        char rerr[256];
        int rc = floe_register_builtins(rerr, sizeof rerr);
        if (rc) {
            snprintf(err, errlen, "%s: %s", path, rerr);
            return rc;
        }
    }
    sc s;
    memset(&s, 0, sizeof s);
    s.path = path;
    s.err = err;
    s.errlen = errlen;
    s.dim = 3;

    char *owned = NULL;
    if (!text) {
        FILE *f = fopen(path, "rb");
        if (!f) {
            snprintf(err, errlen, "%s: cannot open scene file: %s", path, strerror(errno));
            return FLOE_EIO;
        }
        size_t cap = 1 << 16, n = 0;
        owned = malloc(cap);
        while (owned) {
            size_t k = fread(owned + n, 1, cap - n - 1, f);
            n += k;
            if (k == 0) break;
            if (n > SC_MAX_TEXT) {
                fclose(f);
                free(owned);
                snprintf(err, errlen, "%s: the scene file is larger than %zu MiB (a scene lists "
                         "packings, not particles; meshes are separate files)", path, SC_MAX_TEXT >> 20);
                return FLOE_EINVAL;
            }
            if (n + 1 == cap) {
                char *p = realloc(owned, cap * 2);
                if (!p) { free(owned); owned = NULL; break; }
                owned = p;
                cap *= 2;
            }
        }
        int bad = ferror(f);
        fclose(f);
        if (!owned || bad) {
            free(owned);
            snprintf(err, errlen, "%s: cannot read scene file", path);
            return bad ? FLOE_EIO : FLOE_ENOMEM;
        }
        owned[n] = '\0';
        text = owned;
        s.text = text;
        s.textlen = (long)n;
        const char *nul = memchr(text, '\0', n);
        if (nul) {
            s.textlen = (long)(nul - text);
            int rc = sc_fail_pos(&s, FLOE_EPARSE, (long)(nul - text), "a NUL byte (byte %ld of %zu): a scene is "
                                 "UTF-8 text", (long)(nul - text), n);
            free(owned);
            return rc;
        }
    }
    if (strlen(text) > SC_MAX_TEXT) {
        free(owned);
        snprintf(err, errlen, "%s: the scene text is larger than %zu MiB", path, SC_MAX_TEXT >> 20);
        return FLOE_EINVAL;
    }
    {
        s.text = text;
        s.textlen = (long)strlen(text);
        long bad = sc_bad_utf8(text, s.textlen);
        if (bad >= 0) {
            int rc = sc_fail_pos(&s, FLOE_EPARSE, bad, "invalid UTF-8 (byte 0x%02x): a scene is UTF-8 text",
                                 (unsigned)(unsigned char)text[bad]);
            free(owned);
            return rc;
        }
    }

    struct fy_diag_cfg dcfg;
    fy_diag_cfg_default(&dcfg);
    dcfg.fp = NULL;
    dcfg.output_fn = sc_diag_discard;
    dcfg.colorize = false;
    struct fy_diag *diag = fy_diag_create(&dcfg);
    if (!diag) {
        free(owned);
        snprintf(err, errlen, "%s: out of memory", path);
        return FLOE_ENOMEM;
    }
    fy_diag_set_collect_errors(diag, true);
    struct fy_parse_cfg pcfg;
    memset(&pcfg, 0, sizeof pcfg);
    pcfg.flags = FYPCF_QUIET; /* aliases are resolved below, once their expansion is counted */
    pcfg.diag = diag;
    s.text = text;
    s.textlen = (long)strlen(text);
    struct fy_diag *diag2 = fy_diag_create(&dcfg); /* the count's own diagnostics, discarded */
    long written = diag2 ? sc_count_events(text, strlen(text), SC_MAX_NODES, diag2) : 0;
    if (diag2) fy_diag_destroy(diag2);
    if (written > SC_MAX_NODES) {
        fy_diag_destroy(diag);
        free(owned);
        return sc_fail(&s, FLOE_EPARSE, NULL, "the scene has more than %ld YAML nodes: refused (list "
                       "packings, not particles)", SC_MAX_NODES);
    }
    struct fy_document *doc = fy_document_build_from_string(&pcfg, text, strlen(text));
    int rc = FLOE_OK;
    if (!doc || fy_diag_got_error(diag)) {
        rc = sc_parse_error(&s, diag, text);
    } else {
        struct fy_node *bad = NULL;
        long nodes = sc_count_nodes(fy_document_root(doc), 0, SC_MAX_NODES, 0, &bad);
        if (nodes < 0) {
            const char *an = bad && fy_node_is_scalar(bad) ? fy_node_get_scalar0(bad) : NULL;
            rc = sc_fail(&s, FLOE_EPARSE, bad, "alias *%s: no anchor &%s before it, or aliases that nest deeper "
                         "than %d or refer to themselves", an ? an : "?", an ? an : "?", SC_MAX_ALIAS_DEPTH);
        }
        else if (nodes > SC_MAX_NODES)
            rc = sc_fail(&s, FLOE_EPARSE, bad, "the scene expands to more than %ld YAML nodes%s: refused (an "
                         "alias bomb?)", SC_MAX_NODES, bad ? " through this alias" : "");
        else if (fy_document_resolve(doc) != 0 || fy_diag_got_error(diag))
            rc = sc_parse_error(&s, diag, text);
    }
    if (rc != FLOE_OK) {
    } else {
        struct fy_node *root = fy_document_root(doc);
        if (!root || sc_is_missing(root))
            rc = sc_fail(&s, FLOE_EPARSE, NULL, "empty scene: expected a mapping with time, "
                         "materials, laws and bodies");
        else
            rc = sc_build(&s, root, outdir, with_outputs, info);
    }
    if (doc) fy_document_destroy(doc);
    fy_diag_destroy(diag);
    free(owned);

    free(s.mats);
    for (int i = 0; i < s.nlaws; i++) {
        free(s.laws[i].params);
        free(s.laws[i].params_t);
    }
    free(s.laws);
    free(s.law_at);
    free(s.entry_first);
    free(s.entry_count);
    /* every allocated entry: one that failed half-way holds its parameters too */
    for (int i = 0; i < s.outs_cap; i++) free(s.outs[i].uparams);
    free(s.outs);
    if (rc != FLOE_OK) {
        if (s.w) floe_world_destroy(s.w);
        if (!err[0]) snprintf(err, errlen, "%s: %s", path, floe_strerror(rc));
        return rc;
    }
    if (out_world) *out_world = s.w;
    else floe_world_destroy(s.w);
    return FLOE_OK;
}

int floe_scene_load(const char *path, const char *outdir, floe_world **out_world,
                    floe_scene_info *info, char *err, size_t errlen)
{
    return floe_scene_load_ex(path, NULL, outdir, 1, out_world, info, err, errlen);
}

int floe_scene_load_string(const char *text, const char *path, const char *outdir,
                           floe_world **out_world, floe_scene_info *info, char *err, size_t errlen)
{
    if (!text) {
        if (err && errlen) snprintf(err, errlen, "%s: no scene text", path ? path : "<string>");
        return FLOE_EINVAL;
    }
    return floe_scene_load_ex(path ? path : "<string>", text, outdir, 1, out_world, info, err,
                              errlen);
}

/* ------------------------------------------------------------------------------------ */
/* Default demo: ~2,000 glass beads poured into a box (Hertz-Mindlin, e = 0.5, mu = 0.5). */

static const char sc_demo[] =
    "# floe default demo: 2,000 glass beads (r = 1 mm) poured into a 30 mm x 30 mm box.\n"
    "# dt is automatic: 0.75 x the critical estimate (about 1.6e-5 s, 15,000 steps).\n"
    "name: pour\n"
    "dimension: 3\n"
    "time: {duration: 0.25, safety: 0.75}\n"
    "gravity: [0, 0, -9.81]\n"
    "neighbor: {skin: 0.0005}\n"
    "materials:\n"
    "  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}\n"
    "laws:\n"
    "  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}\n"
    "walls:\n"
    "  - {point: [0, 0, 0], normal: [0, 0, 1], material: glass}\n"
    "  - {point: [0, 0, 0], normal: [1, 0, 0], material: glass}\n"
    "  - {point: [0.03, 0, 0], normal: [-1, 0, 0], material: glass}\n"
    "  - {point: [0, 0, 0], normal: [0, 1, 0], material: glass}\n"
    "  - {point: [0, 0.03, 0], normal: [0, -1, 0], material: glass}\n"
    "bodies:\n"
    "  - packing: random\n"
    "    shape: {sphere: {radius: 0.001}}\n"
    "    material: glass\n"
    "    region: {min: [0, 0, 0.002], max: [0.03, 0.03, 0.06]}\n"
    "    count: 2000\n"
    "    seed: 7\n"
    "outputs:\n"
    "  - {type: vtk, every: 2000, prefix: frame}\n"
    "  - {type: energy, every: 100, file: energy.csv}\n"
    "  - {type: stress, every: 100, file: stress.csv, group: all}\n";

const char *floe_scene_default_demo(void) { return sc_demo; }
