/* kdtree.c - static balanced k-d tree (floe_kdtree.h), a C rendering of nanoflann's
 * KDTreeSingleIndexAdaptor (J. L. Blanco, nanoflann 1.4, after FLANN by Muja & Lowe):
 *  - build: index permutation vind; each node is split at the midpoint of the widest
 *    dimension of its points' bounding box, clamped to their range, with nanoflann's
 *    tie rule (middleSplit_ + planeSplit); leaves hold up to leaf_size points;
 *  - search: nanoflann's incremental squared distance from the query to the node box,
 *    kept per dimension in a small vector ("dists"), so a far child is pruned without
 *    touching its points.
 * Differences from nanoflann, all for speed:
 *  - the tree keeps its own copy of the coordinates in leaf order, and within a leaf as
 *    x..., y..., z..., so a leaf scan reads one contiguous block (vectorised, AVX-512
 *    when the compiler targets it) instead of gathering through vind;
 *  - nodes are 24-byte records in one array in depth-first order (left child = next);
 *  - the build partitions the packed coordinates in place with a branch-free block
 *    partition and computes each node's bounding box once;
 *  - searches use an explicit stack with a branch-free push of the far child and never
 *    allocate;
 *  - floe_kdtree_build_threads builds the subtrees below the top levels on OpenMP threads
 *    and joins them into the one-thread tree (kd_build_threads).
 * The pruning tests carry a relative slack of 1e-12 so that rounding in the incremental
 * box distance can never drop a point whose own distance passes the exact test: radius
 * and k-NN results equal a brute-force scan computed as dx*dx + dy*dy + dz*dz (the same
 * expression, without contraction into fused multiply-adds, as under -std=c11). */
#include "floe_kdtree.h"
#include "floe_par.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#if defined(__AVX512F__) && defined(__AVX512VL__)
#include <immintrin.h>
#define KD_AVX512 1
#else
#define KD_AVX512 0
#endif

#define KD_DEFAULT_LEAF 16
#define KD_STACK 64              /* explicit search stack; deeper trees recurse */
#define KD_SLACK (1.0 + 1e-12)   /* conservative pruning, see the file comment */

typedef struct kd_node {
    double lo, hi; /* internal: max of the left child's points and min of the right
                      child's points along the split dimension (nanoflann divlow/divhigh) */
    int a;         /* internal: index of the right child; leaf: end of its point range */
    int b;         /* internal: split dimension (0..2); leaf: -1 - begin */
} kd_node;

struct floe_kdtree {
    int n, dim, leaf_size;
    int nnodes, node_cap;
    int *vind;        /* tree order -> caller's index */
    double *c;        /* coordinates in tree order, leaf by leaf: the leaf holding points
                         [b, e) keeps its x, then its y, then its z values in c[3b .. 3e)
                         (z = 0 when dim == 2); during the build, xyz per point */
    kd_node *nodes;
    double box_lo[3], box_hi[3]; /* root bounding box */
};

/* ------------------------------------------------------------------------------------
 * build */

typedef struct kd_task {
    int begin, end;
    int parent;   /* -1 for the root */
    int is_right; /* which child of parent this is */
} kd_task;

/* a growing array of nodes: the tree's, or a subtree's in a threaded build */
typedef struct kd_buf {
    kd_node *v;
    int n, cap;
} kd_buf;

/* room for item n of an array *v of size-byte items that holds *cap (doubled, first when
 * empty): 0, or -1 out of memory (the array untouched) */
static int kd_grow(void **v, int *cap, int n, size_t size, int first)
{
    if (n < *cap) return 0;
    const int c = *cap ? 2 * *cap : first;
    void *t = realloc(*v, (size_t)c * size);
    if (!t) return -1;
    *v = t;
    *cap = c;
    return 0;
}

static int kd_new_node(kd_buf *B)
{
    if (kd_grow((void **)&B->v, &B->cap, B->n, sizeof *B->v, 16)) return -1;
    return B->n++;
}

static void kd_bbox(const floe_kdtree *t, int b, int e, double lo[3], double hi[3])
{
    const double *restrict c = t->c + 3 * (size_t)b;
    double x0 = INFINITY, x1 = -INFINITY, y0 = x0, y1 = x1, z0 = x0, z1 = x1;
    for (size_t i = 0; i < (size_t)(e - b); i++) { /* NaN coordinates are ignored */
        const double x = c[3 * i], y = c[3 * i + 1], z = c[3 * i + 2];
        x0 = x < x0 ? x : x0; x1 = x > x1 ? x : x1;
        y0 = y < y0 ? y : y0; y1 = y > y1 ? y : y1;
        z0 = z < z0 ? z : z0; z1 = z > z1 ? z : z1;
    }
    lo[0] = x0; lo[1] = y0; lo[2] = z0;
    hi[0] = x1; hi[1] = y1; hi[2] = z1;
}

static inline void kd_swap(floe_kdtree *t, int i, int j)
{
    double *a = t->c + 3 * (size_t)i, *b = t->c + 3 * (size_t)j;
    double tx = a[0], ty = a[1], tz = a[2];
    int ti = t->vind[i];
    a[0] = b[0]; a[1] = b[1]; a[2] = b[2]; t->vind[i] = t->vind[j];
    b[0] = tx; b[1] = ty; b[2] = tz; t->vind[j] = ti;
}

/* Moves the points of [b, e) with key < cut (strict) or key <= cut (!strict) to the
 * front; returns the first index of the rest. Block partition (Edelkamp & Weiss,
 * BlockQuicksort, 2016): the positions of misplaced points are collected for a block at
 * each end without branching on the data, then swapped in pairs; a plain Hoare pass
 * finishes the last two blocks. */
#define KD_PBLOCK 64

static int kd_partition(floe_kdtree *t, int f, int b, int e, double cut, int strict)
{
    const double *key = t->c + f;
    unsigned char offl[KD_PBLOCK], offr[KD_PBLOCK];
    int l = b, r = e, nl = 0, nr = 0, sl = 0, sr = 0;
    while (r - l > 2 * KD_PBLOCK) {
        if (nl == 0) {
            sl = 0;
            for (int i = 0; i < KD_PBLOCK; i++) {
                const double k = key[3 * (size_t)(l + i)];
                offl[nl] = (unsigned char)i;
                nl += strict ? !(k < cut) : !(k <= cut);
            }
        }
        if (nr == 0) {
            sr = 0;
            for (int i = 0; i < KD_PBLOCK; i++) {
                const double k = key[3 * (size_t)(r - 1 - i)];
                offr[nr] = (unsigned char)i;
                nr += strict ? k < cut : k <= cut;
            }
        }
        const int num = nl < nr ? nl : nr;
        for (int k = 0; k < num; k++) kd_swap(t, l + offl[sl + k], r - 1 - offr[sr + k]);
        nl -= num; nr -= num; sl += num; sr += num;
        if (nl == 0) l += KD_PBLOCK;
        if (nr == 0) r -= KD_PBLOCK;
    }
    int i = l, j = r - 1;
    for (;;) {
        if (strict) {
            while (i <= j && key[3 * (size_t)i] < cut) i++;
            while (i <= j && !(key[3 * (size_t)j] < cut)) j--;
        } else {
            while (i <= j && key[3 * (size_t)i] <= cut) i++;
            while (i <= j && !(key[3 * (size_t)j] <= cut)) j--;
        }
        if (i >= j) break;
        kd_swap(t, i, j);
        i++;
        j--;
    }
    return i;
}

/* the split of an internal node over [b, e) with box lo, hi: its dimension *f, and the
 * points moved so that [b, b + split) go left (returns split) */
static int kd_split(floe_kdtree *t, int b, int e, const double lo[3], const double hi[3], int *fp)
{
    /* nanoflann middleSplit_: widest dimension, first one on ties */
    int f = 0;
    double span = hi[0] - lo[0];
    for (int d = 1; d < t->dim; d++)
        if (hi[d] - lo[d] > span) { span = hi[d] - lo[d]; f = d; }
    double cut = 0.5 * lo[f] + 0.5 * hi[f];
    if (cut != cut) cut = 0.0; /* -inf .. +inf */
    if (cut < lo[f]) cut = lo[f];
    if (cut > hi[f]) cut = hi[f];
    /* planeSplit: [< cut | == cut | > cut], then nanoflann's choice of index */
    const int count = e - b, half = count / 2;
    int split;
    int lim1 = kd_partition(t, f, b, e, cut, 1) - b;
    if (lim1 > half) {
        split = lim1;
    } else {
        int lim2 = kd_partition(t, f, b + lim1, e, cut, 0) - b;
        split = lim2 < half ? lim2 : half;
    }
    if (split <= 0 || split >= count) split = half; /* only with NaN coordinates */
    *fp = f;
    return split;
}

/* the subtree of points [begin, end) into B, depth first (left child next, its nodes'
 * indices B's), its root's box into root_lo, root_hi */
static int kd_build_nodes(floe_kdtree *t, kd_buf *B, int begin, int end, double root_lo[3], double root_hi[3])
{
    int stack_cap = 64, sp = 0;
    kd_task *stack = malloc((size_t)stack_cap * sizeof *stack);
    if (!stack) return -1;
    stack[sp++] = (kd_task){begin, end, -1, 0};
    while (sp > 0) {
        kd_task tk = stack[--sp];
        for (;;) {
            int id = kd_new_node(B);
            if (id < 0) { free(stack); return -1; }
            double lo[3], hi[3];
            kd_bbox(t, tk.begin, tk.end, lo, hi);
            if (tk.parent >= 0) {
                kd_node *p = &B->v[tk.parent];
                if (tk.is_right) {
                    p->hi = lo[p->b];
                    p->a = id;
                } else {
                    p->lo = hi[p->b];
                }
            } else {
                memcpy(root_lo, lo, sizeof lo);
                memcpy(root_hi, hi, sizeof hi);
            }
            int count = tk.end - tk.begin;
            kd_node *nd = &B->v[id];
            if (count <= t->leaf_size) {
                nd->lo = nd->hi = 0;
                nd->a = tk.end;
                nd->b = -1 - tk.begin;
                break;
            }
            int f;
            const int split = kd_split(t, tk.begin, tk.end, lo, hi, &f);
            nd = &B->v[id];
            nd->b = f;
            nd->a = -1;
            if (sp == stack_cap) {
                kd_task *ns = realloc(stack, (size_t)(2 * stack_cap) * sizeof *ns);
                if (!ns) { free(stack); return -1; }
                stack = ns;
                stack_cap *= 2;
            }
            stack[sp++] = (kd_task){tk.begin + split, tk.end, id, 1};
            tk = (kd_task){tk.begin, tk.begin + split, id, 0};
        }
    }
    free(stack);
    return 0;
}

/* Threads (floe_kdtree_build_threads): the nodes over more than a quarter of a thread's
 * share of the points (n / (4 threads)), down to depth KD_TOP_MAX at most, are built first, on one
 * thread (kd_top_build: the same splits in the same order as kd_build_nodes); each subtree
 * below them by one thread into its own buffer (their points are disjoint ranges of c and
 * vind; its root's box bounds its parent); then the pieces are joined in depth-first order
 * (kd_build_threads): the tree of a one-thread build, node for node, wherever the subtrees
 * were cut (tests/test_kdtree.c). A top entry is a node, or a subtree (sub >= 0). */
#define KD_TOP_MAX 24
typedef struct kd_top_entry {
    kd_node nd;
    int sub;   /* >= 0: the subtree T.s[sub] stands here */
    int right; /* an internal node: the entry of its right child */
} kd_top_entry;
typedef struct kd_sub {
    int b, e;            /* its points */
    int parent, is_right; /* the entry it is a child of (-1: the root) */
    double lo[3], hi[3]; /* its root's box (kd_build_nodes) */
    kd_buf nodes;
} kd_sub;
typedef struct kd_top {
    kd_top_entry *e;
    int n, cap;
    kd_sub *s;
    int nsub, scap;
    int target; /* a subtree at most this many points */
} kd_top;

static int kd_top_entry_new(kd_top *T)
{
    if (kd_grow((void **)&T->e, &T->cap, T->n, sizeof *T->e, 64)) return -1;
    return T->n++;
}

/* sets the bound of parent's side from its child's box (kd_build_nodes' rule) */
static void kd_top_bound(kd_top *T, int parent, int is_right, int child, const double lo[3], const double hi[3])
{
    kd_node *p = &T->e[parent].nd;
    if (is_right) {
        p->hi = lo[p->b];
        T->e[parent].right = child;
    } else {
        p->lo = hi[p->b];
    }
}

/* the entry of points [b, e) at depth; parent entry and side (parent < 0: the root) */
static int kd_top_build(floe_kdtree *t, kd_top *T, int b, int e, int depth, int parent, int is_right)
{
    const int id = kd_top_entry_new(T);
    if (id < 0) return -1;
    kd_top_entry *en = &T->e[id];
    en->sub = -1;
    en->right = -1;
    const int count = e - b;
    if (count > t->leaf_size && (count <= T->target || depth == KD_TOP_MAX)) { /* below: a thread's */
        if (kd_grow((void **)&T->s, &T->scap, T->nsub, sizeof *T->s, 32)) return -1;
        T->s[T->nsub] = (kd_sub){.b = b, .e = e, .parent = parent, .is_right = is_right};
        en->sub = T->nsub++;
        if (parent >= 0 && is_right) T->e[parent].right = id;
        return 0;
    }
    double lo[3], hi[3];
    kd_bbox(t, b, e, lo, hi);
    if (parent >= 0)
        kd_top_bound(T, parent, is_right, id, lo, hi);
    else {
        memcpy(t->box_lo, lo, sizeof lo);
        memcpy(t->box_hi, hi, sizeof hi);
    }
    if (count <= t->leaf_size) {
        en->nd = (kd_node){0, 0, e, -1 - b};
        return 0;
    }
    int f;
    const int split = kd_split(t, b, e, lo, hi, &f);
    en = &T->e[id];
    en->nd = (kd_node){0, 0, -1, f};
    if (kd_top_build(t, T, b, b + split, depth + 1, id, 0)) return -1;
    return kd_top_build(t, T, b + split, e, depth + 1, id, 1);
}

static int kd_build_threads(floe_kdtree *t, int nt)
{
    kd_top T = {0};
    T.target = t->n / (4 * nt); /* nt <= KD_THREADS_MAX */
    int rc = kd_top_build(t, &T, 0, t->n, 0, -1, 0);
    int fail = 0;
    if (!rc) {
        FLOE_OMP(omp parallel for schedule(dynamic, 1) num_threads(nt) reduction(|: fail))
        for (int q = 0; q < T.nsub; q++) {
            kd_sub *S = &T.s[q];
            S->nodes.cap = 2 * ((S->e - S->b) / t->leaf_size) + 16;
            S->nodes.v = malloc((size_t)S->nodes.cap * sizeof *S->nodes.v);
            if (!S->nodes.v) S->nodes.cap = 0;
            fail |= kd_build_nodes(t, &S->nodes, S->b, S->e, S->lo, S->hi) != 0;
        }
        rc = fail ? -1 : 0;
    }
    for (int q = 0; !rc && q < T.nsub; q++) { /* the subtrees' roots bound their parents */
        const kd_sub *S = &T.s[q];
        if (S->parent >= 0) {
            kd_node *p = &T.e[S->parent].nd;
            if (S->is_right) p->hi = S->lo[p->b];
            else p->lo = S->hi[p->b];
        } else {
            memcpy(t->box_lo, S->lo, sizeof S->lo);
            memcpy(t->box_hi, S->hi, sizeof S->hi);
        }
    }
    /* joined depth first: each entry's first node index, then the nodes */
    int *at = rc ? NULL : malloc((size_t)(T.n ? T.n : 1) * sizeof *at);
    if (!rc && !at) rc = -1;
    int total = 0;
    for (int q = 0; !rc && q < T.n; q++) {
        at[q] = total;
        total += T.e[q].sub >= 0 ? T.s[T.e[q].sub].nodes.n : 1;
    }
    kd_node *nodes = rc ? NULL : malloc((size_t)(total ? total : 1) * sizeof *nodes);
    if (!rc && !nodes) rc = -1;
    for (int q = 0; !rc && q < T.n; q++) {
        const kd_top_entry *en = &T.e[q];
        if (en->sub < 0) {
            nodes[at[q]] = en->nd;
            if (en->nd.b >= 0) nodes[at[q]].a = at[en->right];
            continue;
        }
        const kd_buf *B = &T.s[en->sub].nodes;
        for (int k = 0; k < B->n; k++) {
            kd_node nd = B->v[k];
            if (nd.b >= 0) nd.a += at[q]; /* internal: its right child's index */
            nodes[at[q] + k] = nd;
        }
    }
    if (!rc) {
        free(t->nodes);
        t->nodes = nodes;
        t->nnodes = t->node_cap = total;
    }
    for (int q = 0; q < T.nsub; q++) free(T.s[q].nodes.v);
    free(at);
    free(T.e);
    free(T.s);
    return rc;
}

/* xyz per point -> x..., y..., z... per leaf, in place (nt threads: leaves are disjoint) */
static int kd_transpose_leaves(floe_kdtree *t, int nt)
{
    (void)nt; /* without OpenMP */
    int mmax = 0;
    for (int id = 0; id < t->nnodes; id++) {
        const kd_node *nd = &t->nodes[id];
        if (nd->b < 0 && nd->a - (-1 - nd->b) > mmax) mmax = nd->a - (-1 - nd->b);
    }
    int fail = 0;
    FLOE_OMP(omp parallel num_threads(nt) if (nt > 1) reduction(|: fail))
    {
        double *tmp = malloc((size_t)3 * (size_t)(mmax ? mmax : 1) * sizeof *tmp);
        fail |= !tmp;
        FLOE_OMP(omp for schedule(static))
        for (int id = 0; id < t->nnodes; id++) {
            const kd_node *nd = &t->nodes[id];
            if (nd->b >= 0 || !tmp) continue;
            const int b = -1 - nd->b, m = nd->a - b;
            double *L = t->c + 3 * (size_t)b;
            memcpy(tmp, L, (size_t)3 * (size_t)m * sizeof *tmp);
            for (size_t i = 0; i < (size_t)m; i++) {
                L[i] = tmp[3 * i];
                L[m + i] = tmp[3 * i + 1];
                L[2 * m + i] = tmp[3 * i + 2];
            }
        }
        free(tmp);
    }
    return fail ? -1 : 0;
}

floe_kdtree *floe_kdtree_build(const double *pts, int n, int dim, int leaf_size)
{
    return floe_kdtree_build_threads(pts, n, dim, leaf_size, 1);
}

/* below this many points a threaded build is not worth its threads' start; threads beyond
 * KD_THREADS_MAX are not used */
#define KD_THREADS_MIN 4096
#define KD_THREADS_MAX 256

floe_kdtree *floe_kdtree_build_threads(const double *pts, int n, int dim, int leaf_size, int nthreads)
{
    if (n < 0 || (n > 0 && !pts) || (dim != 2 && dim != 3)) return NULL;
    floe_kdtree *t = calloc(1, sizeof *t);
    if (!t) return NULL;
    t->n = n;
    t->dim = dim;
    t->leaf_size = leaf_size > 0 ? leaf_size : KD_DEFAULT_LEAF;
    if (n == 0) return t;
    /* one block: coordinates | vind */
    size_t bytes = (size_t)n * (3 * sizeof(double) + sizeof(int));
    double *block = malloc(bytes);
    if (!block) { free(t); return NULL; }
    t->c = block;
    t->vind = (int *)(block + 3 * (size_t)n);
    for (int i = 0; i < n; i++) {
        t->c[3 * (size_t)i] = pts[3 * (size_t)i];
        t->c[3 * (size_t)i + 1] = pts[3 * (size_t)i + 1];
        t->c[3 * (size_t)i + 2] = dim == 3 ? pts[3 * (size_t)i + 2] : 0.0;
        t->vind[i] = i;
    }
    /* as many threads as have 4 subtrees each of at least 256 points and 2 leaves (more
     * threads would leave the top levels, built on one thread, most of the tree) */
    int nt = nthreads > 1 && n >= KD_THREADS_MIN ? (nthreads < KD_THREADS_MAX ? nthreads : KD_THREADS_MAX) : 1;
    while (nt > 1 && (n / (4 * nt) < 256 || n / (4 * nt) <= 2 * t->leaf_size)) nt--;
    int rc;
    if (nt > 1)
        rc = kd_build_threads(t, nt);
    else {
        /* a balanced tree has 2-3 n/leaf nodes; the array grows if the data needs more and is
         * trimmed to size at the end (untouched capacity costs no memory) */
        kd_buf B = {NULL, 0, 4 * (n / t->leaf_size) + 16};
        B.v = malloc((size_t)B.cap * sizeof *B.v);
        rc = B.v ? kd_build_nodes(t, &B, 0, n, t->box_lo, t->box_hi) : -1;
        t->nodes = B.v;
        t->nnodes = B.n;
        t->node_cap = B.cap;
        if (!rc && t->nnodes < t->node_cap) { /* shrink to fit; keep the old block if that fails */
            kd_node *nn = realloc(t->nodes, (size_t)t->nnodes * sizeof *nn);
            if (nn) { t->nodes = nn; t->node_cap = t->nnodes; }
        }
    }
    if (rc != 0 || kd_transpose_leaves(t, nt) != 0) {
        floe_kdtree_destroy(t);
        return NULL;
    }
    return t;
}

void floe_kdtree_destroy(floe_kdtree *t)
{
    if (!t) return;
    free(t->c);
    free(t->nodes);
    free(t);
}

int floe_kdtree_size(const floe_kdtree *t) { return t ? t->n : 0; }

const int *floe_kdtree_order(const floe_kdtree *t) { return t ? t->vind : NULL; }

/* ------------------------------------------------------------------------------------
 * search
 *
 * Depth-first, near child first, as nanoflann's searchLevel, but with an explicit stack:
 * at each internal node the far child is written to the stack together with its box
 * distance and kept (sp += 1) only if that distance is within reach, so the pruning
 * decision costs no branch. A frame carries the whole per-dimension distance vector, so
 * nothing has to be restored on the way back. When a (degenerate, very deep) tree fills
 * the stack, the newest frame is searched by a recursive call. */

typedef struct kd_frame {
    int node;
    double mind;   /* squared distance from q to the node's box */
    double d[3];   /* its per-dimension parts (nanoflann's "dists") */
} kd_frame;

/* query point (z = 0 in 2D) and the root frame */
static kd_frame kd_root_frame(const floe_kdtree *t, const double q[3], double qq[3])
{
    kd_frame fr = {0, 0.0, {0, 0, 0}};
    qq[0] = q[0];
    qq[1] = q[1];
    qq[2] = t->dim == 3 ? q[2] : 0.0;
    for (int i = 0; i < 3; i++) {
        double e = 0;
        if (qq[i] < t->box_lo[i]) e = (t->box_lo[i] - qq[i]) * (t->box_lo[i] - qq[i]);
        else if (qq[i] > t->box_hi[i]) e = (qq[i] - t->box_hi[i]) * (qq[i] - t->box_hi[i]);
        fr.d[i] = e;
        fr.mind += e;
    }
    return fr;
}

/* One step down from internal node nd (index node): pushes the far child onto
 * stack[*sp] (kept if its box distance is <= reach) and returns the near child. */
static inline int kd_descend(const kd_node *nd, int node, const double q[3], double mind,
                             const double dd[3], double reach, kd_frame *stack, int *sp)
{
    const int f = nd->b;
    const double v = q[f];
    const double diff1 = v - nd->lo, diff2 = v - nd->hi;
    int near, far;
    double cut;
    if (diff1 + diff2 < 0) { near = node + 1; far = nd->a; cut = diff2 * diff2; }
    else { near = nd->a; far = node + 1; cut = diff1 * diff1; }
    const double nm = mind + cut - dd[f];
    kd_frame *fr = &stack[*sp];
    fr->node = far;
    fr->mind = nm;
    fr->d[0] = dd[0]; fr->d[1] = dd[1]; fr->d[2] = dd[2];
    fr->d[f] = cut;
    *sp += nm <= reach;
    return near;
}

#define KD_CHUNK 32

/* squared distances from q to the points x = L[i], y = L[s + i], z = L[2s + i], i < m */
static inline void kd_leaf_d2(const double *restrict L, int s, int m, const double q[3],
                              double *restrict d2)
{
    const double qx = q[0], qy = q[1], qz = q[2];
    for (int i = 0; i < m; i++) {
        const double dx = L[i] - qx, dy = L[s + i] - qy, dz = L[2 * s + i] - qz;
        d2[i] = dx * dx + dy * dy + dz * dz;
    }
}

typedef struct kd_rq {
    double q[3], r2, reach;
    int *out;
    int cap;
} kd_rq;

/* radius search of the subtree in frame start; cnt hits so far; returns the new count */
static int kd_radius_from(const floe_kdtree *t, const kd_rq *rq, kd_frame start, int cnt)
{
    const kd_node *restrict nodes = t->nodes;
    const double *restrict C = t->c;
    const int *restrict vind = t->vind;
    const double r2 = rq->r2, reach = rq->reach;
    int *restrict out = rq->out;
    const int cap = rq->cap;
#if KD_AVX512
    const __m512d vqx = _mm512_set1_pd(rq->q[0]), vqy = _mm512_set1_pd(rq->q[1]);
    const __m512d vqz = _mm512_set1_pd(rq->q[2]), vr2 = _mm512_set1_pd(r2);
#endif
    kd_frame stack[KD_STACK];
    int sp = 0, node = start.node;
    double mind = start.mind, dd[3] = {start.d[0], start.d[1], start.d[2]};
    for (;;) {
        const kd_node *nd = &nodes[node];
        while (nd->b >= 0) {
            node = kd_descend(nd, node, rq->q, mind, dd, reach, stack, &sp);
            if (sp == KD_STACK) cnt = kd_radius_from(t, rq, stack[--sp], cnt);
            nd = &nodes[node];
        }
        const int b = -1 - nd->b, m = nd->a - b;
        const double *restrict L = C + 3 * (size_t)b;
        const int *restrict id = vind + b;
#if KD_AVX512
        if (cap - cnt >= ((m + 7) & ~7)) {
            /* 8 points at a time; the hits' indices are compressed into out with
             * full-width stores (room checked above) */
            for (int i = 0; i < m; i += 8) {
                const __mmask8 lm = m - i >= 8 ? (__mmask8)0xff : (__mmask8)((1u << (m - i)) - 1);
                const __m512d dx = _mm512_sub_pd(_mm512_maskz_loadu_pd(lm, L + i), vqx);
                const __m512d dy = _mm512_sub_pd(_mm512_maskz_loadu_pd(lm, L + m + i), vqy);
                const __m512d dz = _mm512_sub_pd(_mm512_maskz_loadu_pd(lm, L + 2 * m + i), vqz);
                const __m512d d2 = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)),
                                                 _mm512_mul_pd(dz, dz));
                const __mmask8 hit = _mm512_mask_cmp_pd_mask(lm, d2, vr2, _CMP_LE_OQ);
                const __m256i ids = _mm256_maskz_loadu_epi32(lm, id + i);
                _mm256_storeu_si256((__m256i *)(out + cnt), _mm256_maskz_compress_epi32(hit, ids));
                cnt += __builtin_popcount((unsigned)hit);
            }
        } else
#endif
        for (int i0 = 0; i0 < m; i0 += KD_CHUNK) {
            const int mm = m - i0 < KD_CHUNK ? m - i0 : KD_CHUNK;
            double d2[KD_CHUNK];
            kd_leaf_d2(L + i0, m, mm, rq->q, d2);
            if (cap - cnt >= mm) { /* branch-free: write every index, keep the hits */
                for (int i = 0; i < mm; i++) {
                    out[cnt] = id[i0 + i];
                    cnt += d2[i] <= r2;
                }
            } else {
                for (int i = 0; i < mm; i++) {
                    if (d2[i] <= r2) {
                        if (cnt < cap) out[cnt] = id[i0 + i];
                        cnt++;
                    }
                }
            }
        }
        if (sp == 0) break;
        const kd_frame *fr = &stack[--sp];
        node = fr->node;
        mind = fr->mind;
        dd[0] = fr->d[0]; dd[1] = fr->d[1]; dd[2] = fr->d[2];
    }
    return cnt;
}

int floe_kdtree_radius(const floe_kdtree *t, const double q[3], double r, int *out, int cap)
{
    if (!t || t->n == 0 || !(r >= 0)) return 0;
    kd_rq rq;
    kd_frame fr = kd_root_frame(t, q, rq.q);
    rq.r2 = r * r;
    rq.reach = rq.r2 * KD_SLACK;
    rq.out = out;
    rq.cap = out && cap > 0 ? cap : 0;
    if (!(fr.mind <= rq.reach)) return 0;
    return kd_radius_from(t, &rq, fr, 0);
}

typedef struct kd_vq {
    double q[3], r2, reach;
    floe_kdtree_visit_fn fn;
    void *user;
} kd_vq;

static void kd_visit_from(const floe_kdtree *t, const kd_vq *vq, kd_frame start)
{
    const kd_node *nodes = t->nodes;
    kd_frame stack[KD_STACK];
    int sp = 0, node = start.node;
    double mind = start.mind, dd[3] = {start.d[0], start.d[1], start.d[2]};
    for (;;) {
        const kd_node *nd = &nodes[node];
        while (nd->b >= 0) {
            node = kd_descend(nd, node, vq->q, mind, dd, vq->reach, stack, &sp);
            if (sp == KD_STACK) kd_visit_from(t, vq, stack[--sp]);
            nd = &nodes[node];
        }
        const int b = -1 - nd->b, m = nd->a - b;
        const double *L = t->c + 3 * (size_t)b;
        for (int i0 = 0; i0 < m; i0 += KD_CHUNK) {
            const int mm = m - i0 < KD_CHUNK ? m - i0 : KD_CHUNK;
            double d2[KD_CHUNK];
            kd_leaf_d2(L + i0, m, mm, vq->q, d2);
            for (int i = 0; i < mm; i++)
                if (d2[i] <= vq->r2) vq->fn(t->vind[b + i0 + i], d2[i], vq->user);
        }
        if (sp == 0) break;
        const kd_frame *fr = &stack[--sp];
        node = fr->node;
        mind = fr->mind;
        dd[0] = fr->d[0]; dd[1] = fr->d[1]; dd[2] = fr->d[2];
    }
}

void floe_kdtree_radius_visit(const floe_kdtree *t, const double q[3], double r,
                              floe_kdtree_visit_fn fn, void *user)
{
    if (!t || t->n == 0 || !fn || !(r >= 0)) return;
    kd_vq vq;
    kd_frame fr = kd_root_frame(t, q, vq.q);
    vq.r2 = r * r;
    vq.reach = vq.r2 * KD_SLACK;
    vq.fn = fn;
    vq.user = user;
    if (!(fr.mind <= vq.reach)) return;
    kd_visit_from(t, &vq, fr);
}

/* k-NN: idx/d2 are the caller's buffers, kept sorted by insertion. The reach shrinks as
 * the buffer fills, so frames are checked again when popped. */
typedef struct kd_kq {
    double q[3];
    int k, cnt;
    double worst; /* d2[k-1] once the buffer is full, else +inf */
    int *idx;
    double *d2;
} kd_kq;

static void kd_knn_from(const floe_kdtree *t, kd_kq *kq, kd_frame start)
{
    const kd_node *nodes = t->nodes;
    int *idx = kq->idx;
    double *dist = kq->d2;
    const int k = kq->k;
    kd_frame stack[KD_STACK];
    int sp = 0, node = start.node;
    double mind = start.mind, dd[3] = {start.d[0], start.d[1], start.d[2]};
    for (;;) {
        if (mind <= kq->worst * KD_SLACK) {
            const kd_node *nd = &nodes[node];
            while (nd->b >= 0) {
                node = kd_descend(nd, node, kq->q, mind, dd, kq->worst * KD_SLACK, stack, &sp);
                if (sp == KD_STACK) kd_knn_from(t, kq, stack[--sp]);
                nd = &nodes[node];
            }
            const int b = -1 - nd->b, m = nd->a - b;
            const double *L = t->c + 3 * (size_t)b;
            for (int i0 = 0; i0 < m; i0 += KD_CHUNK) {
                const int mm = m - i0 < KD_CHUNK ? m - i0 : KD_CHUNK;
                double dc[KD_CHUNK];
                kd_leaf_d2(L + i0, m, mm, kq->q, dc);
                for (int i = 0; i < mm; i++) {
                    const double d2 = dc[i];
                    if (!(d2 < kq->worst)) continue;
                    int j = kq->cnt < k ? kq->cnt++ : k - 1;
                    while (j > 0 && dist[j - 1] > d2) {
                        dist[j] = dist[j - 1];
                        idx[j] = idx[j - 1];
                        j--;
                    }
                    dist[j] = d2;
                    idx[j] = t->vind[b + i0 + i];
                    if (kq->cnt == k) kq->worst = dist[k - 1];
                }
            }
        }
        if (sp == 0) break;
        const kd_frame *fr = &stack[--sp];
        node = fr->node;
        mind = fr->mind;
        dd[0] = fr->d[0]; dd[1] = fr->d[1]; dd[2] = fr->d[2];
    }
}

int floe_kdtree_knn(const floe_kdtree *t, const double q[3], int k, int *idx, double *d2)
{
    if (!t || t->n == 0 || k <= 0 || !idx || !d2) return 0;
    kd_kq kq;
    kd_frame fr = kd_root_frame(t, q, kq.q);
    kq.k = k;
    kq.cnt = 0;
    kq.worst = INFINITY;
    kq.idx = idx;
    kq.d2 = d2;
    kd_knn_from(t, &kq, fr);
    return kq.cnt;
}
