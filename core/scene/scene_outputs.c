/* scene_outputs.c - scene sections `outputs` (built-in and registered outputs) and `bonds`
 * (beam bonds). */
#include "scene_read.h"

/* ------------------------------------------------------------------------------------ */
/* Outputs                                                                               */

static int sc_mkdir_p(const char *dir)
{
    char buf[1024];
    size_t n = strlen(dir);
    if (n == 0 || n >= sizeof buf) return -1;
    memcpy(buf, dir, n + 1);
    for (size_t i = 1; i <= n; i++) {
        if (buf[i] == '/' || buf[i] == '\0') {
            char c = buf[i];
            buf[i] = '\0';
            if (mkdir(buf, 0777) != 0 && errno != EEXIST) return -1;
            buf[i] = c;
        }
    }
    struct stat st;
    return stat(dir, &st) == 0 && S_ISDIR(st.st_mode) ? 0 : -1;
}

static const char *const sc_output_types[] = {"vtk", "csv", "energy", "stress", "tracker", NULL};

/* floe_scene_set_vtk_mode (floe_scene.h): the vtk outputs of an MPI run */
static _Thread_local int vtk_mode = FLOE_SCENE_VTK_SERIAL, vtk_rank, vtk_size;
static _Thread_local int (*vtk_take)(void *ctx, floe_observer *o);
static _Thread_local void *vtk_ctx;

int floe_scene_set_vtk_mode(int mode, int rank, int size, int (*take)(void *ctx, floe_observer *o), void *ctx)
{
    if (mode != FLOE_SCENE_VTK_SERIAL && mode != FLOE_SCENE_VTK_SKIP && mode != FLOE_SCENE_VTK_PIECES)
        return FLOE_EINVAL;
    if (mode == FLOE_SCENE_VTK_PIECES && (!take || size < 1 || rank < 0 || rank >= size)) return FLOE_EINVAL;
    vtk_mode = mode;
    vtk_rank = rank;
    vtk_size = size;
    vtk_take = take;
    vtk_ctx = ctx;
    return FLOE_OK;
}

int sc_parse_outputs(sc *s, struct fy_node *seq, struct fy_node *key, const char *outdir,
                            int with_outputs)
{
    static const char *const keys_by_type[5][8] = {
        {"type", "every", "interval", "prefix", "ascii", NULL},
        {"type", "every", "interval", "file", NULL},
        {"type", "every", "interval", "file", NULL},
        {"type", "every", "interval", "file", "group", "volume", NULL},
        {"type", "every", "interval", "file", "particles", "walls", NULL},
    };
    static const char *const keys_all[] = {"type", "every", "interval", "prefix", "ascii", "file",
                                           "group", "volume", "particles", "walls", NULL};
    static const char *const defaults[] = {"frame", "particles.csv", "energy.csv", "stress.csv",
                                           "track.csv"};
    if (!seq) return FLOE_OK;
    if (sc_is_missing(seq) || !fy_node_is_sequence(seq))
        return sc_fail(s, FLOE_EPARSE, sc_is_missing(seq) ? key : seq,
                       "outputs must be a list of {type: vtk|csv|energy|stress|tracker, ...}");
    int n = fy_node_sequence_item_count(seq);
    s->outs = calloc((size_t)(n ? n : 1), sizeof *s->outs);
    if (!s->outs) return sc_fail(s, FLOE_ENOMEM, key, "out of memory");
    s->outs_cap = n ? n : 1;
    if (with_outputs && n > 0 && sc_mkdir_p(outdir) != 0)
        return sc_fail(s, FLOE_EIO, key, "cannot create the output directory '%s': %s", outdir,
                       strerror(errno));
    void *it = NULL;
    struct fy_node *e;
    int i = 0;
    while ((e = fy_node_sequence_iterate(seq, &it))) {
        char what[32];
        snprintf(what, sizeof what, "outputs[%d]", i);
        sc_map m = {e, e, ""};
        snprintf(m.what, sizeof m.what, "%s", what);
        if (!fy_node_is_mapping(e))
            return sc_fail(s, FLOE_EPARSE, e, "%s must be a mapping ({type: ..., every: N, ...}), got %s", what,
                           sc_is_missing(e) ? "nothing" : sc_type_name(e));
        /* type: a built-in output or one registered by a plugin (read by its schema) */
        int type = -1;
        const char *tname;
        struct fy_node *tat;
        FLOE_TRY(sc_str(s, &m, "type", 1, NULL, &tname, &tat));
        for (int q = 0; sc_output_types[q]; q++)
            if (!strcmp(tname, sc_output_types[q])) type = q;
        const floe_registry_entry *ent = floe_registry_find(FLOE_KIND_OBSERVER, tname);
        if (!ent) {
            const char *names[128];
            int nn = 0;
            for (; nn < floe_registry_count(FLOE_KIND_OBSERVER) && nn < 128; nn++)
                names[nn] = floe_registry_at(FLOE_KIND_OBSERVER, nn)->name;
            char sug[1024];
            sc_suggest(sug, sizeof sug, tname, names, nn);
            return sc_fail(s, FLOE_EINVAL, tat, "%s.type: unknown value '%s'%s", what, tname, sug);
        }
        void *uparams = NULL; /* a registered output's parameters */
        if (type < 0) {
            char label[96];
            snprintf(label, sizeof label, "type %s", ent->name);
            uparams = calloc(1, ent->params_size);
            if (!uparams) return sc_fail(s, FLOE_ENOMEM, e, "out of memory");
            int rc = sc_read_schema(s, &m, ent, label, "type|every|interval|file", uparams);
            if (rc) { free(uparams); return rc; }
        } else {
            FLOE_TRY(sc_map_open(s, e, e, what, keys_all, &m));
            int nv = 0;
            while (keys_by_type[type][nv]) nv++;
            void *it2 = NULL;
            struct fy_node_pair *p;
            while ((p = fy_node_mapping_iterate(e, &it2))) {
                const char *ks = sc_text(fy_node_pair_key(p));
                int ok = 0;
                for (int j = 0; j < nv; j++) ok |= !strcmp(ks, keys_by_type[type][j]);
                if (!ok) {
                    char sug[512];
                    sc_suggest(sug, sizeof sug, ks, keys_by_type[type], nv);
                    return sc_fail(s, FLOE_EPARSE, fy_node_pair_key(p),
                                   "unknown key '%s' in %s (type %s)%s", ks, what,
                                   sc_output_types[type], sug);
                }
            }
        }
        sc_output *o = &s->outs[i];
        snprintf(o->type, sizeof o->type, "%s", tname);
        o->uparams = uparams; /* freed with the loader */
        o->ent = ent;
        char udefault[160];
        snprintf(udefault, sizeof udefault, "%s.csv", tname);
        if (sc_has(&m, "every") && sc_has(&m, "interval"))
            return sc_fail(s, FLOE_EPARSE, sc_get(&m, "interval", NULL),
                           "%s: give either every (steps) or interval (seconds), not both", what);
        FLOE_TRY(sc_long(s, &m, "every", 0, 100, &o->every));
        FLOE_TRY(sc_num(s, &m, "interval", 0, 0.0, &o->interval));
        if (sc_has(&m, "interval")) {
            if (!(o->interval > 0)) return sc_range(s, &m, "interval", "> 0 (s)", o->interval);
            /* the world steps next_time by interval until it passes t: an interval below the
             * time resolution would never get there */
            if (!(o->interval >= 1e-9 * s->duration))
                return sc_fail(s, FLOE_EINVAL, sc_get(&m, "interval", NULL),
                               "%s.interval %g s is below the time resolution of this run (1e-9 x "
                               "time.duration = %g s)", what, o->interval, 1e-9 * s->duration);
            o->every = 0;
        } else if (o->every < 1) {
            return sc_range(s, &m, "every", ">= 1 (steps)", (double)o->every);
        }
        const char *name;
        struct fy_node *name_at;
        /* a series of files named by a prefix (vtk, and registered outputs whose schema has
         * `prefix`, such as outlines), or one file */
        const int pk = type < 0 && ent ? floe_schema_index(ent, "prefix") : -1;
        const int by_prefix = type == 0 || pk >= 0;
        const char *defname = type == 0 ? defaults[0]
                              : pk >= 0  ? (ent->params[pk].def_text ? ent->params[pk].def_text : tname)
                              : type < 0 ? udefault
                                         : defaults[type];
        FLOE_TRY(sc_str(s, &m, by_prefix ? "prefix" : "file", 0, defname, &name, &name_at));
        if (!*name || (by_prefix && strchr(name, '/')))
            return sc_fail(s, FLOE_EINVAL, name_at, "%s.%s: '%s' is not a valid %s", what,
                           by_prefix ? "prefix" : "file", name, by_prefix ? "prefix" : "file name");
        if (by_prefix || name[0] != '/')
            snprintf(o->target, sizeof o->target, "%s/%s", outdir, name);
        else
            snprintf(o->target, sizeof o->target, "%s", name);
        /* two writers of one file would interleave and corrupt it */
        {
            const char *nm = name;
            while (nm[0] == '.' && nm[1] == '/') nm += 2;
            if (by_prefix || nm[0] != '/') snprintf(o->file, sizeof o->file, "%s/%s%s", outdir, nm, by_prefix ? ".pvd" : "");
            else snprintf(o->file, sizeof o->file, "%s", nm);
            o->name_at = name_at;
            for (int j = 0; j < i; j++) {
                if (strcmp(s->outs[j].file, o->file) != 0) continue;
                int l = 0, c = 0;
                struct fy_node *prev = s->outs[j].name_at ? s->outs[j].name_at
                                                          : fy_node_sequence_get_by_index(seq, j);
                sc_loc(s, prev, &l, &c);
                return sc_fail(s, FLOE_EINVAL, name_at ? name_at : e,
                               "%s writes %s, which outputs[%d] (line %d, column %d) writes too: give "
                               "each output its own %s", what, o->file, j, l, c,
                               by_prefix ? "prefix" : "file");
            }
        }

        long group = -1;
        double volume = 0;
        int ascii = 0;
        if (type == 0) FLOE_TRY(sc_bool(s, &m, "ascii", 0, &ascii));
        int *ids = NULL, nids = 0;
        if (type == 3) {
            struct fy_node *gk;
            struct fy_node *gv = sc_get(&m, "group", &gk);
            if (gv && !(sc_text(gv) && !strcmp(sc_text(gv), "all"))) {
                char f[64];
                snprintf(f, sizeof f, "%s.group", what);
                FLOE_TRY(sc_node_long(s, gv, gk, f, &group));
                if (group < 0 || group >= s->nbody_entries)
                    return sc_fail(s, FLOE_EINVAL, gv,
                                   "%s must be 'all' or a body index in [0, %d] (got %ld)", f,
                                   s->nbody_entries - 1, group);
            }
            FLOE_TRY(sc_num(s, &m, "volume", 0, 0.0, &volume));
            if (!(volume >= 0)) return sc_range(s, &m, "volume", ">= 0 (0 = bounding box)", volume);
        }
        if (type == 4) {
            /* particles: body particle ids; walls: wall indices (world id nparticles + i) */
            static const char *const lists[2] = {"particles", "walls"};
            struct fy_node *lv[2], *lk[2];
            int cnt[2] = {0, 0};
            for (int l = 0; l < 2; l++) {
                lv[l] = sc_get(&m, lists[l], &lk[l]);
                if (!lv[l]) continue;
                if (lv[l] == lk[l] || !fy_node_is_sequence(lv[l]) ||
                    fy_node_sequence_item_count(lv[l]) == 0)
                    return sc_fail(s, FLOE_EPARSE, lv[l] == lk[l] ? lk[l] : lv[l],
                                   "%s.%s: expected a non-empty list of %s", what, lists[l],
                                   l ? "wall indices" : "particle ids");
                cnt[l] = fy_node_sequence_item_count(lv[l]);
            }
            if (!lv[0] && !lv[1])
                return sc_fail(s, FLOE_EPARSE, e, "%s: give particles (a list of particle ids) "
                               "and/or walls (a list of wall indices)", what);
            ids = malloc((size_t)(cnt[0] + cnt[1]) * sizeof *ids);
            if (!ids) return sc_fail(s, FLOE_ENOMEM, e, "out of memory");
            for (int l = 0; l < 2; l++)
                for (int j = 0; j < cnt[l]; j++) {
                    struct fy_node *c = fy_node_sequence_get_by_index(lv[l], j);
                    char f2[96];
                    snprintf(f2, sizeof f2, "%s.%s[%d]", what, lists[l], j);
                    long id = -1;
                    long lim = l ? s->nwalls : s->nparticles;
                    int rc = sc_node_long(s, c, NULL, f2, &id);
                    if (rc == FLOE_OK && (id < 0 || id >= lim))
                        rc = sc_fail(s, FLOE_EINVAL, c, "%s: %s %ld does not exist (the scene has "
                                     "%ld %s, 0..%ld)", f2, l ? "wall" : "particle", id, lim,
                                     l ? "walls" : "particles", lim - 1);
                    if (rc != FLOE_OK) { free(ids); return rc; }
                    ids[nids++] = (int)(l ? s->nparticles + id : id);
                }
        }
        /* an MPI run's vtk outputs (floe_scene_set_vtk_mode): pieces opened alone, or left to them */
        const int open_it = with_outputs && (vtk_mode == FLOE_SCENE_VTK_SERIAL ||
                                             (vtk_mode == FLOE_SCENE_VTK_SKIP && type != 0) ||
                                             (vtk_mode == FLOE_SCENE_VTK_PIECES && type == 0));
        const int piece = type == 0 && vtk_mode == FLOE_SCENE_VTK_PIECES;
        if (open_it) {
            char oerr[512] = "";
            floe_observer *obs = NULL;
            if (type < 0) {
                floe_output_ctx octx = {outdir, o->target, s->w, s->dim};
                obs = ((floe_output_create_fn)ent->create)(uparams, &octx, oerr, sizeof oerr);
            }
            switch (type) {
            case 0:
                obs = piece ? floe_vtk_writer_create_piece(outdir, name, vtk_rank, vtk_size, oerr, sizeof oerr)
                            : floe_vtk_writer_create(outdir, name, oerr, sizeof oerr);
                if (obs && ascii) floe_vtk_writer_set_ascii(obs, 1);
                break;
            case 1: obs = floe_csv_writer_create(o->target, oerr, sizeof oerr); break;
            case 2: obs = floe_energy_tracker_create(o->target, oerr, sizeof oerr); break;
            case 3: obs = floe_collection_tracker_create(o->target, (int)group, volume, oerr,
                                                         sizeof oerr);
                break;
            case 4: obs = floe_particle_tracker_create(o->target, ids, nids, oerr, sizeof oerr); break;
            }
            free(ids);
            if (!obs)
                return sc_fail(s, FLOE_EIO, e, "%s (%s): %s", what, o->type,
                               oerr[0] ? oerr : "could not create the output");
            obs->period_steps = o->every;
            obs->period_time = o->every ? 0.0 : o->interval;
            if (piece) { /* handed over, not attached: the caller adds it to the split world */
                if (vtk_take(vtk_ctx, obs) != 0) return sc_fail(s, FLOE_ENOMEM, e, "%s: out of memory", what);
                s->nouts = ++i;
                s->nobservers = i;
                continue;
            }
            int rc = floe_world_add_observer(s->w, obs);
            if (rc != FLOE_OK) {
                floe_observer_destroy(obs);
                return sc_fail(s, rc < 0 ? -rc : rc, e, "%s: %s", what,
                               floe_world_last_error(s->w));
            }
        } else {
            free(ids);
        }
        s->nouts = ++i;
        s->nobservers = i;
    }
    return FLOE_OK;
}

/* ------------------------------------------------------------------------------------ */
/* Beam bonds (contact/bonds/floe_beam.h, issue #5): `bonds:` a list of bond sets, each bonding   */
/* the particles within a radius (floe_world_add_beam_bonds)                              */

int sc_parse_bonds(sc *s, struct fy_node *seq, struct fy_node *key)
{
    static const char *const keys[] = {"young", "poisson", "radius_factor", "max_distance", "timoshenko",
                                       "shear_coefficient", "area", "inertia", "polar", "section_modulus",
                                       "radius_ratio", "thickness", "damping_ratio", "tensile_strength",
                                       "tensile_sd", "shear_strength", "shear_sd", "compressive_strength",
                                       "compressive_sd", "friction_angle", "yield", "seed", "group", NULL};
    if (!seq) return FLOE_OK;
    if (sc_is_missing(seq) || !fy_node_is_sequence(seq))
        return sc_fail(s, FLOE_EPARSE, sc_is_missing(seq) ? key : seq,
                       "bonds must be a list of {young, radius_factor, ...} (beam bonds)");
    void *it = NULL;
    struct fy_node *e;
    for (int i = 0; (e = fy_node_sequence_iterate(seq, &it)); i++) {
        char what[32];
        snprintf(what, sizeof what, "bonds[%d]", i);
        sc_map m;
        FLOE_TRY(sc_map_open(s, e, e, what, keys, &m));
        floe_beam_params bp = floe_default_beam_params();
        double rf = 1.01;
        long seed = 1, group = 0;
        int has_group = sc_has(&m, "group");
        FLOE_TRY(sc_num(s, &m, "young", 1, 0, &bp.young));
        FLOE_TRY(sc_num(s, &m, "poisson", 0, bp.poisson, &bp.poisson));
        FLOE_TRY(sc_num(s, &m, "radius_factor", 0, rf, &rf));
        FLOE_TRY(sc_num(s, &m, "max_distance", 0, 0, &bp.max_distance));
        FLOE_TRY(sc_bool(s, &m, "timoshenko", 0, &bp.timoshenko));
        FLOE_TRY(sc_num(s, &m, "shear_coefficient", 0, 0, &bp.shear_coefficient));
        FLOE_TRY(sc_num(s, &m, "area", 0, 0, &bp.area));
        FLOE_TRY(sc_num(s, &m, "inertia", 0, 0, &bp.inertia));
        FLOE_TRY(sc_num(s, &m, "polar", 0, 0, &bp.polar));
        FLOE_TRY(sc_num(s, &m, "section_modulus", 0, 0, &bp.section_modulus));
        FLOE_TRY(sc_num(s, &m, "radius_ratio", 0, bp.radius_ratio, &bp.radius_ratio));
        FLOE_TRY(sc_num(s, &m, "thickness", 0, bp.thickness, &bp.thickness));
        FLOE_TRY(sc_num(s, &m, "damping_ratio", 0, 0, &bp.damping_ratio));
        FLOE_TRY(sc_num(s, &m, "tensile_strength", 0, 0, &bp.tensile_strength));
        FLOE_TRY(sc_num(s, &m, "tensile_sd", 0, 0, &bp.tensile_sd));
        FLOE_TRY(sc_num(s, &m, "shear_strength", 0, 0, &bp.shear_strength));
        FLOE_TRY(sc_num(s, &m, "shear_sd", 0, 0, &bp.shear_sd));
        FLOE_TRY(sc_num(s, &m, "compressive_strength", 0, 0, &bp.compressive_strength));
        FLOE_TRY(sc_num(s, &m, "compressive_sd", 0, 0, &bp.compressive_sd));
        FLOE_TRY(sc_num(s, &m, "friction_angle", 0, 0, &bp.friction_angle));
        static const char *const yields[] = {"limits", "ellipse", NULL};
        FLOE_TRY(sc_enum(s, &m, "yield", yields, FLOE_BEAM_YIELD_LIMITS, &bp.yield));
        FLOE_TRY(sc_long(s, &m, "seed", 0, 1, &seed));
        FLOE_TRY(sc_long(s, &m, "group", 0, 0, &group));
        if (seed < 0) return sc_range(s, &m, "seed", ">= 0", (double)seed);
        bp.seed = (unsigned long long)seed;
        bp.group = has_group ? (int)group : FLOE_BEAM_ALL_GROUPS;
        if (!(rf > 0)) return sc_range(s, &m, "radius_factor", "> 0", rf);
        int rc = floe_world_add_beam_bonds(s->w, rf, &bp);
        if (rc < 0) return sc_fail(s, -rc, e, "%s: %s", what, floe_world_last_error(s->w));
        if (rc == 0)
            return sc_fail(s, FLOE_EINVAL, e, "%s: no pair of particles is within reach (radius_factor %g x (R_i + R_j)%s)",
                           what, rf, bp.max_distance > 0 ? " or max_distance" : "");
    }
    return FLOE_OK;
}
