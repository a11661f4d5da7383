/* file_writer.h - the one file writer of the observers (internal: not installed).
 *
 * Row files (CSV): floe_fw_open creates (truncates) the file and writes its header line;
 * an observation formats its rows whole into a buffer (floe_fw_row) and floe_fw_flush
 * writes them at the end of the observation, so that a run killed at any instant (SIGKILL)
 * keeps every row it flushed and leaves no partial row:
 *   - nothing reaches the file while rows are being formatted;
 *   - Linux copies a write() into the page cache page by page (folio by folio) and, when
 *     the process is killed, stops between two pages: a long write can be cut at any
 *     multiple of 4096 bytes of the file (measured: one write per observation of 85 kB CSV
 *     frames, killed at random instants, ended inside a row in 3 runs of 40). So the rows
 *     go out in writes that each stay inside one 4096-byte page of the file (whole rows;
 *     all or nothing), and a row that crosses a page boundary goes alone in its own write;
 *     a kill between two writes cuts between two rows.
 * What remains: a kill that lands inside the write() of a row crossing a page boundary,
 * after its first page and before its second (a fraction of a microsecond per 4 kB written).
 * A killed run may end with an incomplete last observation (whole rows, not all of them).
 * floe_fw_close closes the file; a later row (a run continued after finish) reopens it in
 * append mode.
 *
 * Whole files (VTK frames, the .pvd collection): floe_fw_replace_begin opens PATH.tmp,
 * floe_fw_replace_commit closes it and renames it onto PATH, so that PATH is at every
 * instant either absent, its previous complete version, or the new complete one.
 *
 * VTK XML series (the vtk and outlines outputs): frame and collection names, the .pvd, the
 * opening of a .vtu and ASCII data arrays, below.
 *
 * Errors are reported through the world (floe_world_report_error), each message beginning
 * with the writer's name (`who`) and naming the path and the errno text. */
#ifndef FILE_WRITER_H
#define FILE_WRITER_H

#include "floe_view.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

typedef struct floe_file_writer {
    const char *who;   /* "particle tracker": the start of every message (a literal) */
    char *path;
    int fd;            /* -1 when closed */
    char *buf;         /* pending rows of this observation */
    size_t len, cap;
    long long offset;  /* the file's size (where the next write goes) */
    int nomem;         /* a row did not fit in memory: the flush fails */
    int held;          /* opened for a restart (floe_outputs_keep_existing): rows are dropped
                          until the checkpoint's restore (floe_fw_resume) */
} floe_file_writer;

/* Creates (truncates) path and writes header (a whole line, with its newline). FLOE_OK, or
 * FLOE_EIO / FLOE_ENOMEM with "WHO: cannot open PATH: errno text" (or "cannot write") in err. */
int floe_fw_open(floe_file_writer *fw, const char *who, const char *path, const char *header,
                 char *err, size_t errlen);
/* Appends one formatted row (the caller ends it with "\n") to the pending rows. */
void floe_fw_row(floe_file_writer *fw, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* Drops the pending rows (an observation refused after some rows were formatted). */
void floe_fw_discard(floe_file_writer *fw);
/* Writes the pending rows (page by page, as above; reopening the file in append mode if it
 * was closed); FLOE_OK, or FLOE_EIO / FLOE_ENOMEM reported through w. The pending rows are
 * dropped either way. */
int floe_fw_flush(floe_file_writer *fw, floe_world *w);
/* Flushes what is pending and closes the file (a no-op when closed). */
int floe_fw_close(floe_file_writer *fw, floe_world *w);
/* Frees everything (closes without reporting). */
void floe_fw_free(floe_file_writer *fw);
/* The length of the next write of the n pending bytes at p (whole rows), at file offset
 * off: all of them when they end inside the 4096-byte page of off; otherwise the whole rows
 * that end inside it or, when the first row crosses the page boundary, that row alone. */
size_t floe_fw_next_write(const char *p, size_t n, long long off);

/* A whole file written under a temporary name and renamed into place. */
typedef struct floe_fw_replace {
    FILE *f;           /* write the content here */
    char *path, *tmp;
} floe_fw_replace;

/* Opens path + ".tmp" for writing (binary). FLOE_OK, or FLOE_ENOMEM / FLOE_EIO with errno
 * set; on failure nothing is left to abandon. */
int floe_fw_replace_begin(floe_fw_replace *r, const char *path);
/* Closes the temporary file and renames it onto the path; on failure (a write or close
 * error, errno set) the temporary file is removed and FLOE_EIO returned. Frees r's names. */
int floe_fw_replace_commit(floe_fw_replace *r);
/* Closes and removes the temporary file (a frame refused half-written). Frees r's names. */
void floe_fw_replace_abandon(floe_fw_replace *r);

/* ---- VTK XML series (the vtk and outlines outputs) ----
 * A series is DIR/PREFIX_NNNNNN.vtu per frame and DIR/PREFIX.pvd listing them, each written
 * through floe_fw_replace_* (the .pvd rewritten after every frame, so that it lists only
 * complete frames). */
typedef enum floe_fw_vtk_type { FLOE_FW_INT32, FLOE_FW_FLOAT64, FLOE_FW_INT64, FLOE_FW_UINT8 } floe_fw_vtk_type;
/* "Int32", "Float64", "Int64", "UInt8" */
const char *floe_fw_vtk_type_name(floe_fw_vtk_type t);
/* bytes of one value: 4, 8, 8, 1 */
size_t floe_fw_vtk_type_size(floe_fw_vtk_type t);
/* "LittleEndian" or "BigEndian": this machine's byte order, as a VTKFile declares it */
const char *floe_fw_vtk_byte_order(void);
/* malloc'd (NULL: out of memory) "DIR/PREFIX_NNNNNN" + suffix for frame >= 0, else
 * "DIR/PREFIX" + suffix; dir NULL: without "DIR/" (the name a .pvd gives) */
char *floe_fw_series_path(const char *dir, const char *prefix, int frame, const char *suffix);
/* Writes DIR/PREFIX.pvd listing frames 0..frames-1 at times[] (s). FLOE_OK, or FLOE_ENOMEM /
 * FLOE_EIO with errno set. */
int floe_fw_write_pvd(const char *dir, const char *prefix, const double *times, int frames);
/* the same with frame files PREFIX_NNNNNN + suffix (".pvtu": a series of parallel frames) */
int floe_fw_write_pvd_as(const char *dir, const char *prefix, const double *times, int frames, const char *suffix);
/* A series being written: frames opened with floe_fw_series_begin (the next frame's
 * PREFIX_NNNNNN.vtu.tmp; r->f to write it), then floe_fw_series_commit (renamed into place,
 * its time recorded, the .pvd rewritten) or floe_fw_series_abandon. Errors are reported
 * through the world with `who`. floe_fw_series_due: this step is not written yet. */
typedef struct floe_fw_series {
    const char *who;   /* "vtk writer": the start of every message (a literal) */
    char *dir, *prefix;
    double *times;     /* the frames' times (s) */
    int frames, cap;
    long last_step;    /* the step of the last frame */
    int observed;      /* a frame was written */
    char *path;        /* the frame being written */
    int held;          /* created for a restart: frames are dropped until the restore */
} floe_fw_series;
/* strdup's dir and prefix; FLOE_ENOMEM (and nothing held) when out of memory */
int floe_fw_series_init(floe_fw_series *s, const char *who, const char *dir, const char *prefix);
void floe_fw_series_free(floe_fw_series *s);
int floe_fw_series_due(const floe_fw_series *s, long step);
int floe_fw_series_begin(floe_fw_series *s, floe_world *w, floe_fw_replace *r);
int floe_fw_series_commit(floe_fw_series *s, floe_world *w, floe_fw_replace *r, double time, long step);
void floe_fw_series_abandon(floe_fw_series *s, floe_fw_replace *r);
/* The opening of a .vtu up to its <Piece>: the XML declaration, VTKFile (UnstructuredGrid,
 * header_type UInt64, this machine's byte order) and the field data TimeValue (s; ParaView
 * reads it as the time of a single file) and Step. */
void floe_fw_vtu_begin(FILE *f, double time, long step);
/* m tuples of ncomp values of type t at buf as the text of an ASCII DataArray, one tuple a
 * line (Float64 with 17 significant digits: read back exactly). */
void floe_fw_vtk_ascii_values(FILE *f, floe_fw_vtk_type t, int ncomp, int m, const void *buf);

/* ---- checkpoints (docs/checkpoints.md; the observers' state hooks, floe_observer_base.h) ----
 * While floe_outputs_keep_existing(1) is in force (floe_checkpoint.h: a restart loading
 * its scene), floe_fw_open opens the file without truncating it or writing the header, and
 * a series is created held: what the observers write before the checkpoint's restore (the
 * scene loader's first observation) is dropped, so a refused restart changes no file; the
 * observer's restore then cuts the file back to its length at the checkpoint
 * (floe_fw_resume), refusing a file shorter than that (changed or removed since). The usual state of a row
 * file: its length, the step of the last row block and whether one was written; of a
 * series: the frames' times and the last frame's step (the .pvd is rewritten). Each save
 * returns the end of what it wrote, each restore reads as much from buf. */
size_t floe_fw_state_size(void);
unsigned char *floe_fw_state_save(const floe_file_writer *fw, long last_step, int observed, unsigned char *buf);
int floe_fw_state_restore(floe_file_writer *fw, floe_world *w, long *last_step, int *observed,
                          const unsigned char *buf);
int floe_fw_resume(floe_file_writer *fw, floe_world *w, long long length);
size_t floe_fw_series_state_size(const floe_fw_series *s);
unsigned char *floe_fw_series_state_save(const floe_fw_series *s, unsigned char *buf);
int floe_fw_series_state_restore(floe_fw_series *s, floe_world *w, const unsigned char *buf, size_t n);
/* the same with the collection's frames named by suffix (".vtu", ".pvtu"); pvd: 0 the .pvd
 * left alone, 1 rewritten when there are frames, 2 always */
int floe_fw_series_state_restore_as(floe_fw_series *s, floe_world *w, const unsigned char *buf, size_t n,
                                    const char *suffix, int pvd);
/* bytes in and out of a state buffer; each returns the position after them */
static inline unsigned char *floe_fw_put(unsigned char *buf, const void *p, size_t n) {
    memcpy(buf, p, n);
    return buf + n;
}
static inline const unsigned char *floe_fw_get(const unsigned char *buf, void *p, size_t n) {
    memcpy(p, buf, n);
    return buf + n;
}

#endif
