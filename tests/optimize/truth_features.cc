#include "tests/optimize/truth_features.h"

#include <cmath>

namespace docunfold::testing {

Json TruthFeatures(const GroundTruth& gt, const std::string& reference, double piece_px) {
  const PinholeCamera* cam = gt.cameras.Find(reference);
  if (!cam) throw std::runtime_error("no true camera for " + reference);
  Json doc = MakeHeader("docunfold.features", 1, "truth-features");
  doc["image"] = reference;
  doc["width"] = cam->width;
  doc["height"] = cam->height;
  doc["segments"] = Json::array();
  for (const TrueLine& line : TrueLinesInView(gt, *cam, 2.0)) {
    if (line.kind == "border") continue;
    // Pieces of the projected line, each short enough to be straight.
    Json piece = Json::array();
    double length = 0;
    for (size_t k = 0; k < line.points.size(); ++k) {
      if (k > 0) length += (line.points[k] - line.points[k - 1]).norm();
      piece.push_back({line.points[k].x(), line.points[k].y()});
      if (length >= piece_px || k + 1 == line.points.size()) {
        if (piece.size() >= 2 && length > 8)
          doc["segments"].push_back(
              {{"kind", line.kind == "text" ? "text" : "edge"}, {"points", piece}});
        piece = Json::array({{line.points[k].x(), line.points[k].y()}});
        length = 0;
      }
    }
  }
  return doc;
}

}  // namespace docunfold::testing
