// nanoflann_bench.cpp - the peer side of floe's kd-tree benchmark: nanoflann 1.4.3
// (Debian libnanoflann-dev) build + fixed-radius search for every point. Single thread.
// Same methodology as /work/shared/peers/kdtree-nanoflann/kdtree_bench.cpp, with two
// changes so that it prints the same figures as kdtree_bench.c: the points come from
// splitmix64 (seed 42, the same points as kdtree_bench.c) instead of mt19937_64, and the
// bytes allocated by the build (glibc mallinfo2) are reported per point (nanoflann's
// index references the caller's coordinates, so they are not included).
// Usage: nanoflann_bench N LEAF [REPS] [TARGET_MEAN]
#include <malloc.h>
#include <nanoflann.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

struct Cloud {
  std::vector<double> p;  // xyz interleaved
  size_t kdtree_get_point_count() const { return p.size() / 3; }
  double kdtree_get_pt(size_t i, size_t d) const { return p[3 * i + d]; }
  template <class BBOX> bool kdtree_get_bbox(BBOX&) const { return false; }
};
using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 3, uint32_t>;

static uint64_t rng_state;
static uint64_t splitmix64() {
  uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

static double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
static double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int main(int argc, char** argv) {
  if (argc < 3) { std::fprintf(stderr, "usage: %s N LEAF [REPS] [TARGET_MEAN]\n", argv[0]); return 2; }
  const size_t N = std::strtoull(argv[1], nullptr, 10);
  const size_t leaf = std::strtoull(argv[2], nullptr, 10);
  const int reps = argc > 3 ? std::atoi(argv[3]) : 3;
  const double target = argc > 4 ? std::atof(argv[4]) : 30.0;

  Cloud c; c.p.resize(3 * N);
  rng_state = 42;
  for (auto& x : c.p) x = (double)(splitmix64() >> 11) * 0x1.0p-53;

  // radius for the target mean count; bulk estimate, then calibrate on a sample (untimed)
  double r = std::cbrt(3.0 * target / (4.0 * M_PI * (double)N));
  std::vector<std::pair<uint32_t, double>> res;
  res.reserve(256);
  nanoflann::SearchParams sp(32, 0.0f, false);
  {
    Tree t(3, c, nanoflann::KDTreeSingleIndexAdaptorParams(leaf));
    for (int it = 0; it < 3; ++it) {
      size_t S = std::min<size_t>(N, 20000), tot = 0;
      for (size_t i = 0; i < S; ++i) tot += t.radiusSearch(&c.p[3 * (i * (N / S))], r * r, res, sp);
      double m = (double)tot / (double)S;
      r *= std::cbrt(target / m);
    }
  }

  std::vector<double> tb, tq, tqs;
  size_t total = 0;
  double checksum = 0, mem_per_pt = 0;
  for (int rep = 0; rep < reps; ++rep) {
    struct mallinfo2 m0 = mallinfo2();
    double t0 = now();
    Tree t(3, c, nanoflann::KDTreeSingleIndexAdaptorParams(leaf));  // constructor builds the index
    double t1 = now();
    struct mallinfo2 m1 = mallinfo2();
    mem_per_pt = ((double)(m1.uordblks + m1.hblkhd) - (double)(m0.uordblks + m0.hblkhd)) / (double)N;
    tb.push_back(t1 - t0);

    size_t tot = 0; double cs = 0;
    t0 = now();
    for (size_t i = 0; i < N; ++i) {
      tot += t.radiusSearch(&c.p[3 * i], r * r, res, sp);
      for (auto& m : res) cs += m.first;
    }
    t1 = now();
    tq.push_back(t1 - t0);
    total = tot; checksum = cs;

    // queries in tree (leaf) order: spatially coherent, as in a DEM/PD neighbour build
    const auto& order = t.vAcc;
    size_t tot2 = 0;
    t0 = now();
    for (size_t k = 0; k < N; ++k) {
      tot2 += t.radiusSearch(&c.p[3 * order[k]], r * r, res, sp);
      for (auto& m : res) cs += m.first;
    }
    t1 = now();
    tqs.push_back(t1 - t0);
    if (tot2 != tot) { std::fprintf(stderr, "ERROR: order-dependent count %zu vs %zu\n", tot, tot2); return 1; }

    if (rep == 0) {  // brute-force check of 200 queries
      for (size_t q = 0; q < 200; ++q) {
        size_t i = (q * 7919) % N, bf = 0;
        for (size_t j = 0; j < N; ++j) {
          double dx = c.p[3*i]-c.p[3*j], dy = c.p[3*i+1]-c.p[3*j+1], dz = c.p[3*i+2]-c.p[3*j+2];
          // nanoflann's RadiusResultSet keeps dist < radius (strict)
          if (dx*dx + dy*dy + dz*dz < r * r) ++bf;
        }
        size_t k = t.radiusSearch(&c.p[3 * i], r * r, res, sp);
        if (k != bf) { std::fprintf(stderr, "ERROR: query %zu: kd-tree %zu vs brute force %zu\n", i, k, bf); return 1; }
      }
    }
  }
  double b = median(tb), q = median(tq), qs = median(tqs);
  std::printf("nanoflann_kdtree N=%zu leaf=%zu reps=%d radius=%.6g mean_neighbours=%.2f build_s=%.4f query_s=%.4f "
              "queries_per_s=%.3e query_sorted_s=%.4f queries_sorted_per_s=%.3e neighbours_per_s=%.3e "
              "mem_bytes_per_point=%.1f checksum=%.0f\n",
              N, leaf, reps, r, (double)total / (double)N, b, q, (double)N / q, qs, (double)N / qs,
              (double)total / q, mem_per_pt, checksum);
  return 0;
}
