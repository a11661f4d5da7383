/* check.h - minimal test harness: CHECK(cond, fmt, ...) records a pass or a failure with
 * a message; CHECK_NEAR(a, b, rtol, what) compares with a stated relative tolerance;
 * check_summary() prints "N passed, N failed" and returns the exit code. */
#ifndef FLOE_CHECK_H
#define FLOE_CHECK_H
#include <math.h>
#include <stdio.h>

static int check_pass_ = 0, check_fail_ = 0;

#define CHECK(cond, ...)                                                        \
    do {                                                                        \
        if (cond) { check_pass_++; }                                            \
        else {                                                                  \
            check_fail_++;                                                      \
            fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__);                \
            fprintf(stderr, __VA_ARGS__);                                       \
            fprintf(stderr, "\n");                                              \
        }                                                                       \
    } while (0)

/* |a - b| <= rtol * |b| (or <= rtol when b == 0) */
#define CHECK_NEAR(a, b, rtol, what)                                            \
    do {                                                                        \
        double ca_ = (a), cb_ = (b), ct_ = (rtol);                              \
        double cref_ = fabs(cb_) > 0 ? fabs(cb_) : 1.0;                         \
        double crel_ = fabs(ca_ - cb_) / cref_;                                 \
        CHECK(crel_ <= ct_ && ca_ == ca_, "%s: got %.10g, expected %.10g (rel err %.3g > tol %.3g)", \
              what, ca_, cb_, crel_, ct_);                                       \
        printf("  %-52s %.6g vs %.6g  rel.err %.2e (tol %.1e)\n", what, ca_, cb_, crel_, ct_); \
    } while (0)

static inline int check_summary(const char *name) {
    printf("%s: %d passed, %d failed\n", name, check_pass_, check_fail_);
    return check_fail_ ? 1 : 0;
}
#endif
