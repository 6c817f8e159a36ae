// The solver's flags, declared once for every stage that runs it.
#include "common/isometry/isometry.h"
#include "common/option_table.h"

namespace docunfold::isometry {

void DeclareSolveOptions(OptionTable& table, SolveOptions* o) {
  table.Value("lambda-iso", &o->weights.iso, 0.0, 1e9, "λ1, weight of the isometry E_iso");
  table.Value("lambda-dist", &o->weights.dist, 0.0, 1e9,
              "λ2, weight of the distance to the points E_dist");
  table.Value("lambda-fair3d", &o->weights.fair3d, 0.0, 1e9, "λ3, weight of the fairness of M");
  table.Value("lambda-fair2d", &o->weights.fair2d, 0.0, 1e9, "λ4, weight of the fairness of M'");
  table.Value("outlier-distance", &o->outlier_distance, 0.0, 10.0,
              "φ: points farther from M than this fraction of the model size are ignored "
              "(re-decided every outer iteration)");
  table.Choice("iso-normalization", &o->iso_normalization,
               {{"strain", IsoNormalization::kStrain}, {"raw", IsoNormalization::kRaw}},
               "strain: E_iso as mean squared strain (independent of the grid's resolution); "
               "raw: the paper's sum of squared c_iso");
  table.Value("iso-edges", &o->iso_edges, 0.0, 100.0,
              "weight of E_iso's edge-length rows next to the paper's diagonal rows (0 = "
              "diagonals only, as in the paper)");
  table.Choice("solver", &o->method, {{"gn", Method::kGaussNewton}, {"lbfgs", Method::kLbfgs}},
               "gn: Gauss-Newton/Levenberg-Marquardt with sparse Cholesky; lbfgs: L-BFGS (the "
               "paper's)");
  table.Choice("linear-solver", &o->linear_solver,
               {{"auto", LinearSolver::kAuto},
                {"direct", LinearSolver::kDirect},
                {"cg", LinearSolver::kConjugateGradient}},
               "Gauss-Newton's normal equations: auto (conjugate gradients, solved tighter on "
               "coarse grids), direct (sparse Cholesky, exact steps) or cg (conjugate gradients "
               "to one loose tolerance on every grid)");
  table.Value("max-iterations", &o->max_outer_iterations, 0, 100000,
              "outer iterations at most (per round), Q");
  table.Value("tolerance", &o->relative_tolerance, 0.0, 1.0,
              "stop when |ΔF/F| between outer iterations is below this, ε");
  table.Value("converged-max-damping", &o->converged_max_damping, 0.0, 1e6,
              "|ΔF/F| below --tolerance does not stop the solve while the Levenberg-Marquardt "
              "damping is above this (its steps are then short, not converged); 0 = it always "
              "stops");
  table.Value("threads", &o->num_threads, 1, 256,
              "solver threads at most; each outer iteration runs fewer while other processes "
              "keep the cores busy");
}

}  // namespace docunfold::isometry
