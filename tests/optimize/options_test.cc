// optimize's flags: what each round hands the solver by default, and flags
// that parse into it.
#include <gtest/gtest.h>

#include "common/option_table.h"
#include "stages/optimize/optimize.h"

namespace docunfold::optimize {
namespace {

// Parses `args` (after the program name) into a fresh OptimizeOptions.
OptimizeOptions Parse(std::vector<std::string> args, Json* record = nullptr) {
  CLI::App app;
  OptionTable table(app);
  OptimizeOptions o;
  DeclareOptions(table, &o);
  std::vector<const char*> argv = {"optimize"};
  for (const std::string& a : args) argv.push_back(a.c_str());
  app.parse(int(argv.size()), argv.data());
  if (record) *record = table.Record();
  return o;
}

TEST(OptimizeOptions, RoundsHandTheSolverThePapersSettingsAndTheirStoppingRule) {
  const OptimizeOptions o = Parse({});
  const isometry::SolveOptions defaults;
  for (int r = 0; r < 4; ++r) {
    isometry::Weights w;
    w.line = w.ray = r + 1;
    const isometry::SolveOptions so = RoundSolveOptions(o, r, w);
    EXPECT_EQ(so.weights.iso, 1);
    EXPECT_EQ(so.weights.dist, 1);
    EXPECT_EQ(so.weights.fair3d, 1e-4);
    EXPECT_EQ(so.weights.fair2d, 0.1);
    EXPECT_EQ(so.weights.line, r + 1);
    EXPECT_EQ(so.weights.ray, r + 1);
    EXPECT_EQ(so.outlier_distance, 0.06);
    EXPECT_EQ(so.iso_edges, 0);
    EXPECT_EQ(so.iso_normalization, isometry::IsoNormalization::kStrain);
    // The first two rounds run to 1e-4 (the coarse grids are cheap), the
    // later ones to the paper's 1 %.
    EXPECT_EQ(so.relative_tolerance, r < 2 ? 1e-4 : 0.01) << r;
    EXPECT_EQ(so.max_outer_iterations, 100);
    // The first two rounds end at the second short step and never on
    // rises; the later ones at the first, or at the third rise.
    EXPECT_EQ(so.converged_iterations, r < 2 ? 2 : 1) << r;
    EXPECT_EQ(so.max_rises, r < 2 ? 0 : 3) << r;
    EXPECT_EQ(so.method, isometry::Method::kGaussNewton);
    EXPECT_EQ(so.linear_solver, isometry::LinearSolver::kAuto);
    EXPECT_TRUE(so.project_markers);
    EXPECT_EQ(so.num_threads, 2);
    EXPECT_EQ(so.converged_max_damping, defaults.converged_max_damping);
    EXPECT_EQ(so.beta_point, defaults.beta_point);
    EXPECT_EQ(so.beta_normal, defaults.beta_normal);
    EXPECT_TRUE(so.refit_lines);
    EXPECT_FALSE(so.on_outer_iteration);
  }
  EXPECT_TRUE(o.features);
  EXPECT_FALSE(o.boundary_only);
  EXPECT_TRUE(o.upright_by_lines);
  EXPECT_EQ(o.axis_lines, AxisLines::kAll);
}

TEST(OptimizeOptions, FlagsParseIntoTheOptionsAndTheRecord) {
  Json record;
  const OptimizeOptions o =
      Parse({"--no-feature-lines", "--no-projection", "--boundary-only", "--solver", "lbfgs",
             "--axis-lines", "none", "--merge-straightness", "0.2", "--lambda-line", "0.5",
             "--threads", "1", "--no-upright-by-lines"},
            &record);
  EXPECT_FALSE(o.features);
  EXPECT_FALSE(o.solve.project_markers);
  EXPECT_TRUE(o.boundary_only);
  EXPECT_EQ(o.solve.method, isometry::Method::kLbfgs);
  EXPECT_EQ(o.axis_lines, AxisLines::kNone);
  EXPECT_EQ(o.grouping.straightness, 0.2);
  EXPECT_EQ(o.solve.weights.line, 0.5);
  EXPECT_EQ(o.solve.num_threads, 1);
  EXPECT_FALSE(o.upright_by_lines);
  EXPECT_EQ(record.at("feature_lines"), false);
  EXPECT_EQ(record.at("projection"), false);
  EXPECT_EQ(record.at("solver"), "lbfgs");
  EXPECT_EQ(record.at("axis_lines"), "none");
  EXPECT_EQ(record.at("merge_straightness"), 0.2);
  EXPECT_FALSE(record.contains("straightness"));
  // Switches tried and not kept are gone.
  for (const char* gone : {"--line-spacing", "--corner-max-px", "--border-snap", "--fair2d-along",
                           "--unsupported-fairness", "--straightness"})
    EXPECT_THROW(Parse({gone, "1"}), CLI::ParseError) << gone;
}

}  // namespace
}  // namespace docunfold::optimize
