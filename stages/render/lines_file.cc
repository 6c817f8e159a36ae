#include "stages/render/lines_file.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/json_io.h"

namespace docunfold::render {

LinesFile ReadLinesFile(const fs::path& file) {
  LinesFile out;
  const Json doc = ReadJsonFile(file);
  const JsonReader r(doc, file);
  if (!r.At("/lines").is_array()) r.Fail("/lines", "expected an array");
  if (r.Has("/text_down_flat")) out.text_down = r.Vector2("/text_down_flat");
  for (size_t i = 0; i < doc["lines"].size(); ++i) {
    const std::string where = "/lines/" + std::to_string(i);
    const Eigen::Vector2d n = r.Vector2(where + "/normal");
    const Eigen::Vector2d along(-n.y(), n.x());
    const Json& flat = r.At(where + "/flat");
    if (!flat.is_array()) r.Fail(where + "/flat", "expected [[x, y], ...]");
    double lo = 1e300, hi = -1e300;
    for (size_t k = 0; k < flat.size(); ++k) {
      const double t = along.dot(r.Vector2(where + "/flat/" + std::to_string(k)));
      lo = std::min(lo, t);
      hi = std::max(hi, t);
    }
    if (hi > lo && std::isfinite(hi - lo)) {
      out.lines.push_back({std::atan2(n.y(), n.x()) * 180 / M_PI, hi - lo});
      if (doc["lines"][i].value("kind", "") == "text")
        out.text_lines.push_back({std::atan2(along.y(), along.x()) * 180 / M_PI, hi - lo});
    }
  }
  return out;
}

}  // namespace docunfold::render
