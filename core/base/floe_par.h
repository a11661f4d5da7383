/* floe_par.h - threads (OpenMP, issue 14; docs/parallel.md). Every threaded loop in floe
 * gives the same bits for any number of threads: sums are taken over blocks of a fixed size
 * (FLOE_PAR_BLOCK items, independent of the thread count) and the blocks' partial sums added
 * in block order, also in a serial run; forces of pairs and bonds go to a per-pair buffer and
 * each particle gathers them in the order a serial loop would add them. Without OpenMP
 * (FLOE_WITH_OPENMP=OFF) the pragmas vanish and the same code runs on one thread. */
#ifndef FLOE_PAR_H
#define FLOE_PAR_H
#include "floe_base.h"

#ifdef _OPENMP
#include <omp.h>
#define FLOE_OMP(x) _Pragma(#x)
static inline int floe_par_max_threads(void) { return omp_get_max_threads(); }
static inline int floe_par_thread(void) { return omp_get_thread_num(); }
static inline int floe_par_nthreads(void) { return omp_get_num_threads(); }
static inline double floe_par_wtime(void) { return omp_get_wtime(); } /* seconds, for balancing */
#else
#define FLOE_OMP(x)
static inline int floe_par_max_threads(void) { return 1; }
static inline int floe_par_thread(void) { return 0; }
static inline int floe_par_nthreads(void) { return 1; }
static inline double floe_par_wtime(void) { return 0.0; }
#endif

/* why a thread count is refused (NULL: taken; *code the FLOE_E* code to return): the world's
 * and the Newmark solver's set_threads */
static inline const char *floe_par_threads_refused(int nthreads, int *code) {
    if (nthreads < 0) {
        *code = FLOE_EINVAL;
        return "(0 for OpenMP's default, or >= 1)";
    }
#ifndef _OPENMP
    if (nthreads > 1) {
        *code = FLOE_ENOTSUP;
        return "asked, but floe was built without OpenMP (configure with -DFLOE_WITH_OPENMP=ON)";
    }
#endif
    (void)code;
    return 0;
}

/* items (particles, pairs) per reduction block: fixed, so that the partial sums and their
 * order do not depend on the thread count */
#define FLOE_PAR_BLOCK 512

/* the first of the n sorted values a[] that is >= v (n if none) */
static inline int floe_int_lower(const int *a, int n, int v) {
    int lo = 0, hi = n;
    while (lo < hi) {
        const int mid = lo + (hi - lo) / 2;
        if (a[mid] < v) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* the rows [i0, i1) of a list of np entries sorted by their first particles pi (a thread's
 * run of them): row[i] the first entry with pi >= i (np if none). Each particle's entries
 * stored backwards (the last store is its first entry), then the empty rows from the next
 * one's start: no branch per entry (a loop that stepped the entries per particle mispredicted
 * one at each row's end: 90 us a dem-settle list on one thread) */
static inline void floe_list_rows(const int *pi, int np, int i0, int i1, int *row) {
    const int e0 = floe_int_lower(pi, np, i0), e1 = floe_int_lower(pi, np, i1);
    for (int i = i0; i < i1; i++) row[i] = -1;
    for (int k = e1 - 1; k >= e0; k--) row[pi[k]] = k;
    for (int i = i1 - 1, next = e1; i >= i0; i--) {
        row[i] = row[i] < 0 ? next : row[i];
        next = row[i];
    }
}

#endif
