#include "stages/sfm/reference_view.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/imgproc.hpp>
#include <random>

#include "common/point_index.h"
#include "common/statistics.h"

namespace docunfold::sfm {
namespace {

// The weighted q-quantile of (value, weight) pairs; 0 when empty.
double WeightedQuantile(std::vector<std::pair<double, double>> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  double total = 0;
  for (const auto& p : v) total += p.second;
  double acc = 0;
  for (const auto& p : v) {
    acc += p.second;
    if (acc >= q * total) return p.first;
  }
  return v.back().first;
}

}  // namespace

std::vector<Eigen::Vector3d> EstimateNormals(const std::vector<Eigen::Vector3d>& points,
                                             int neighbours, std::vector<double>* spacing2) {
  std::vector<Eigen::Vector3d> normals(points.size(), Eigen::Vector3d::UnitZ());
  if (spacing2) spacing2->assign(points.size(), 1.0);
  if (points.size() < 3) return normals;
  const size_t k = std::min(points.size(), size_t(std::max(3, neighbours)));
  const PointIndex3d tree(points, 10);
  for (size_t i = 0; i < points.size(); ++i) {
    const std::vector<PointIndex3d::Neighbour> near = tree.Nearest(points[i], int(k));
    const size_t found = near.size();
    if (spacing2 && found) (*spacing2)[i] = near[found - 1].second;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (size_t j = 0; j < found; ++j) mean += points[near[j].first];
    mean /= double(found);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (size_t j = 0; j < found; ++j) {
      const Eigen::Vector3d d = points[near[j].first] - mean;
      cov += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    normals[i] = eig.eigenvectors().col(0).normalized();  // smallest eigenvalue
  }
  return normals;
}

cv::Mat1b RoughPageMask(const cv::Mat& bgr) {
  if (bgr.empty() || bgr.channels() != 3) return {};
  cv::Mat lab;
  cv::cvtColor(bgr, lab, cv::COLOR_BGR2Lab);
  cv::Mat1b paper(bgr.size());
  for (int y = 0; y < lab.rows; ++y)
    for (int x = 0; x < lab.cols; ++x) {
      const cv::Vec3b v = lab.at<cv::Vec3b>(y, x);
      const double chroma = std::hypot(v[1] - 128.0, v[2] - 128.0);
      paper(y, x) = cv::saturate_cast<uchar>(v[0] - 2 * chroma);
    }
  cv::Mat1b mask;
  cv::threshold(paper, mask, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
  const int k = std::max(3, int(0.02 * std::max(mask.cols, mask.rows))) | 1;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k});
  cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, kernel);  // text strokes
  cv::morphologyEx(mask, mask, cv::MORPH_OPEN, kernel);   // specks of table
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  if (contours.empty()) return {};
  size_t largest = 0;
  for (size_t i = 1; i < contours.size(); ++i)
    if (cv::contourArea(contours[i]) > cv::contourArea(contours[largest])) largest = i;
  // Its convex hull: the shaded side of a fold is darker than the threshold
  // but still page; a page's outline is nearly convex anyway.
  std::vector<cv::Point> hull;
  cv::convexHull(contours[largest], hull);
  cv::Mat1b page(mask.size(), uchar(0));
  cv::fillConvexPoly(page, hull, cv::Scalar(255));
  const double fraction = cv::countNonZero(page) / double(page.total());
  if (fraction < 0.01 || fraction > 0.95) return {};
  return page;
}

namespace {

// Plane through `points` (least squares): centroid and orthonormal axes u, v
// (in the plane) and n (normal).
struct Plane {
  Eigen::Vector3d origin, u, v, n;
  Eigen::Vector2d Project(const Eigen::Vector3d& x) const {
    return {(x - origin).dot(u), (x - origin).dot(v)};
  }
};

Plane FitPlane(const std::vector<Eigen::Vector3d>& points) {
  Plane p;
  p.origin = Eigen::Vector3d::Zero();
  for (const auto& x : points) p.origin += x;
  p.origin /= double(points.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& x : points) cov += (x - p.origin) * (x - p.origin).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  p.n = eig.eigenvectors().col(0).normalized();
  p.u = eig.eigenvectors().col(2).normalized();
  p.v = p.n.cross(p.u);
  return p;
}

std::vector<cv::Point2f> Hull(const std::vector<Eigen::Vector3d>& points, const Plane& plane) {
  std::vector<cv::Point2f> flat, hull;
  for (const auto& x : points) {
    const Eigen::Vector2d q = plane.Project(x);
    flat.emplace_back(float(q.x()), float(q.y()));
  }
  if (flat.size() >= 3) cv::convexHull(flat, hull);
  return hull;
}

// The plane with the most points within `tolerance` (RANSAC, fixed seed).
std::vector<size_t> DominantPlane(const std::vector<Eigen::Vector3d>& points, double tolerance) {
  std::vector<size_t> best;
  if (points.size() < 3) return best;
  std::mt19937 rng(12345);
  std::uniform_int_distribution<size_t> pick(0, points.size() - 1);
  for (int iter = 0; iter < 300; ++iter) {
    const Eigen::Vector3d& a = points[pick(rng)];
    const Eigen::Vector3d& b = points[pick(rng)];
    const Eigen::Vector3d& c = points[pick(rng)];
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() < 1e-12) continue;
    n.normalize();
    std::vector<size_t> inliers;
    for (size_t i = 0; i < points.size(); ++i)
      if (std::abs((points[i] - a).dot(n)) < tolerance) inliers.push_back(i);
    if (inliers.size() > best.size()) best = std::move(inliers);
  }
  return best;
}

}  // namespace

std::vector<bool> PagePoints(const ColmapModel& model,
                             const std::map<std::string, cv::Mat1b>& masks) {
  const size_t n = model.points.size();
  // 1. Light points: inside the paper mask of at least half the views that
  // see them (the page's bright panels).
  std::vector<bool> light(n, false);
  size_t light_count = 0;
  if (!masks.empty()) {
    for (size_t i = 0; i < n; ++i) {
      const ColmapPoint& p = model.points[i];
      int inside = 0, judged = 0;
      uint32_t last = 0;
      for (uint32_t id : p.image_ids) {
        if (id == last) continue;
        last = id;
        const ColmapImage& image = model.images.at(id);
        const auto it = masks.find(image.name);
        if (it == masks.end() || it->second.empty()) continue;
        const ColmapCamera& camera = model.cameras.at(image.camera_id);
        const cv::Mat1b& mask = it->second;
        const Eigen::Vector3d xc = image.R() * p.xyz + image.t;
        ++judged;
        if (xc.z() <= 0) continue;
        const Eigen::Vector2d px = camera.Project(xc);
        const int u = int(std::floor((px.x() + 0.5) * mask.cols / camera.width));
        const int v = int(std::floor((px.y() + 0.5) * mask.rows / camera.height));
        if (u >= 0 && v >= 0 && u < mask.cols && v < mask.rows && mask(v, u)) ++inside;
      }
      light[i] = judged > 0 && 2 * inside >= judged;
      light_count += light[i];
    }
  }
  if (light_count >= 30) {
    // 2. The rest is either the page's shaded side or the table. A table is
    // a plane reaching well beyond the page; its points are dropped. Without
    // such a plane (a plain background) every point is the page's.
    std::vector<Eigen::Vector3d> lit, other;
    std::vector<size_t> other_index;
    for (size_t i = 0; i < n; ++i) {
      if (light[i]) {
        lit.push_back(model.points[i].xyz);
      } else {
        other.push_back(model.points[i].xyz);
        other_index.push_back(i);
      }
    }
    const Plane page_plane = FitPlane(lit);
    const std::vector<cv::Point2f> page_hull = Hull(lit, page_plane);
    double diameter = 0;
    for (size_t a = 0; a < page_hull.size(); ++a)
      for (size_t b = a + 1; b < page_hull.size(); ++b)
        diameter = std::max(diameter, double(cv::norm(page_hull[a] - page_hull[b])));
    std::vector<bool> page(n, true);
    if (other.size() >= 30 && diameter > 0) {
      const std::vector<size_t> on_plane = DominantPlane(other, 0.01 * diameter);
      std::vector<Eigen::Vector3d> table;
      for (size_t k : on_plane) table.push_back(other[k]);
      if (table.size() >= 3) {
        const Plane table_plane = FitPlane(table);
        const std::vector<cv::Point2f> table_hull = Hull(table, table_plane);
        const std::vector<cv::Point2f> footprint = Hull(lit, table_plane);
        if (table_hull.size() >= 3 && footprint.size() >= 3 &&
            cv::contourArea(table_hull) > 1.5 * cv::contourArea(footprint)) {
          // A table: a point that is not light and lies less than 5 % of the
          // page's size above it is the table's (the page's flat parts
          // are light; its shaded side stands up from the table).
          Eigen::Vector3d up = table_plane.n;
          Eigen::Vector3d cameras = Eigen::Vector3d::Zero();
          for (const auto& [id, image] : model.images) cameras += image.Center();
          cameras /= double(model.images.size());
          if ((cameras - table_plane.origin).dot(up) < 0) up = -up;
          for (size_t k = 0; k < other.size(); ++k)
            if ((other[k] - table_plane.origin).dot(up) < 0.05 * diameter)
              page[other_index[k]] = false;
        }
      }
    }
    return page;
  }
  // Fallback: seen by at least half of the registered views.
  std::vector<bool> page(n, false);
  const size_t need = std::max<size_t>(2, (model.images.size() + 1) / 2);
  size_t count = 0;
  for (size_t i = 0; i < n; ++i) {
    std::vector<uint32_t> ids = model.points[i].image_ids;
    std::sort(ids.begin(), ids.end());
    page[i] = size_t(std::unique(ids.begin(), ids.end()) - ids.begin()) >= need;
    count += page[i];
  }
  if (count < 20) page.assign(n, true);
  return page;
}

double ReferenceScore(const ViewScore& s, double max_resolution, const ReferenceOptions& options) {
  return std::pow(s.coverage, 4) * s.resolution / max_resolution * s.frontality *
         std::max(0.0, 1.0 - options.hidden_penalty * s.hidden);
}

std::vector<ViewScore> ScoreReferenceViews(const ColmapModel& model,
                                           const std::map<std::string, cv::Mat1b>& masks,
                                           const ReferenceOptions& options) {
  // Everything below is on the page's points only: a table's points would
  // tilt the normals of the page's points near them.
  const std::vector<bool> page = PagePoints(model, masks);
  std::vector<size_t> page_indices;
  std::vector<Eigen::Vector3d> xyz;
  for (size_t i = 0; i < page.size(); ++i)
    if (page[i]) {
      page_indices.push_back(i);
      xyz.push_back(model.points[i].xyz);
    }
  std::vector<double> area;
  const std::vector<Eigen::Vector3d> normals =
      EstimateNormals(xyz, options.normal_neighbours, &area);
  // Isolated points would stand for huge areas: cap at the 90th percentile.
  if (!area.empty()) {
    const double cap = NthSmallest(area, area.size() * 9 / 10);
    for (double& a : area) a = std::min(a, cap);
  }

  std::map<uint32_t, std::vector<size_t>> seen;  // page points per view
  for (size_t i : page_indices)
    for (uint32_t id : model.points[i].image_ids) {
      auto& v = seen[id];
      if (v.empty() || v.back() != i) v.push_back(i);  // once per point
    }

  // Normals point to the side the cameras are on (every photo shows the
  // page's front), so a view that sees a part from behind (a curled corner)
  // can tell it is hidden.
  Eigen::Vector3d cameras_mean = Eigen::Vector3d::Zero();
  for (const auto& [id, image] : model.images) cameras_mean += image.Center();
  if (!model.images.empty()) cameras_mean /= double(model.images.size());
  std::vector<Eigen::Vector3d> oriented = normals;
  for (size_t i = 0; i < xyz.size(); ++i)
    if ((cameras_mean - xyz[i]).dot(oriented[i]) < 0) oriented[i] = -oriented[i];

  std::vector<ViewScore> scores;
  double max_resolution = 1e-300;
  for (const auto& [id, image] : model.images) {
    const ColmapCamera& camera = model.cameras.at(image.camera_id);
    const Eigen::Matrix3d R = image.R();
    const Eigen::Vector3d center = image.Center();
    ViewScore s;
    s.image = image.name;
    s.image_id = id;
    const auto it = seen.find(id);
    const std::vector<size_t> none;
    const std::vector<size_t>& mine = it == seen.end() ? none : it->second;
    s.points_seen = int(mine.size());
    const double margin = options.margin_fraction * std::min(camera.width, camera.height);
    int inside = 0;
    double hidden_area = 0, total_area = 0;
    std::vector<std::pair<double, double>> cosines;     // (|cos|, pixels)
    std::vector<std::pair<double, double>> resolution;  // (px per unit, page area)
    for (size_t i = 0; i < xyz.size(); ++i) {
      total_area += area[i];
      const Eigen::Vector3d xc = R * xyz[i] + image.t;
      const Eigen::Vector2d px = xc.z() > 0 ? camera.Project(xc) : Eigen::Vector2d(-1, -1);
      if (px.x() < 0 || px.y() < 0 || px.x() > camera.width - 1 || px.y() > camera.height - 1) {
        resolution.push_back({0, area[i]});  // not in the picture at all
        continue;
      }
      const double signed_cos = (center - xyz[i]).normalized().dot(oriented[i]);
      const double c = std::abs(signed_cos);
      if (signed_cos < 0) hidden_area += area[i];
      // Pixels per unit length across the foreshortened direction.
      resolution.push_back({camera.MeanFocal() * std::max(signed_cos, 0.0) / xc.z(), area[i]});
      // The pixels this point's patch covers: area * |cos| / depth^2.
      const double weight = area[i] * c / (xc.z() * xc.z());
      cosines.push_back({c, weight});
      s.page_pixels += weight * camera.MeanFocal() * camera.MeanFocal();
      if (px.x() >= margin && px.y() >= margin && px.x() <= camera.width - 1 - margin &&
          px.y() <= camera.height - 1 - margin)
        ++inside;
    }
    s.frontality = WeightedQuantile(std::move(cosines), 0.5);
    s.resolution = WeightedQuantile(std::move(resolution), options.resolution_quantile);
    s.hidden = total_area > 0 ? hidden_area / total_area : 0;
    s.coverage = page_indices.empty() ? 0 : double(inside) / double(page_indices.size());
    max_resolution = std::max(max_resolution, s.resolution);
    scores.push_back(s);
  }
  for (ViewScore& s : scores) s.score = ReferenceScore(s, max_resolution, options);
  std::stable_sort(scores.begin(), scores.end(), [](const ViewScore& a, const ViewScore& b) {
    if (a.score != b.score) return a.score > b.score;
    return a.image < b.image;
  });
  return scores;
}

}  // namespace docunfold::sfm
