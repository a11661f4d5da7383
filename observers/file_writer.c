/* file_writer.c - the observers' file writer (file_writer.h): CSV rows formatted whole and
 * written at the end of the observation in writes that never cut a row at a page boundary;
 * whole files through a temporary name and rename; the parts of a VTK XML series that the
 * vtk and outlines outputs share. */
#include "file_writer.h"
#include "floe_checkpoint.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

enum { FW_INITIAL_CAP = 4096 };
/* Linux copies a write() into the page cache one page (folio) at a time and stops between
 * two when the process is killed; a write that stays inside one page is all or nothing.
 * Every folio boundary is a multiple of 4096 bytes. */
#define FW_PAGE ((size_t)4096)

static char *dup_str(const char *s) {
    char *d = malloc(strlen(s) + 1);
    if (d) strcpy(d, s);
    return d;
}

/* write all n bytes (retrying short writes and EINTR); 0, or -1 with errno set */
static int write_all(int fd, const char *p, size_t n) {
    while (n > 0) {
        ssize_t k = write(fd, p, n);
        if (k < 0) {
            if (errno == EINTR) continue;
            return -1;
        }
        if (k == 0) {
            errno = EIO;
            return -1;
        }
        p += k;
        n -= (size_t)k;
    }
    return 0;
}

/* floe_outputs_keep_existing (floe_checkpoint.h): files opened from now on in this thread
 * keep their content (a restart) */
static _Thread_local int keep_existing;
void floe_outputs_keep_existing(int on) { keep_existing = on != 0; }

int floe_fw_open(floe_file_writer *fw, const char *who, const char *path, const char *header,
                 char *err, size_t errlen) {
    memset(fw, 0, sizeof *fw);
    fw->who = who;
    fw->fd = -1;
    fw->path = dup_str(path);
    fw->buf = malloc(FW_INITIAL_CAP);
    fw->cap = FW_INITIAL_CAP;
    if (!fw->path || !fw->buf) {
        if (err && errlen) snprintf(err, errlen, "%s: out of memory", who);
        floe_fw_free(fw);
        return FLOE_ENOMEM;
    }
    if (keep_existing) { /* a restart: nothing written until the restore cuts the file back */
        fw->held = 1;
        return FLOE_OK;
    }
    fw->fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    fw->offset = (long long)strlen(header);
    if (fw->fd < 0 || write_all(fw->fd, header, strlen(header)) != 0) {
        if (err && errlen)
            snprintf(err, errlen, "%s: cannot %s %s: %s", who, fw->fd < 0 ? "open" : "write", path, strerror(errno));
        floe_fw_free(fw);
        return FLOE_EIO;
    }
    return FLOE_OK;
}

void floe_fw_row(floe_file_writer *fw, const char *fmt, ...) {
    if (fw->nomem) return;
    for (;;) {
        size_t room = fw->cap - fw->len;
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(fw->buf + fw->len, room, fmt, ap);
        va_end(ap);
        if (n < 0) { /* cannot happen with the observers' formats */
            fw->nomem = 1;
            return;
        }
        if ((size_t)n < room) {
            fw->len += (size_t)n;
            return;
        }
        size_t cap = 2 * fw->cap;
        if (cap < fw->len + (size_t)n + 1) cap = fw->len + (size_t)n + 1;
        char *b = realloc(fw->buf, cap);
        if (!b) {
            fw->nomem = 1;
            return;
        }
        fw->buf = b;
        fw->cap = cap;
    }
}

void floe_fw_discard(floe_file_writer *fw) {
    fw->len = 0;
    fw->nomem = 0;
}

size_t floe_fw_next_write(const char *p, size_t n, long long off) {
    size_t room = FW_PAGE - (size_t)(off % FW_PAGE);
    if (n <= room) return n;
    size_t k = room;
    while (k > 0 && p[k - 1] != '\n') k--;
    if (k > 0) return k;
    const char *nl = memchr(p, '\n', n);
    return nl ? (size_t)(nl - p) + 1 : n;
}

int floe_fw_flush(floe_file_writer *fw, floe_world *w) {
    if (fw->held) {
        floe_fw_discard(fw);
        return FLOE_OK;
    }
    if (fw->nomem) {
        floe_fw_discard(fw);
        return floe_world_report_error(w, FLOE_ENOMEM, "%s: out of memory formatting rows for %s",
                                       fw->who, fw->path);
    }
    if (fw->len == 0) return FLOE_OK;
    if (fw->fd < 0) {
        fw->fd = open(fw->path, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0666);
        off_t end = fw->fd >= 0 ? lseek(fw->fd, 0, SEEK_END) : -1;
        if (end < 0) {
            int e = errno;
            if (fw->fd >= 0) close(fw->fd);
            fw->fd = -1;
            floe_fw_discard(fw);
            return floe_world_report_error(w, FLOE_EIO, "%s: cannot reopen %s: %s", fw->who, fw->path,
                                           strerror(e));
        }
        fw->offset = (long long)end;
    }
    const char *p = fw->buf;
    size_t left = fw->len;
    int bad = 0;
    while (left > 0 && !bad) {
        size_t n = floe_fw_next_write(p, left, fw->offset);
        bad = write_all(fw->fd, p, n);
        p += n;
        left -= n;
        fw->offset += (long long)n;
    }
    floe_fw_discard(fw);
    if (bad)
        return floe_world_report_error(w, FLOE_EIO, "%s: write to %s failed: %s", fw->who, fw->path,
                                       strerror(errno));
    return FLOE_OK;
}

int floe_fw_close(floe_file_writer *fw, floe_world *w) {
    int rc = floe_fw_flush(fw, w);
    if (fw->fd >= 0) {
        if (close(fw->fd) != 0 && rc == FLOE_OK)
            rc = floe_world_report_error(w, FLOE_EIO, "%s: closing %s failed: %s", fw->who, fw->path,
                                         strerror(errno));
        fw->fd = -1;
    }
    return rc;
}

void floe_fw_free(floe_file_writer *fw) {
    if (fw->fd >= 0) close(fw->fd);
    fw->fd = -1;
    free(fw->path);
    free(fw->buf);
    fw->path = NULL;
    fw->buf = NULL;
    fw->len = fw->cap = 0;
}

/* ---- whole files: temporary name, then rename ---- */

static void replace_free(floe_fw_replace *r) {
    free(r->path);
    free(r->tmp);
    r->path = r->tmp = NULL;
    r->f = NULL;
}

int floe_fw_replace_begin(floe_fw_replace *r, const char *path) {
    r->f = NULL;
    r->path = dup_str(path);
    r->tmp = malloc(strlen(path) + sizeof ".tmp");
    if (!r->path || !r->tmp) {
        replace_free(r);
        errno = ENOMEM;
        return FLOE_ENOMEM;
    }
    strcpy(r->tmp, path);
    strcat(r->tmp, ".tmp");
    r->f = fopen(r->tmp, "wb");
    if (!r->f) {
        int e = errno;
        replace_free(r);
        errno = e;
        return FLOE_EIO;
    }
    return FLOE_OK;
}

int floe_fw_replace_commit(floe_fw_replace *r) {
    int bad = ferror(r->f) ? EIO : 0;
    if (fclose(r->f) != 0 && !bad) bad = errno ? errno : EIO;
    if (!bad && rename(r->tmp, r->path) != 0) bad = errno;
    if (bad) remove(r->tmp);
    replace_free(r);
    errno = bad;
    return bad ? FLOE_EIO : FLOE_OK;
}

void floe_fw_replace_abandon(floe_fw_replace *r) {
    if (r->f) fclose(r->f);
    if (r->tmp) remove(r->tmp);
    replace_free(r);
}

/* ---- VTK XML series ---- */

const char *floe_fw_vtk_type_name(floe_fw_vtk_type t) {
    switch (t) {
    case FLOE_FW_INT32: return "Int32";
    case FLOE_FW_FLOAT64: return "Float64";
    case FLOE_FW_INT64: return "Int64";
    default: return "UInt8";
    }
}

size_t floe_fw_vtk_type_size(floe_fw_vtk_type t) {
    switch (t) {
    case FLOE_FW_INT32: return 4;
    case FLOE_FW_FLOAT64: return 8;
    case FLOE_FW_INT64: return 8;
    default: return 1;
    }
}

const char *floe_fw_vtk_byte_order(void) {
    const uint16_t one = 1;
    unsigned char c;
    memcpy(&c, &one, 1);
    return c == 1 ? "LittleEndian" : "BigEndian";
}

char *floe_fw_series_path(const char *dir, const char *prefix, int frame, const char *suffix) {
    size_t len = (dir ? strlen(dir) : 0) + strlen(prefix) + strlen(suffix) + 32;
    char *s = malloc(len);
    if (!s) return NULL;
    const char *d = dir ? dir : "";
    const char *sep = dir ? "/" : "";
    if (frame >= 0)
        snprintf(s, len, "%s%s%s_%06d%s", d, sep, prefix, frame, suffix);
    else
        snprintf(s, len, "%s%s%s%s", d, sep, prefix, suffix);
    return s;
}

static void write_xml_attr(FILE *f, const char *s) {
    for (; *s; s++) {
        switch (*s) {
        case '&': fputs("&amp;", f); break;
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '"': fputs("&quot;", f); break;
        case '\'': fputs("&apos;", f); break;
        default: fputc(*s, f);
        }
    }
}

int floe_fw_write_pvd(const char *dir, const char *prefix, const double *times, int frames) {
    return floe_fw_write_pvd_as(dir, prefix, times, frames, ".vtu");
}

int floe_fw_write_pvd_as(const char *dir, const char *prefix, const double *times, int frames, const char *suffix) {
    if (keep_existing && frames == 0) return FLOE_OK; /* a restart's new series: the restore writes it */
    char *path = floe_fw_series_path(dir, prefix, -1, ".pvd");
    if (!path) {
        errno = ENOMEM;
        return FLOE_ENOMEM;
    }
    floe_fw_replace r;
    int rc = floe_fw_replace_begin(&r, path);
    free(path);
    if (rc != FLOE_OK) return rc;
    FILE *f = r.f;
    fprintf(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" "
               "byte_order=\"%s\">\n  <Collection>\n", floe_fw_vtk_byte_order());
    for (int k = 0; k < frames; k++) {
        char *name = floe_fw_series_path(NULL, prefix, k, suffix);
        if (!name) {
            floe_fw_replace_abandon(&r);
            errno = ENOMEM;
            return FLOE_ENOMEM;
        }
        fprintf(f, "    <DataSet timestep=\"%.17g\" group=\"\" part=\"0\" file=\"", times[k]);
        write_xml_attr(f, name);
        fputs("\"/>\n", f);
        free(name);
    }
    fputs("  </Collection>\n</VTKFile>\n", f);
    return floe_fw_replace_commit(&r);
}

int floe_fw_series_init(floe_fw_series *s, const char *who, const char *dir, const char *prefix) {
    memset(s, 0, sizeof *s);
    s->who = who;
    s->held = keep_existing;
    s->dir = strdup(dir);
    s->prefix = strdup(prefix);
    if (s->dir && s->prefix) return FLOE_OK;
    floe_fw_series_free(s);
    return FLOE_ENOMEM;
}

void floe_fw_series_free(floe_fw_series *s) {
    free(s->dir);
    free(s->prefix);
    free(s->times);
    free(s->path);
    memset(s, 0, sizeof *s);
}

int floe_fw_series_due(const floe_fw_series *s, long step) { return !s->observed || s->last_step != step; }

int floe_fw_series_begin(floe_fw_series *s, floe_world *w, floe_fw_replace *r) {
    if (s->frames == s->cap) {
        int nc = s->cap ? 2 * s->cap : 64;
        double *t = realloc(s->times, (size_t)nc * sizeof *t);
        if (!t) return floe_world_report_error(w, FLOE_ENOMEM, "%s: out of memory", s->who);
        s->times = t;
        s->cap = nc;
    }
    free(s->path);
    s->path = floe_fw_series_path(s->dir, s->prefix, s->frames, ".vtu");
    if (!s->path) return floe_world_report_error(w, FLOE_ENOMEM, "%s: out of memory", s->who);
    int rc = floe_fw_replace_begin(r, s->path);
    if (rc != FLOE_OK)
        return floe_world_report_error(w, rc, "%s: cannot open %s.tmp: %s", s->who, s->path, strerror(errno));
    return FLOE_OK;
}

int floe_fw_series_commit(floe_fw_series *s, floe_world *w, floe_fw_replace *r, double time, long step) {
    if (s->held) { /* a restart before its restore: the frame is dropped */
        floe_fw_replace_abandon(r);
        return FLOE_OK;
    }
    int rc = floe_fw_replace_commit(r);
    if (rc != FLOE_OK)
        return floe_world_report_error(w, rc, "%s: writing %s failed: %s", s->who, s->path, strerror(errno));
    s->times[s->frames++] = time;
    s->last_step = step;
    s->observed = 1;
    rc = floe_fw_write_pvd(s->dir, s->prefix, s->times, s->frames);
    if (rc != FLOE_OK)
        return floe_world_report_error(w, rc, "%s: writing %s/%s.pvd failed: %s", s->who, s->dir, s->prefix,
                                       rc == FLOE_ENOMEM ? "out of memory" : strerror(errno));
    return FLOE_OK;
}

void floe_fw_series_abandon(floe_fw_series *s, floe_fw_replace *r) {
    (void)s;
    floe_fw_replace_abandon(r);
}

void floe_fw_vtu_begin(FILE *f, double time, long step) {
    fprintf(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
               "byte_order=\"%s\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n", floe_fw_vtk_byte_order());
    fprintf(f, "    <FieldData>\n"
               "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" "
               "format=\"ascii\">%.17g</DataArray>\n"
               "      <DataArray type=\"Int64\" Name=\"Step\" NumberOfTuples=\"1\" "
               "format=\"ascii\">%ld</DataArray>\n    </FieldData>\n",
            time, step);
}

void floe_fw_vtk_ascii_values(FILE *f, floe_fw_vtk_type t, int ncomp, int m, const void *buf) {
    const int32_t *i32 = buf;
    const int64_t *i64 = buf;
    const double *f64 = buf;
    const uint8_t *u8 = buf;
    for (int a = 0; a < m; a++) {
        fputs("          ", f);
        for (int c = 0; c < ncomp; c++) {
            size_t e = (size_t)a * ncomp + c;
            if (c) fputc(' ', f);
            switch (t) {
            case FLOE_FW_INT32: fprintf(f, "%ld", (long)i32[e]); break;
            case FLOE_FW_INT64: fprintf(f, "%lld", (long long)i64[e]); break;
            case FLOE_FW_UINT8: fprintf(f, "%u", (unsigned)u8[e]); break;
            default: fprintf(f, "%.17g", f64[e]); break;
            }
        }
        fputc('\n', f);
    }
}

/* ---- checkpoints ---- */

size_t floe_fw_state_size(void) { return sizeof(long long) + sizeof(long) + sizeof(int); }

unsigned char *floe_fw_state_save(const floe_file_writer *fw, long last_step, int observed, unsigned char *buf) {
    buf = floe_fw_put(buf, &fw->offset, sizeof fw->offset);
    buf = floe_fw_put(buf, &last_step, sizeof last_step);
    return floe_fw_put(buf, &observed, sizeof observed);
}

int floe_fw_state_restore(floe_file_writer *fw, floe_world *w, long *last_step, int *observed,
                          const unsigned char *buf) {
    long long len;
    buf = floe_fw_get(buf, &len, sizeof len);
    buf = floe_fw_get(buf, last_step, sizeof *last_step);
    floe_fw_get(buf, observed, sizeof *observed);
    return floe_fw_resume(fw, w, len);
}

int floe_fw_resume(floe_file_writer *fw, floe_world *w, long long length) {
    if (fw->fd < 0) fw->fd = open(fw->path, O_WRONLY | O_CLOEXEC);
    struct stat st;
    if (fw->fd < 0 && errno == ENOENT)
        return floe_world_report_error(w, FLOE_EINVAL, "%s: %s is missing: it had %lld bytes at the checkpoint; the "
                                       "run cannot continue it (restart with the output directory of the run that "
                                       "wrote the checkpoint)", fw->who, fw->path, length);
    if (fw->fd < 0 || fstat(fw->fd, &st) != 0)
        return floe_world_report_error(w, FLOE_EIO, "%s: cannot reopen %s: %s", fw->who, fw->path, strerror(errno));
    if ((long long)st.st_size < length)
        return floe_world_report_error(w, FLOE_EINVAL, "%s: %s has %lld bytes, fewer than the %lld it had at the "
                                       "checkpoint: it was changed or removed since, the run cannot continue it "
                                       "(restart with the output directory of the run that wrote the checkpoint)",
                                       fw->who, fw->path, (long long)st.st_size, length);
    if (ftruncate(fw->fd, (off_t)length) != 0 || lseek(fw->fd, (off_t)length, SEEK_SET) < 0)
        return floe_world_report_error(w, FLOE_EIO, "%s: cannot cut %s back to %lld bytes: %s", fw->who, fw->path,
                                       length, strerror(errno));
    fw->offset = length;
    fw->held = 0;
    floe_fw_discard(fw);
    return FLOE_OK;
}

size_t floe_fw_series_state_size(const floe_fw_series *s) {
    return sizeof(int) + sizeof(long) + sizeof(int) + (size_t)s->frames * sizeof(double);
}

unsigned char *floe_fw_series_state_save(const floe_fw_series *s, unsigned char *buf) {
    buf = floe_fw_put(buf, &s->frames, sizeof s->frames);
    buf = floe_fw_put(buf, &s->last_step, sizeof s->last_step);
    buf = floe_fw_put(buf, &s->observed, sizeof s->observed);
    return s->frames ? floe_fw_put(buf, s->times, (size_t)s->frames * sizeof(double)) : buf;
}

int floe_fw_series_state_restore(floe_fw_series *s, floe_world *w, const unsigned char *buf, size_t n) {
    return floe_fw_series_state_restore_as(s, w, buf, n, ".vtu", 1);
}

int floe_fw_series_state_restore_as(floe_fw_series *s, floe_world *w, const unsigned char *buf, size_t n,
                                    const char *suffix, int pvd) {
    int frames;
    if (n < sizeof(int)) return floe_world_report_error(w, FLOE_EINVAL, "%s: checkpoint state too short", s->who);
    floe_fw_get(buf, &frames, sizeof frames);
    if (frames < 0 || n < sizeof(int) + sizeof(long) + sizeof(int) + (size_t)frames * sizeof(double))
        return floe_world_report_error(w, FLOE_EINVAL, "%s: checkpoint state does not match", s->who);
    if (frames > s->cap) {
        double *t = realloc(s->times, (size_t)frames * sizeof *t);
        if (!t) return floe_world_report_error(w, FLOE_ENOMEM, "%s: out of memory", s->who);
        s->times = t;
        s->cap = frames;
    }
    buf += sizeof frames;
    buf = floe_fw_get(buf, &s->last_step, sizeof s->last_step);
    buf = floe_fw_get(buf, &s->observed, sizeof s->observed);
    if (frames) floe_fw_get(buf, s->times, (size_t)frames * sizeof(double));
    s->frames = frames;
    s->held = 0;
    /* the collection as it was at the checkpoint (frames written after it are written again) */
    if ((pvd == 2 || (pvd == 1 && frames > 0)) &&
        floe_fw_write_pvd_as(s->dir, s->prefix, s->times, s->frames, suffix) != FLOE_OK)
        return floe_world_report_error(w, FLOE_EIO, "%s: writing %s/%s.pvd failed: %s", s->who, s->dir, s->prefix,
                                       strerror(errno));
    return FLOE_OK;
}
