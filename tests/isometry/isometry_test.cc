// The joint optimisation library of M and M' (common/isometry): energies,
// derivatives, solvers, subdivision, unfolding and spatial queries.
#include "common/isometry/isometry.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <map>
#include <random>

#include "common/isometry/block_matrix.h"
#include "common/isometry/mesh_index.h"
#include "common/isometry/metrics.h"
#include "common/isometry/residuals.h"
#include "common/isometry/subdivision.h"
#include "common/isometry/unfold.h"
#include "common/ply.h"
#include "tests/isometry/test_meshes.h"
#include "tests/support/test_support.h"

namespace docunfold {
namespace {

using isometry::Problem;
using isometry::SolveOptions;
using testing::CurledSheet;
using testing::DataSetsWithGroundTruth;
using testing::ProfileSheet;
using testing::SampleSurface;
using testing::SurfaceDistance;

// A flattened copy of M: each vertex moved `amount` of the way toward the
// best-fit plane of M.
MeshPair Flattened(const MeshPair& m, double amount) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& v : m.mesh3d) mean += v / double(m.mesh3d.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& v : m.mesh3d) cov += (v - mean) * (v - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d normal = eig.eigenvectors().col(0);
  MeshPair out = m;
  for (auto& v : out.mesh3d) v -= amount * normal.dot(v - mean) * normal;
  return out;
}

TEST(Isometry, ExactlyDevelopableSheetHasZeroIsometryEnergy) {
  Problem p;
  p.meshes = CurledSheet(12, 9, 0.6, 0.45, 0.3);
  const auto e = isometry::Evaluate(p);
  EXPECT_LT(e.terms.iso, 1e-24);
  EXPECT_LT(isometry::IsometryEdgeError(p.meshes).max, 1e-12);
  EXPECT_EQ(e.terms.dist, 0);
  // Bending it is not an isometry any more: E_iso grows.
  p.meshes.mesh3d[p.meshes.grid.Index(4, 5)].z() += 0.01;
  EXPECT_GT(isometry::Evaluate(p).terms.iso, 1e-8);
}

TEST(Isometry, TrueMeshesOfEveryDataSetAreIsometric) {
  const auto sets = DataSetsWithGroundTruth();
  if (sets.empty()) GTEST_SKIP() << "no data sets with ground truth";
  for (const auto& set : sets) {
    auto gt = testing::LoadGroundTruth(set);
    ASSERT_TRUE(gt);
    Problem p;
    p.meshes = testing::TrueMeshPair(*gt, gt->cameras.views[0].image);
    const auto e = isometry::Evaluate(p);
    const auto edge = isometry::IsometryEdgeError(p.meshes);
    // "≈ 0": far below what a uniform 1 % stretch of M' costs (E_iso is a
    // mean squared strain; creases sharper than the truth's 1 mm grid leave
    // a little).
    Problem stretched = p;
    for (auto& v : stretched.meshes.mesh2d) v *= 1.01;
    const double one_percent = isometry::Evaluate(stretched).terms.iso;
    EXPECT_LT(e.terms.iso, 0.2 * one_percent) << set;
    EXPECT_LT(edge.mean, 1e-3) << set;
    std::cout << set.filename() << ": E_iso " << e.terms.iso << " (1 % stretch: " << one_percent
              << "), edge error mean " << edge.mean << " max " << edge.max << "\n";
  }
}

// --- derivatives -----------------------------------------------------------

using isometry::internal::Row;
using isometry::internal::State;
using isometry::internal::StepData;

// All rows of one term, in emission order.
std::vector<Row> RowsOf(const State& s, const StepData& d, int term) {
  std::vector<Row> rows;
  isometry::internal::ForEachRow(s, d, [&](int t, const Row& r) {
    if (t == term) rows.push_back(r);
  });
  return rows;
}

// The paper's c_iso compares a quad's diagonals only: a quad of M whose two
// diagonals keep their vectors but are pushed apart out of the plane (a
// twist) costs nothing, though each edge is longer. The edge rows see it.
TEST(Isometry, EdgeRowsSeeATwistTheDiagonalsMiss) {
  using isometry::internal::State;
  using isometry::internal::StepData;
  State s;
  s.grid = {2, 2};
  const double twist = 0.3;
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c) {
      s.v2.emplace_back(c, r);
      s.v3.emplace_back(c, r, (r + c) % 2 ? twist : 0.0);
    }
  StepData d;
  EXPECT_NEAR(isometry::internal::EvaluateTerms(s, d).iso, 0, 1e-24);
  d.iso_edge_weight = 1;
  // Four edges of squared length 1 + twist² against 1, each row / √2.
  EXPECT_NEAR(isometry::internal::EvaluateTerms(s, d).iso, 4 * 0.5 * std::pow(twist, 4), 1e-12);
}

TEST(Isometry, AnalyticJacobianMatchesFiniteDifferencesForEveryTerm) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uni(-1, 1);
  State s;
  s.grid = {5, 4};
  const MeshPair sheet = CurledSheet(5, 4, 1.0, 0.75, 0.8);
  for (int i = 0; i < s.grid.NumVertices(); ++i) {
    s.v3.push_back(sheet.mesh3d[i] + 0.05 * Eigen::Vector3d(uni(rng), uni(rng), uni(rng)));
    s.v2.push_back(sheet.mesh2d[i] + 0.05 * Eigen::Vector2d(uni(rng), uni(rng)));
  }
  s.lines = {{0.3, 0.2}, {1.7, -0.1}};
  StepData d;
  d.iso_scale = 3.0;
  d.iso_edge_weight = 0.7;
  d.beta_point = 1;
  d.beta_normal = 0.1;
  for (int i = 0; i < 6; ++i) {
    d.points.push_back(s.v3[i + 3] + 0.1 * Eigen::Vector3d(uni(rng), uni(rng), uni(rng)));
    isometry::internal::Footpoint f;
    f.triangle = (5 * i) % (2 * s.grid.NumQuads());
    f.bary = Eigen::Vector3d(0.2, 0.3, 0.5);
    f.normal = Eigen::Vector3d(uni(rng), uni(rng), 1).normalized();
    f.inlier = i != 2;  // one outlier: no rows
    d.footpoints.push_back(f);
  }
  d.num_inliers = 5;
  for (int i = 0; i < 5; ++i) {
    isometry::Marker m;
    m.where = {(7 * i + 1) % (2 * s.grid.NumQuads()), Eigen::Vector3d(0.6, 0.1, 0.3)};
    m.ray_origin = Eigen::Vector3d(uni(rng), uni(rng), 0);
    m.ray_direction = Eigen::Vector3d(uni(rng), uni(rng), 1).normalized();
    m.line = i < 2 ? 0 : (i < 4 ? 1 : -1);
    // The last is held to a plane through its ray only (one row), with a
    // weight of its own.
    if (i == 4) {
      m.across = m.ray_direction.cross(Eigen::Vector3d(1, 0, 0)).normalized();
      m.weight = 2.5;
    }
    d.markers.push_back(m);
    d.marker_weights += m.weight;
  }
  const double h = 1e-6;
  const auto check = [&](int term) {
    const std::vector<Row> rows = RowsOf(s, d, term);
    ASSERT_FALSE(rows.empty()) << "term " << term;
    double worst = 0;
    // Vertex unknowns.
    for (int v = 0; v < s.grid.NumVertices(); ++v)
      for (int dof = 0; dof < 5; ++dof) {
        State plus = s, minus = s;
        if (dof < 3) {
          plus.v3[v][dof] += h;
          minus.v3[v][dof] -= h;
        } else {
          plus.v2[v][dof - 3] += h;
          minus.v2[v][dof - 3] -= h;
        }
        const auto rp = RowsOf(plus, d, term), rm = RowsOf(minus, d, term);
        ASSERT_EQ(rp.size(), rows.size());
        for (size_t k = 0; k < rows.size(); ++k) {
          const double numeric = (rp[k].value - rm[k].value) / (2 * h);
          double analytic = 0;
          for (int a = 0; a < rows[k].count; ++a)
            if (rows[k].vertex[a] == v) analytic += rows[k].d[a][dof];
          worst = std::max(worst, std::abs(numeric - analytic));
          EXPECT_NEAR(numeric, analytic, 1e-6 * (1 + std::abs(analytic)))
              << "term " << term << " row " << k << " vertex " << v << " dof " << dof;
        }
      }
    // Line unknowns.
    for (size_t l = 0; l < s.lines.size(); ++l)
      for (int which = 0; which < 2; ++which) {
        State plus = s, minus = s;
        (which == 0 ? plus.lines[l].theta : plus.lines[l].offset) += h;
        (which == 0 ? minus.lines[l].theta : minus.lines[l].offset) -= h;
        const auto rp = RowsOf(plus, d, term), rm = RowsOf(minus, d, term);
        for (size_t k = 0; k < rows.size(); ++k) {
          const double numeric = (rp[k].value - rm[k].value) / (2 * h);
          const double analytic =
              rows[k].line == int(l) ? (which == 0 ? rows[k].d_theta : rows[k].d_offset) : 0;
          EXPECT_NEAR(numeric, analytic, 1e-6 * (1 + std::abs(analytic)))
              << "term " << term << " row " << k << " line " << l;
        }
      }
  };
  for (int term = 0; term < isometry::internal::kNumTerms; ++term) check(term);
}

class BlockMatrix : public ::testing::TestWithParam<std::pair<int, int>> {};

TEST_P(BlockMatrix, MatchesDenseJtJ) {
  // JᵀJ assembled in blocks and multiplied equals the dense product (also on
  // grids two or three vertices wide, where neighbour offsets coincide).
  QuadGrid g{GetParam().first, GetParam().second};
  isometry::internal::GridBlockMatrix H(g);
  const int n = 5 * g.NumVertices();
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(n, n);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uni(-1, 1);
  auto random5 = [&] {
    return isometry::internal::Vec5d(uni(rng), uni(rng), uni(rng), uni(rng), uni(rng));
  };
  for (int q = 0; q < g.NumQuads(); ++q) {
    const auto c = g.Quad(q);
    std::array<isometry::internal::Vec5d, 4> d;
    for (auto& x : d) x = random5();
    for (int a = 0; a < 4; ++a)
      for (int b = a; b < 4; ++b) {
        H.AddOuter(c[a], d[a], c[b], d[b]);
        dense.block<5, 5>(5 * c[a], 5 * c[b]) += d[a] * d[b].transpose();
        if (a != b) dense.block<5, 5>(5 * c[b], 5 * c[a]) += d[b] * d[a].transpose();
      }
  }
  // Fairness-like couplings two steps apart along a column and a row.
  const auto da = random5(), db = random5();
  std::vector<std::pair<int, int>> pairs = {{g.Index(1, 0), g.Index(3, 0)}};
  if (g.nx > 2) pairs.push_back({g.Index(2, g.nx - 3), g.Index(2, g.nx - 1)});
  for (const auto& [a, b] : pairs) {
    H.AddOuter(a, da, b, db);
    dense.block<5, 5>(5 * a, 5 * b) += da * db.transpose();
    dense.block<5, 5>(5 * b, 5 * a) += db * da.transpose();
  }
  Eigen::VectorXd x = Eigen::VectorXd::Random(n), y;
  H.Multiply(x, y);
  EXPECT_LT((y - dense * x).norm(), 1e-10 * (1 + y.norm()));
  H.Multiply(x, y, 2);
  EXPECT_LT((y - dense * x).norm(), 1e-10 * (1 + y.norm()));
  Eigen::SparseMatrix<double> upper;
  H.ToSparseUpper(upper, Eigen::VectorXd::Constant(n, 0.5));
  Eigen::MatrixXd full = Eigen::MatrixXd(upper).selfadjointView<Eigen::Upper>();
  Eigen::MatrixXd expected = dense;
  expected.diagonal().array() += 0.5;
  EXPECT_LT((full - expected).norm(), 1e-10 * expected.norm());
  EXPECT_THROW(H.AddOuter(g.Index(0, 0), da, g.Index(3, g.nx - 1), db), std::logic_error);
}

INSTANTIATE_TEST_SUITE_P(Grids, BlockMatrix,
                         ::testing::Values(std::pair{4, 5}, std::pair{2, 5}, std::pair{3, 4}));

// --- solving -----------------------------------------------------------------

TEST(Isometry, SolveFitsNoisyPointsAndFlagsOutliers) {
  const MeshPair truth = CurledSheet(21, 16, 0.8, 0.6, 0.45);
  const double size = isometry::ModelSize(truth);
  const auto sample = SampleSurface(truth, 3000, 0.002 * size, 0.05, 11);
  Problem p;
  p.meshes = Flattened(truth, 0.6);
  p.points = sample.points;
  const double before = SurfaceDistance(p.meshes, truth).mean;
  const auto result = isometry::Solve(p);
  const double after = SurfaceDistance(result.meshes, truth).mean;
  EXPECT_LT(after, 0.3 * before);
  EXPECT_LT(after, 0.005 * size);
  EXPECT_LT(isometry::IsometryEdgeError(result.meshes).mean, 0.005);
  // Far outliers are flagged, true points are kept.
  isometry::TriangleMeshIndex index(truth.mesh3d, truth.grid.Triangles());
  int far = 0, far_flagged = 0, true_points = 0, true_kept = 0;
  for (size_t i = 0; i < sample.points.size(); ++i) {
    if (sample.outlier[i]) {
      if (index.Closest(sample.points[i])->distance > 0.08 * size) {
        ++far;
        far_flagged += !result.point_inlier[i];
      }
    } else {
      ++true_points;
      true_kept += result.point_inlier[i];
    }
  }
  ASSERT_GT(far, 10);
  EXPECT_EQ(far_flagged, far);
  EXPECT_GT(true_kept, 0.99 * true_points);
  const auto& report = result.report;
  ASSERT_GE(report.iterations.size(), 2u);
  EXPECT_LT(report.iterations.back().F, report.iterations.front().F);
  EXPECT_EQ(report.method, "gauss-newton/cg");
  EXPECT_EQ(report.iterations.back().inliers + report.iterations.back().outliers,
            int(sample.points.size()));
  const Json j = isometry::ToJson(report);
  EXPECT_EQ(j["iterations"].size(), report.iterations.size());
  EXPECT_TRUE(j["iterations"][0]["terms"].contains("ray"));
}

TEST(Isometry, SolveMovesTowardTheTruthOnEveryDataSet) {
  // Three data sets spread over each directory keep the test lean (init-mesh's
  // tests cover every data set). Picked per directory, so that the samples
  // tested are the same whether or not the realistic sets are present.
  const auto all = DataSetsWithGroundTruth();
  if (all.empty()) GTEST_SKIP() << "no data sets with ground truth";
  std::map<fs::path, std::vector<fs::path>> by_directory;
  for (const fs::path& set : all) by_directory[set.parent_path()].push_back(set);
  std::vector<fs::path> sets;
  for (const auto& [directory, in_it] : by_directory) {
    sets.push_back(in_it.front());
    if (in_it.size() > 2) sets.push_back(in_it[in_it.size() / 2]);
    if (in_it.size() > 1) sets.push_back(in_it.back());
  }
  for (const auto& set : sets) {
    auto gt = testing::LoadGroundTruth(set);
    ASSERT_TRUE(gt);
    const std::string ref = testing::ChooseReferenceView(*gt);
    const MeshPair fine = testing::TrueMeshPair(*gt, ref);
    const int step = std::max(1, std::max(fine.grid.nx, fine.grid.ny) / 30);
    const MeshPair truth = testing::SubGrid(fine, step);
    testing::TempDir dir;
    testing::SfmFromTruthOptions so;
    so.num_points = 3000;
    so.noise = 0.002;
    so.outlier_fraction = 0.05;
    testing::WriteSfmFromTruth(*gt, ref, dir / "10_sfm", so);
    const PlyData cloud = ReadPly(dir / "10_sfm/points.ply");
    Problem p;
    p.meshes = Flattened(truth, 0.5);
    p.points = cloud.vertices;
    const double diag = gt->Diagonal() * testing::ReferenceFrame(*gt, ref).scale;
    const double before = SurfaceDistance(p.meshes, fine).mean;
    const auto result = isometry::Solve(p);
    const double after = SurfaceDistance(result.meshes, fine).mean;
    EXPECT_LT(after, 0.7 * before) << set;
    EXPECT_LT(after, 0.004 * diag) << set;
    // WriteSfmFromTruth appends its outliers after the surface points.
    isometry::TriangleMeshIndex index(fine.mesh3d, fine.grid.Triangles());
    int far = 0, flagged = 0;
    for (size_t i = so.num_points; i < cloud.vertices.size(); ++i)
      if (index.Closest(cloud.vertices[i])->distance > 0.1 * result.report.model_size) {
        ++far;
        flagged += !result.point_inlier[i];
      }
    EXPECT_EQ(flagged, far) << set;
    std::cout << set.filename() << ": mean distance to truth " << before / diag * 100 << "% -> "
              << after / diag * 100 << "% of the diagonal, " << result.report.iterations.size()
              << " outer iterations, " << result.report.seconds << " s, far outliers flagged "
              << flagged << "/" << far << "\n";
  }
}

TEST(Isometry, FlatFairnessEvensOutUnevenSpacing) {
  // A flat page whose grid columns are spaced ever wider (as a panel seen at
  // a grazing angle is by the reference image's even grid). The paper's
  // E_fair(M') evens the spacing out (the points let M slide along itself).
  MeshPair page;
  page.grid = {21, 11};
  for (int r = 0; r < page.grid.ny; ++r)
    for (int c = 0; c < page.grid.nx; ++c) {
      const double u = double(c) / (page.grid.nx - 1);
      const double x = 0.8 * std::expm1(3 * u) / std::expm1(3.0);
      const Eigen::Vector2d p(x, 0.5 * r / (page.grid.ny - 1));
      page.mesh2d.push_back(p);
      page.mesh3d.emplace_back(p.x(), p.y(), 0.0);
    }
  Problem problem;
  problem.meshes = page;
  problem.points = page.mesh3d;
  // Widest over narrowest column gap of M' along the middle row.
  const auto gap_ratio = [&](const MeshPair& m) {
    const int r = m.grid.ny / 2, last = m.grid.nx - 1;
    return (m.mesh2d[m.grid.Index(r, last)] - m.mesh2d[m.grid.Index(r, last - 1)]).norm() /
           (m.mesh2d[m.grid.Index(r, 1)] - m.mesh2d[m.grid.Index(r, 0)]).norm();
  };
  const double before = gap_ratio(page);
  ASSERT_GT(before, 10);
  EXPECT_LT(gap_ratio(isometry::Solve(problem).meshes), 0.5 * before);
}

TEST(Isometry, FairnessSparedAtAFoldKeepsItSharp) {
  // A sheet folded through 80 degrees at its middle column, fitted from the
  // flat sheet. With λ3 everywhere the fold comes out rounded; with the
  // triplets across the fold spared (as optimize does where the photo shows
  // a crease) M follows the points there.
  const int nx = 21;
  const MeshPair truth = ProfileSheet(nx, 11, 0.8, 0.4, [](int c) {
    return c == 10 ? 80 * M_PI / 180 : 0.0;  // the kink at vertex column 10
  });
  const auto sample = SampleSurface(truth, 4000, 0.0005, 0, 5);
  Problem p;
  p.meshes = Flattened(truth, 0.3);
  p.points = sample.points;
  isometry::SolveOptions o;
  o.weights.fair3d = 3e-3;
  const auto fold_distance = [&](const MeshPair& m) {
    double worst = 0;
    for (int r = 0; r < m.grid.ny; ++r)
      worst = std::max(
          worst, (m.mesh3d[m.grid.Index(r, 10)] - truth.mesh3d[truth.grid.Index(r, 10)]).norm());
    return worst;
  };
  const double rounded = fold_distance(isometry::Solve(p, o).meshes);
  const auto triplets = isometry::FairTriplets(p.meshes.grid);
  p.fair3d_weights.assign(triplets.size(), 1.0);
  for (size_t t = 0; t < triplets.size(); ++t)
    if (triplets[t][1] % nx == 10 && triplets[t][0] % nx != 10) p.fair3d_weights[t] = 0.02;
  const double sharp = fold_distance(isometry::Solve(p, o).meshes);
  std::printf("fold vertices off the truth: %.5f rounded, %.5f spared\n", rounded, sharp);
  EXPECT_LT(sharp, 0.5 * rounded);
  // A weight per triplet or none, each finite and not negative.
  p.fair3d_weights.back() = NAN;
  EXPECT_THROW(isometry::Solve(p, o), std::invalid_argument);
  p.fair3d_weights.pop_back();
  EXPECT_THROW(isometry::Solve(p, o), std::invalid_argument);
}

TEST(Isometry, GaussNewtonCholmodCgAndLbfgsAgree) {
  const MeshPair truth = CurledSheet(9, 7, 0.8, 0.6, 0.5);
  const double size = isometry::ModelSize(truth);
  Problem p;
  p.meshes = Flattened(truth, 0.5);
  p.points = SampleSurface(truth, 800, 0.001 * size, 0.0, 5).points;
  SolveOptions o;
  o.relative_tolerance = 1e-6;
  o.max_outer_iterations = 40;
  o.linear_solver = isometry::LinearSolver::kDirect;
  const auto direct = isometry::Solve(p, o);
  o.linear_solver = isometry::LinearSolver::kConjugateGradient;
  o.cg_tolerance = 1e-8;
  o.cg_max_iterations = 2000;
  const auto cg = isometry::Solve(p, o);
  o.method = isometry::Method::kLbfgs;
  o.lbfgs_iterations = 500;
  o.max_outer_iterations = 20;
  const auto lbfgs = isometry::Solve(p, o);
  EXPECT_EQ(cg.report.method, "gauss-newton/cg");
  EXPECT_EQ(lbfgs.report.method, "lbfgs");
  const double f = direct.report.iterations.back().F;
  EXPECT_NEAR(cg.report.iterations.back().F, f, 0.02 * f);
  EXPECT_NEAR(lbfgs.report.iterations.back().F, f, 0.05 * f);
  // Same surface (M' may differ by a rigid motion, M must not).
  EXPECT_LT(SurfaceDistance(cg.meshes, direct.meshes).max, 1e-3 * size);
  EXPECT_LT(SurfaceDistance(lbfgs.meshes, direct.meshes).mean, 2e-3 * size);
}

TEST(Isometry, MarkersStraightenLinesAndFollowTheirRays) {
  // True pair: a curled sheet seen by an identity camera. Markers: points of
  // two straight lines of the flat page (a row and a column), with the rays
  // through their true 3D positions. Start: M' with a bent row and column.
  const MeshPair truth = CurledSheet(11, 9, 0.8, 0.6, 0.6);
  Problem p;
  p.meshes = truth;
  const double bump = 0.02;
  for (int r = 0; r < truth.grid.ny; ++r)
    for (int c = 0; c < truth.grid.nx; ++c)
      p.meshes.mesh2d[truth.grid.Index(r, c)].y() += bump * std::sin(0.5 * c) * (r == 4);
  for (int r = 0; r < truth.grid.ny; ++r) p.meshes.mesh3d[truth.grid.Index(r, 5)].z() += 0.01;
  isometry::FlatMeshLocator locator(truth);
  p.lines = {{M_PI / 2, 0}, {0, 0}};
  for (int k = 0; k <= 40; ++k) {
    for (int line = 0; line < 2; ++line) {
      const Eigen::Vector2d flat =
          line == 0 ? Eigen::Vector2d(0.02 * k, 0.3) : Eigen::Vector2d(0.4, 0.015 * k);
      auto where = locator.Locate(flat);
      ASSERT_TRUE(where);
      isometry::Marker m;
      m.where = *where;
      m.line = line;
      m.ray_origin = Eigen::Vector3d::Zero();
      m.ray_direction = PointOnMesh3d(truth, *where).normalized();
      p.markers.push_back(m);
    }
  }
  p.lines[0].offset = 0.3;
  p.lines[1].offset = 0.4;
  SolveOptions o;
  o.weights.dist = 0;
  const auto before = isometry::Evaluate(p, o);
  const auto result = isometry::Solve(p, o);
  const auto& last = result.report.iterations.back();
  EXPECT_LT(last.terms.line, 0.05 * before.terms.line);
  EXPECT_LT(last.terms.ray, 0.05 * before.terms.ray);
  EXPECT_EQ(last.markers, 82);
  EXPECT_EQ(last.lines, 2);
  // The fitted lines stay horizontal and vertical.
  EXPECT_NEAR(std::abs(std::sin(result.lines[0].theta)), 1, 1e-3);
  EXPECT_NEAR(std::abs(std::cos(result.lines[1].theta)), 1, 1e-3);

  // Feature line projection moves markers onto their lines (E_line = 0 at
  // the start of each step) and still converges.
  o.project_markers = true;
  const auto projected = isometry::Solve(p, o);
  EXPECT_LT(projected.report.iterations.back().terms.line, 0.05 * before.terms.line);
  bool moved = false;
  for (size_t i = 0; i < p.markers.size(); ++i)
    moved = moved || (projected.markers[i].where.bary - p.markers[i].where.bary).norm() > 1e-9;
  EXPECT_TRUE(moved);

  // Axis-aligned lines given slanted keep exactly the nearest axis under
  // both solvers; only their offsets move.
  o.project_markers = false;
  Problem slanted = p;
  slanted.lines[0].theta = M_PI / 2 + 0.05;
  slanted.lines[1].theta = -0.04;
  for (auto& l : slanted.lines) l.axis_aligned = true;
  for (const auto method : {isometry::Method::kGaussNewton, isometry::Method::kLbfgs}) {
    o.method = method;
    o.max_outer_iterations = 5;
    const auto held = isometry::Solve(slanted, o);
    EXPECT_EQ(held.lines[0].theta, M_PI / 2);
    EXPECT_EQ(held.lines[1].theta, 0);
    EXPECT_LT(held.report.iterations.back().terms.line, 0.05 * before.terms.line);
  }
}

TEST(Isometry, SolveIsTheSameForAnyNumberOfThreads) {
  // On a grid as optimize's coarsest (651 vertices, conjugate gradients to
  // the coarse tolerance) and one past 1000 vertices (the fine tolerance),
  // both large enough for the parallel loops (kMinParallelVertices; several
  // chunks of points): the solver's sums are added in an order that does not
  // depend on the threads, so one thread and two give bit-identical meshes
  // (the solver picks the number per outer iteration from the machine's load).
  for (const auto& [nx, ny] : {std::pair{31, 21}, std::pair{61, 41}}) {
    SCOPED_TRACE(std::to_string(nx) + "x" + std::to_string(ny));
    ASSERT_GE(nx * ny, isometry::internal::kMinParallelVertices);
    const MeshPair truth = CurledSheet(nx, ny, 0.8, 0.6, 0.45);
    Problem p;
    p.meshes = Flattened(truth, 0.6);
    p.points = SampleSurface(truth, 5000, 0.002 * isometry::ModelSize(truth), 0.02, 5).points;
    SolveOptions o;
    o.max_outer_iterations = 4;
    o.num_threads = 1;
    const auto one = isometry::Solve(p, o);
    o.num_threads = 2;
    const auto two = isometry::Solve(p, o);
    EXPECT_EQ(one.report.method, "gauss-newton/cg");
    ASSERT_EQ(one.report.iterations.size(), two.report.iterations.size());
    for (size_t i = 0; i < one.report.iterations.size(); ++i)
      EXPECT_EQ(one.report.iterations[i].F, two.report.iterations[i].F) << "iteration " << i;
    EXPECT_TRUE(one.meshes.mesh3d == two.meshes.mesh3d);
    EXPECT_TRUE(one.meshes.mesh2d == two.meshes.mesh2d);
  }
}

// A 6x5 curled sheet started flat, fitted to 300 exact points of it: small,
// and a few outer iterations from converged.
Problem FlatStartOfACurledSheet() {
  Problem p;
  const MeshPair truth = CurledSheet(6, 5, 0.5, 0.4, 0.4);
  p.meshes = Flattened(truth, 0.5);
  p.points = SampleSurface(truth, 300, 0.0, 0.0, 2).points;
  return p;
}

TEST(Isometry, CallbackSeesEveryOuterIteration) {
  const Problem p = FlatStartOfACurledSheet();
  SolveOptions o;
  int calls = 0;
  o.on_outer_iteration = [&](const isometry::OuterIterationContext& c) {
    EXPECT_EQ(c.iteration, calls++);
    EXPECT_EQ(c.meshes->grid.nx, 6);
  };
  const auto r = isometry::Solve(p, o);
  EXPECT_EQ(calls, int(r.report.iterations.size()));
}

// A marker whose ray the callback moves away on every other iteration makes
// F rise and fall: with max_rises the solve stops at the given rise.
TEST(Isometry, StopsWhenFOscillates) {
  Problem p;
  const MeshPair truth = CurledSheet(6, 5, 0.5, 0.4, 0.4);
  p.meshes = truth;
  p.points = SampleSurface(truth, 300, 0.0, 0.0, 2).points;
  isometry::Marker m;
  m.where = {7, Eigen::Vector3d(0.3, 0.3, 0.4)};
  m.ray_direction = Eigen::Vector3d::UnitZ();
  p.markers = {m};
  SolveOptions o;
  o.relative_tolerance = 1e-12;
  o.max_outer_iterations = 40;
  o.max_rises = 2;
  o.on_outer_iteration = [&](const isometry::OuterIterationContext& c) {
    const Eigen::Vector3d at = PointOnMesh3d(*c.meshes, (*c.markers)[0].where);
    (*c.markers)[0].ray_origin = at + Eigen::Vector3d(c.iteration % 2 ? 0.05 : 0.0, 0, 0);
  };
  const auto r = isometry::Solve(p, o);
  const auto& it = r.report.iterations;
  EXPECT_EQ(r.report.stop_reason, "oscillating");
  int rises = 0;
  for (size_t i = 1; i < it.size(); ++i) rises += it[i].F > it[i - 1].F;
  EXPECT_EQ(rises, 2);
  EXPECT_GT(it.back().F, it[it.size() - 2].F);
  o.max_rises = 0;
  EXPECT_EQ(isometry::Solve(p, o).report.iterations.size(), 41u);
}

// converged_iterations = k: the solve ends at the k-th outer iteration with
// |ΔF/F| < ε, never on the first short step.
TEST(Isometry, ConvergenceWaitsForTheKthShortStep) {
  const Problem p = FlatStartOfACurledSheet();
  SolveOptions o;
  o.relative_tolerance = 0.05;
  const auto once = isometry::Solve(p, o);
  o.converged_iterations = 3;
  const auto thrice = isometry::Solve(p, o);
  ASSERT_EQ(thrice.report.stop_reason, "converged");
  const auto& it = thrice.report.iterations;
  ASSERT_GE(it.size(), 4u);
  int short_steps = 0;
  for (size_t i = 1; i < it.size(); ++i)
    short_steps += std::abs(it[i].F - it[i - 1].F) <= o.relative_tolerance * it[i - 1].F;
  EXPECT_EQ(short_steps, 3);
  EXPECT_LE(std::abs(it.back().F - it[it.size() - 2].F),
            o.relative_tolerance * it[it.size() - 2].F);
  EXPECT_GE(it.size(), once.report.iterations.size() + 2);
  EXPECT_LE(it.back().F, once.report.iterations.back().F * (1 + 1e-9));
}

TEST(Isometry, RejectsInconsistentProblems) {
  Problem p;
  p.meshes = CurledSheet(4, 3, 0.5, 0.4, 0.4);
  Problem bad = p;
  bad.meshes.mesh2d.pop_back();
  EXPECT_THROW(isometry::Solve(bad), std::invalid_argument);
  bad = p;
  bad.points.push_back(Eigen::Vector3d(NAN, 0, 0));
  EXPECT_THROW(isometry::Solve(bad), std::invalid_argument);
  bad = p;
  bad.markers.push_back(
      {{99, Eigen::Vector3d(1, 0, 0)}, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), -1});
  EXPECT_THROW(isometry::Solve(bad), std::invalid_argument);
  bad = p;
  bad.markers.push_back(
      {{0, Eigen::Vector3d(1, 0, 0)}, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 3});
  EXPECT_THROW(isometry::Solve(bad), std::invalid_argument);
  for (const double weight : {0.0, -1.0, double(NAN)}) {
    bad = p;
    isometry::Marker m;
    m.where = {0, Eigen::Vector3d(1, 0, 0)};
    m.weight = weight;
    bad.markers.push_back(m);
    EXPECT_THROW(isometry::Solve(bad), std::invalid_argument) << weight;
  }
  bad = p;
  for (auto& v : bad.meshes.mesh3d) v.setZero();
  EXPECT_THROW(isometry::Solve(bad), std::invalid_argument);
}

TEST(Isometry, AMarkerOfWeightKCountsAsKCopies) {
  // Plane markers on a curled sheet, pulled off it: one of weight 3 gives the
  // same solve as three copies of weight 1 (E_ray and H2 alike).
  const MeshPair sheet = CurledSheet(9, 7, 0.8, 0.6, 0.6);
  Problem weighted;
  weighted.meshes = sheet;
  for (int i = 0; i < 6; ++i) {
    isometry::Marker m;
    m.where = {7 * i + 3, Eigen::Vector3d(0.2, 0.3, 0.5)};
    const Eigen::Vector3d x = PointOnMesh3d(sheet, m.where) + Eigen::Vector3d(0, 0, 0.03 * i);
    m.ray_origin = Eigen::Vector3d(0, 0, -2);
    m.ray_direction = (x - m.ray_origin).normalized();
    m.across = m.ray_direction.cross(Eigen::Vector3d(0, 1, 0)).normalized();
    weighted.markers.push_back(m);
  }
  Problem copies = weighted;
  weighted.markers[2].weight = 3;
  copies.markers.push_back(copies.markers[2]);
  copies.markers.push_back(copies.markers[2]);
  SolveOptions o;
  o.weights.dist = 0;
  o.max_outer_iterations = 5;
  // Exact steps: CG stops at a tolerance, and the two sums of rows are the
  // same only up to rounding, which its iteration counts would magnify.
  o.linear_solver = isometry::LinearSolver::kDirect;
  const auto a = isometry::Solve(weighted, o), b = isometry::Solve(copies, o);
  double worst = 0;
  for (size_t v = 0; v < a.meshes.mesh3d.size(); ++v)
    worst = std::max(worst, (a.meshes.mesh3d[v] - b.meshes.mesh3d[v]).norm());
  EXPECT_LT(worst, 1e-9);
  EXPECT_NEAR(a.report.iterations.back().terms.ray, b.report.iterations.back().terms.ray, 1e-12);
  // and not as one copy.
  weighted.markers[2].weight = 1;
  const auto c = isometry::Solve(weighted, o);
  double moved = 0;
  for (size_t v = 0; v < a.meshes.mesh3d.size(); ++v)
    moved = std::max(moved, (a.meshes.mesh3d[v] - c.meshes.mesh3d[v]).norm());
  EXPECT_GT(moved, 1e-4);
}

// --- subdivision, unfolding, queries ----------------------------------------

TEST(Isometry, SubdivisionKeepsTheTruePairIsometric) {
  // Analytic: a coarse exactly-isometric curl stays nearly isometric.
  const MeshPair sheet = CurledSheet(11, 8, 0.8, 0.6, 0.4);
  MeshPair fine = isometry::SubdivideCatmullClark(isometry::SubdivideCatmullClark(sheet));
  EXPECT_EQ(fine.grid.nx, 41);
  EXPECT_EQ(fine.grid.ny, 29);
  EXPECT_LT(isometry::IsometryEdgeError(fine).mean, 0.003);
  // Corners stay; M' of a regular grid stays a regular grid.
  EXPECT_LT((fine.mesh3d[0] - sheet.mesh3d[0]).norm(), 1e-12);
  EXPECT_LT((fine.mesh2d.back() - sheet.mesh2d.back()).norm(), 1e-12);
  EXPECT_NEAR((fine.mesh2d[1] - fine.mesh2d[0]).norm(), 0.8 / 40, 1e-12);

  const auto sets = DataSetsWithGroundTruth();
  for (const auto& set : sets) {
    auto gt = testing::LoadGroundTruth(set);
    ASSERT_TRUE(gt);
    const MeshPair truth = testing::TrueMeshPair(*gt, gt->cameras.views[0].image);
    const double before = isometry::IsometryEdgeError(truth).mean;
    const double after = isometry::IsometryEdgeError(isometry::SubdivideCatmullClark(truth)).mean;
    EXPECT_LT(after, before + 0.002) << set;
    // Coarse grids cut creases: Catmull-Clark rounds them a little more.
    // A coarse sub-grid of the truth, subdivided twice.
    const MeshPair coarse = testing::SubGrid(truth, 8);
    const double coarse_before = isometry::IsometryEdgeError(coarse).mean;
    const double coarse_after =
        isometry::IsometryEdgeError(
            isometry::SubdivideCatmullClark(isometry::SubdivideCatmullClark(coarse)))
            .mean;
    EXPECT_LT(coarse_after, 3 * coarse_before + 0.002) << set;
    std::cout << set.filename() << ": edge error " << before << " -> " << after << " (full truth), "
              << coarse_before << " -> " << coarse_after << " (every 8th line, subdivided twice)\n";
  }
}

TEST(Isometry, SubdividedSurfacePointStaysOnTheSameFlatPoint) {
  MeshPair m = CurledSheet(5, 4, 0.8, 0.6, 0.5);  // M' is a regular grid
  const MeshPair fine = isometry::SubdivideCatmullClark(m);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> uni(0, 1);
  for (int k = 0; k < 200; ++k) {
    double a = uni(rng), b = uni(rng);
    if (a + b > 1) {
      a = 1 - a;
      b = 1 - b;
    }
    SurfacePoint p{int(uni(rng) * 2 * m.grid.NumQuads()), Eigen::Vector3d(1 - a - b, a, b)};
    const SurfacePoint q = isometry::SubdividedSurfacePoint(m.grid, p);
    EXPECT_LT((PointOnMesh2d(fine, q) - PointOnMesh2d(m, p)).norm(), 1e-12);
    EXPECT_GE(q.bary.minCoeff(), -1e-12);
  }
}

TEST(Isometry, UnfoldArapFlattensADevelopableSheet) {
  const MeshPair sheet = CurledSheet(21, 15, 0.8, 0.6, 0.35);
  // Initial layout: the sheet seen by a pinhole camera (perspective + curl).
  std::vector<Eigen::Vector2d> image;
  for (const auto& v : sheet.mesh3d) image.push_back(1000 * v.head<2>() / v.z());
  const auto result = isometry::UnfoldArap(sheet.grid, sheet.mesh3d, image);
  MeshPair pair = sheet;
  pair.mesh2d = result.mesh2d;
  EXPECT_LT(isometry::IsometryEdgeError(pair).mean, 0.002);
  // Same orientation as the image layout (no mirror).
  auto signed_area = [](const std::vector<Eigen::Vector2d>& u) {
    const Eigen::Vector2d a = u[1] - u[0], b = u[22] - u[0];
    return a.x() * b.y() - a.y() * b.x();
  };
  EXPECT_GT(signed_area(result.mesh2d) * signed_area(image), 0);
}

TEST(Isometry, ClosestPointIsExact) {
  const MeshPair sheet = CurledSheet(15, 10, 0.8, 0.6, 0.3);
  const auto tris = sheet.grid.Triangles();
  isometry::TriangleMeshIndex index(sheet.mesh3d, tris);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> uni(-0.6, 0.6);
  for (int k = 0; k < 300; ++k) {
    const Eigen::Vector3d p(uni(rng), uni(rng), 1 + uni(rng));
    double best = 1e9;
    for (const Triangle& t : tris)
      best = std::min(best, isometry::ClosestPointOnTriangle(p, sheet.mesh3d[t[0]],
                                                             sheet.mesh3d[t[1]], sheet.mesh3d[t[2]])
                                .distance);
    const auto c = index.Closest(p);
    ASSERT_TRUE(c);
    EXPECT_NEAR(c->distance, best, 1e-12);
    EXPECT_LT((PointOnMesh3d(sheet, {c->triangle, c->bary}) - c->point).norm(), 1e-12);
    // A bound below the distance rejects the point.
    if (best > 0.01) {
      EXPECT_FALSE(index.Closest(p, 0.5 * best));
    }
  }
}

TEST(Isometry, FlatMeshLocatorFindsTheContainingTriangle) {
  MeshPair sheet = CurledSheet(8, 6, 0.8, 0.6, 0.3);
  // Shear M' so triangles are not axis aligned.
  for (auto& v : sheet.mesh2d) v.x() += 0.3 * v.y();
  isometry::FlatMeshLocator locator(sheet);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> uni(0, 1);
  for (int k = 0; k < 300; ++k) {
    const Eigen::Vector2d p(uni(rng) * 0.8 + 0.3 * 0.6 * uni(rng), uni(rng) * 0.6);
    const auto where = locator.Locate(p);
    // Inside iff it is inside the sheared rectangle.
    const bool inside = p.x() >= 0.3 * p.y() && p.x() <= 0.8 + 0.3 * p.y();
    ASSERT_EQ(bool(where), inside) << p.transpose();
    if (where) {
      EXPECT_LT((PointOnMesh2d(sheet, *where) - p).norm(), 1e-12);
      EXPECT_GE(where->bary.minCoeff(), -1e-9);
    }
  }
}

}  // namespace
}  // namespace docunfold
