/* file_writer.c - the observers' file writer (file_writer.h): CSV rows formatted whole and
 * written at the end of the observation in writes that never cut a row at a page boundary;
 * whole files through a temporary name and rename. */
#include "file_writer.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
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
