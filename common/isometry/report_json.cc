// log.json material: the solver's report as JSON.
#include <cmath>

#include "common/isometry/isometry.h"

namespace docunfold::isometry {
namespace {

Json IterationJson(const IterationReport& it) {
  Json j;
  j["iteration"] = it.iteration;
  j["F"] = it.F;
  j["terms"] = ToJson(it.terms);
  j["inliers"] = it.inliers;
  j["outliers"] = it.outliers;
  j["markers"] = it.markers;
  j["lines"] = it.lines;
  j["seconds"] = it.seconds;
  j["footpoint_seconds"] = it.footpoint_seconds;
  j["step_seconds"] = it.step_seconds;
  j["linear_iterations"] = it.linear_iterations;
  j["damping"] = it.damping;
  j["step_accepted"] = it.step_accepted;
  j["threads"] = it.threads;
  if (std::isfinite(it.F_after_step)) j["F_after_step"] = it.F_after_step;
  return j;
}

}  // namespace

Json ToJson(const TermValues& t) {
  return Json{{"iso", t.iso},       {"dist", t.dist}, {"fair3d", t.fair3d},
              {"fair2d", t.fair2d}, {"line", t.line}, {"ray", t.ray}};
}

Json ToJson(const SolveReport& r) {
  Json j;
  j["method"] = r.method;
  j["converged"] = r.converged;
  j["stop_reason"] = r.stop_reason;
  j["model_size"] = r.model_size;
  j["seconds"] = r.seconds;
  j["vertices"] = r.num_vertices;
  j["points"] = r.num_points;
  j["iterations"] = Json::array();
  for (const IterationReport& it : r.iterations) j["iterations"].push_back(IterationJson(it));
  return j;
}

}  // namespace docunfold::isometry
