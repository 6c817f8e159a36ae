#include "tests/evaluate/truth_frontend.h"

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "common/atomic_file.h"
#include "common/json_io.h"
#include "tests/support/truth_frame.h"

namespace docunfold::testing {
namespace {

bool Inside(const PinholeCamera& c, const Eigen::Vector2d& p) {
  return p.x() >= 0 && p.y() >= 0 && p.x() <= c.width - 1 && p.y() <= c.height - 1;
}

Json Point(const Eigen::Vector2d& p) { return Json::array({p.x(), p.y()}); }

}  // namespace

std::string ChooseTrueReference(const GroundTruth& gt) {
  // Whole page first (a cut-off data set may have no such view), then size.
  std::string best;
  std::pair<bool, long> best_score(false, -1);
  for (const PinholeCamera& camera : gt.cameras.views) {
    const auto corners = TrueCorners(gt, camera);
    const bool whole = std::all_of(corners.begin(), corners.end(),
                                   [&](const Eigen::Vector2d& p) { return Inside(camera, p); });
    const std::pair<bool, long> score(whole, cv::countNonZero(TruePageMask(gt, camera)));
    if (score > best_score) {
      best_score = score;
      best = camera.image;
    }
  }
  if (best.empty() || best_score.second <= 0) throw std::runtime_error("no view sees the page");
  return best;
}

void WriteBoundaryFromTruth(const GroundTruth& gt, const std::string& reference,
                            const fs::path& out_dir) {
  const PinholeCamera* camera = gt.cameras.Find(reference);
  if (!camera) throw std::runtime_error("no true camera for " + reference);
  const auto& s = gt.mesh.FindProperty("s")->values;
  const auto& t = gt.mesh.FindProperty("t")->values;
  // Border vertices of each side, ordered along it; sides run top TL->TR,
  // right TR->BR, bottom BL->BR, left TL->BL (schema of boundary.json).
  constexpr double kEps = 1e-6;
  struct Side {
    const char* name;
    std::vector<std::pair<double, Eigen::Vector2d>> points;
    bool real = true;
  } sides[4] = {{"top", {}}, {"right", {}}, {"bottom", {}}, {"left", {}}};
  for (size_t v = 0; v < gt.mesh.vertices.size(); ++v) {
    const Eigen::Vector2d px = camera->Project(gt.mesh.vertices[v]);
    if (t[v] < kEps) sides[0].points.push_back({s[v], px});
    if (s[v] > 1 - kEps) sides[1].points.push_back({t[v], px});
    if (t[v] > 1 - kEps) sides[2].points.push_back({s[v], px});
    if (s[v] < kEps) sides[3].points.push_back({t[v], px});
  }
  Json doc = MakeHeader("docunfold.boundary", 1, "boundary-from-truth");
  doc["image"] = reference;
  doc["width"] = camera->width;
  doc["height"] = camera->height;
  Json sides_json = Json::object();
  for (Side& side : sides) {
    if (side.points.size() < 2)
      throw std::runtime_error(std::string("true mesh has no ") + side.name + " border");
    std::sort(side.points.begin(), side.points.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    Json pts = Json::array();
    for (const auto& [param, px] : side.points) {
      pts.push_back(Point(px));
      side.real = side.real && Inside(*camera, px);
    }
    sides_json[side.name] = {{"points", pts}, {"real", side.real}};
  }
  doc["sides"] = sides_json;
  const auto corners = TrueCorners(gt, *camera);
  doc["corners"] = Json::array();
  for (const auto& c : corners) doc["corners"].push_back(Point(c));
  // Closed outline: top, right, bottom reversed, left reversed.
  Json contour = Json::array();
  std::vector<cv::Point> polygon;
  auto add = [&](const Side& side, bool reversed) {
    const size_t n = side.points.size();
    for (size_t k = 0; k + 1 < n; ++k) {
      const Eigen::Vector2d& p = side.points[reversed ? n - 1 - k : k].second;
      contour.push_back(Point(p));
      polygon.emplace_back(int(std::lround(p.x())), int(std::lround(p.y())));
    }
  };
  add(sides[0], false);
  add(sides[1], false);
  add(sides[2], true);
  add(sides[3], true);
  doc["contour"] = contour;

  EnsureDirectory(out_dir);
  const cv::Mat1b mask = TruePageMask(gt, *camera);
  WriteImageAtomic(out_dir / "mask.png", mask);
  cv::Mat overlay = cv::imread((gt.root / "images" / reference).string(), cv::IMREAD_COLOR);
  if (!overlay.empty()) {
    cv::polylines(overlay, std::vector<std::vector<cv::Point>>{polygon}, true,
                  cv::Scalar(0, 0, 255), 2, cv::LINE_AA);
    WriteImageAtomic(out_dir / "overlay.png", overlay);
  }
  WriteJsonAtomic(out_dir / "boundary.json", doc);
}

std::string WriteTruthFrontEnd(const GroundTruth& gt, const fs::path& work, std::string reference) {
  if (reference.empty()) reference = ChooseTrueReference(gt);
  WriteSfmFromTruth(gt, reference, work / "10_sfm");
  WriteBoundaryFromTruth(gt, reference, work / "20_boundary");
  return reference;
}

}  // namespace docunfold::testing
