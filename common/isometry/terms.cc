// F's terms at a state, summed in a fixed order whatever the number of
// threads.
#include <algorithm>
#include <array>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "common/isometry/block_matrix.h"
#include "common/isometry/solver_internal.h"

namespace docunfold::isometry::internal {
namespace {

// Adds the squares of the first `n` rows' values to `sum`, one by one.
void AddSquares(const Row* rows, int n, double* sum) {
  for (int i = 0; i < n; ++i) *sum += rows[i].value * rows[i].value;
}

// Items per chunk of OrderedSums. Chunks, not threads, fix the order in
// which floating-point sums are added, so F, and with it every step Levenberg-
// Marquardt accepts, is the same whatever number of threads runs (the solver
// re-decides that number every outer iteration from the machine's load).
constexpr int kSumChunk = 1024;

// Per chunk of [0, n): add(i, acc) for its items in order, into acc[0..K).
// Returns the chunks' sums added in chunk order.
template <int K, class Add>
std::array<double, K> OrderedSums(int n, int threads, Add&& add) {
  const int chunks = (n + kSumChunk - 1) / kSumChunk;
  std::vector<std::array<double, K>> part(static_cast<size_t>(chunks));
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && chunks > 1)
  for (int c = 0; c < chunks; ++c) {
    std::array<double, K> acc{};
    Row rows[kMaxRowsPerItem];
    for (int i = c * kSumChunk; i < std::min(n, (c + 1) * kSumChunk); ++i) add(i, rows, acc);
    part[size_t(c)] = acc;
  }
  std::array<double, K> total{};
  for (const auto& acc : part)
    for (int k = 0; k < K; ++k) total[size_t(k)] += acc[size_t(k)];
  return total;
}

double WeightedF(const TermValues& t, const Weights& w) { return t.Weighted(w); }

}  // namespace

TermValues EvaluateTerms(const State& s, const StepData& data, int threads) {
  const int quads = s.grid.NumQuads(), points = int(data.points.size());
  const int triplets = NumFairTriplets(s.grid), markers = int(data.markers.size());
  threads = quads >= kMinParallelVertices ? threads : 1;
  const double iso = OrderedSums<1>(quads, threads, [&](int q, Row* rows, auto& acc) {
    AddSquares(rows, IsoRows(s, data, q, rows), &acc[0]);
  })[0];
  const double dist = OrderedSums<1>(points, threads, [&](int p, Row* rows, auto& acc) {
    AddSquares(rows, DistRows(s, data, p, rows), &acc[0]);
  })[0];
  const auto fair = OrderedSums<2>(triplets, threads, [&](int t, Row* rows, auto& acc) {
    AddSquares(rows, FairRows(s, data, t, false, rows), &acc[0]);
    AddSquares(rows, FairRows(s, data, t, true, rows), &acc[1]);
  });
  const auto feature = OrderedSums<2>(markers, threads, [&](int m, Row* rows, auto& acc) {
    AddSquares(rows, LineRows(s, data, m, rows), &acc[0]);
    AddSquares(rows, RayRows(s, data, m, rows), &acc[1]);
  });
  const double fair3d = fair[0], fair2d = fair[1], line = feature[0], ray = feature[1];
  TermValues t;
  t.iso = iso;
  t.dist = dist;
  t.fair3d = fair3d;
  t.fair2d = fair2d;
  t.line = line;
  t.ray = ray;
  return t;
}

// Surrogate F (footpoints, normals and — under Gauss-Newton — lines fixed)
// at a state.
double SurrogateF(const State& s, const StepData& data, const Weights& w, int threads) {
  return WeightedF(EvaluateTerms(s, data, threads), w);
}

}  // namespace docunfold::isometry::internal
