#include "stages/densify/densify.h"

#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "common/atomic_file.h"
#include "common/cli.h"
#include "common/depth_field.h"
#include "common/errors.h"
#include "common/point_index.h"

namespace docunfold::densify {
namespace {

using Clock = std::chrono::steady_clock;

// Bilinear sample of a float image; 0 outside.
float Sample(const cv::Mat1f& m, double x, double y) {
  if (!(x >= 0 && y >= 0 && x <= m.cols - 1 && y <= m.rows - 1)) return 0;
  const int x0 = std::min(int(x), m.cols - 2), y0 = std::min(int(y), m.rows - 2);
  const float fx = float(x - x0), fy = float(y - y0);
  return (1 - fy) * ((1 - fx) * m(y0, x0) + fx * m(y0, x0 + 1)) +
         fy * ((1 - fx) * m(y0 + 1, x0) + fx * m(y0 + 1, x0 + 1));
}

// A photo as the stage works on it: undistorted, resized, with its camera
// and the gradient of a slightly blurred copy (grey levels per pixel).
struct View {
  int index = -1;  // in the camera set
  PinholeCamera camera;
  cv::Mat1b grey;
  cv::Mat1f gx, gy;

  Eigen::Vector2d Gradient(const Eigen::Vector2d& p) const {
    return {Sample(gx, p.x(), p.y()), Sample(gy, p.x(), p.y())};
  }
  bool Inside(const Eigen::Vector2d& p, double border = 1) const {
    return p.x() >= border && p.y() >= border && p.x() <= grey.cols - 1 - border &&
           p.y() <= grey.rows - 1 - border;
  }
};

View MakeView(int index, const PinholeCamera& camera, const cv::Mat& grey_photo,
              const std::array<double, 4>& distortion, double scale) {
  View v;
  v.index = index;
  v.camera = ScaleCamera(camera, scale);
  cv::Mat resized;
  if (scale != 1) {
    cv::resize(grey_photo, resized, cv::Size(v.camera.width, v.camera.height), 0, 0,
               cv::INTER_AREA);
  } else {
    resized = grey_photo;
  }
  const bool distorted =
      std::any_of(distortion.begin(), distortion.end(), [](double d) { return d != 0; });
  if (distorted) {
    cv::Mat K;
    cv::eigen2cv(v.camera.K, K);
    const std::vector<double> coefficients(distortion.begin(), distortion.end());
    cv::undistort(resized, v.grey, K, coefficients);
  } else {
    v.grey = resized.clone();
  }
  cv::Mat blurred;
  cv::GaussianBlur(v.grey, blurred, cv::Size(0, 0), 1.2);
  cv::Sobel(blurred, v.gx, CV_32F, 1, 0, 3, 0.125);
  cv::Sobel(blurred, v.gy, CV_32F, 0, 1, 3, 0.125);
  return v;
}

Eigen::Vector2d ScalePixel(const Eigen::Vector2d& p, double scale) {
  return (p.array() + 0.5) * scale - 0.5;
}

// Point of the reference camera's ray through `pixel` at camera depth `depth`.
Eigen::Vector3d RayPoint(const PinholeCamera& camera, const Eigen::Vector2d& pixel, double depth) {
  const Eigen::Vector3d xc =
      depth * (camera.K.inverse() * Eigen::Vector3d(pixel.x(), pixel.y(), 1));
  return camera.R.transpose() * (xc - camera.t);
}

struct Observation {
  const PinholeCamera* camera;
  Eigen::Vector2d pixel;
};

// Sub-pixel position of the local maximum g[i] (a parabola through it and
// its neighbours), as an offset in samples from i.
double ParabolaPeak(const std::vector<double>& g, int i) {
  const double curvature = g[i - 1] - 2 * g[i] + g[i + 1];
  return curvature < 0 ? 0.5 * (g[i - 1] - g[i + 1]) / curvature : 0;
}

// Appends a point made by densify with its PLY properties (Run sets up
// track_length, reprojection_error and source, in that order).
void AppendPoint(const Eigen::Vector3d& X, const std::array<uint8_t, 3>& rgb, int views,
                 double reprojection_error, PointSource source, PlyData* points) {
  points->vertices.push_back(X);
  points->colors.push_back(rgb);
  points->properties[0].values.push_back(views);
  points->properties[1].values.push_back(reprojection_error);
  points->properties[2].values.push_back(source);
}

// Triangulates and checks: in front of every camera, every reprojection
// within `max_error`, rays at least `min_angle` apart. Returns false when not.
bool TriangulateChecked(const std::vector<Observation>& obs, double max_error, double min_angle_rad,
                        Eigen::Vector3d* point, double* mean_error) {
  std::vector<const PinholeCamera*> cameras;
  std::vector<Eigen::Vector2d> pixels;
  for (const Observation& o : obs) {
    cameras.push_back(o.camera);
    pixels.push_back(o.pixel);
  }
  const Eigen::Vector3d X = Triangulate(cameras, pixels);
  if (!X.allFinite()) return false;
  double sum = 0;
  for (const Observation& o : obs) {
    const Eigen::Vector3d xc = o.camera->CamFromWorld(X);
    if (!(xc.z() > 0)) return false;
    const double e = (o.camera->ProjectCam(xc) - o.pixel).norm();
    if (e > max_error) return false;
    sum += e;
  }
  double widest = 0;
  const Eigen::Vector3d d0 = (X - obs[0].camera->Center()).normalized();
  for (size_t i = 1; i < obs.size(); ++i)
    widest = std::max(widest, std::acos(std::clamp(
                                  d0.dot((X - obs[i].camera->Center()).normalized()), -1.0, 1.0)));
  if (widest < min_angle_rad) return false;
  *point = X;
  *mean_error = sum / double(obs.size());
  return true;
}

// Homography taking reference pixels of the page to `view`'s pixels, fitted
// to the page's SfM points; empty when too few are seen by both.
cv::Mat PageHomography(const View& ref, const View& view,
                       const std::vector<Eigen::Vector3d>& page_points, int* used) {
  std::vector<cv::Point2f> a, b;
  for (const Eigen::Vector3d& X : page_points) {
    const Eigen::Vector3d cr = ref.camera.CamFromWorld(X), cv_ = view.camera.CamFromWorld(X);
    if (!(cr.z() > 0) || !(cv_.z() > 0)) continue;
    const Eigen::Vector2d pr = ref.camera.ProjectCam(cr), pv = view.camera.ProjectCam(cv_);
    if (!ref.Inside(pr, 0) || !view.Inside(pv, 0)) continue;
    a.emplace_back(float(pr.x()), float(pr.y()));
    b.emplace_back(float(pv.x()), float(pv.y()));
  }
  *used = int(a.size());
  if (a.size() < 12) return cv::Mat();
  return cv::findHomography(a, b, cv::RANSAC, 5.0);
}

// --- texture points -------------------------------------------------------

// A textured sample of the reference view and where the flow found it in
// the other views; `done` once it is triangulated.
struct Track {
  Eigen::Vector2d pixel;
  std::vector<Observation> obs;
  bool done = false;
};

// Every `step_px`-th pixel of the region with enough texture (text, print).
std::vector<Track> TextureSamples(const View& ref, const cv::Mat1b& region,
                                  const TextureOptions& o) {
  cv::Mat1f texture;
  cv::cornerMinEigenVal(ref.grey, texture, 7, 3);
  std::vector<float> values;
  for (int y = 0; y < region.rows; ++y)
    for (int x = 0; x < region.cols; ++x)
      if (region(y, x)) values.push_back(texture(y, x));
  if (values.empty()) return {};
  const size_t q95 = values.size() * 95 / 100;
  std::nth_element(values.begin(), values.begin() + q95, values.end());
  const double threshold = o.min_texture * values[q95];
  std::vector<Track> tracks;
  const double step = std::max(1.0, o.step_px);
  for (double y = 0; y < region.rows; y += step)
    for (double x = 0; x < region.cols; x += step) {
      const int u = int(x), v = int(y);
      if (!region(v, u) || texture(v, u) < threshold) continue;
      tracks.push_back({Eigen::Vector2d(u, v), {}});
    }
  return tracks;
}

// Follows the tracks not yet done from the reference into `view` by optical
// flow between the reference and `warped` (the view brought onto the
// reference; `covered` where it has pixels), kept where the flow agrees
// forwards and backwards; `to_view` takes a pixel of `warped` to the view's
// pixel (false where it cannot). Returns the matches made.
template <class ToView>
int FollowFlow(const View& ref, const View& view, const cv::Mat1b& warped, const cv::Mat1b& covered,
               const ToView& to_view, const TextureOptions& o, std::vector<Track>* tracks) {
  auto dis = cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_MEDIUM);
  cv::Mat forward, backward;
  dis->calc(ref.grey, warped, forward);
  dis->calc(warped, ref.grey, backward);
  int matches = 0;
  for (Track& t : *tracks) {
    if (t.done) continue;
    const int u = int(t.pixel.x()), v = int(t.pixel.y());
    const cv::Point2f f = forward.at<cv::Point2f>(v, u);
    const double qx = u + f.x, qy = v + f.y;
    if (!(qx >= 1 && qy >= 1 && qx <= ref.grey.cols - 2 && qy <= ref.grey.rows - 2)) continue;
    const int iu = int(std::lround(qx)), iv = int(std::lround(qy));
    if (!covered(iv, iu)) continue;
    const cv::Point2f b = backward.at<cv::Point2f>(iv, iu);
    if (std::hypot(f.x + b.x, f.y + b.y) > o.max_flow_disagreement_px) continue;
    Eigen::Vector2d p;
    if (!to_view(qx, qy, &p)) continue;
    t.obs.push_back({&view.camera, p});
    ++matches;
  }
  return matches;
}

// Triangulates the tracks not yet done that reach min_views; appends the
// points (colour from the full-size reference image). Returns how many.
int TriangulateTracks(const View& ref, const cv::Mat& reference_bgr, const TextureOptions& o,
                      std::vector<Track>* tracks, DensifyResult* result) {
  const double min_angle = o.min_triangulation_angle_deg * M_PI / 180;
  int added = 0;
  for (Track& t : *tracks) {
    if (t.done || int(t.obs.size()) + 1 < o.min_views) continue;
    std::vector<Observation> obs{{&ref.camera, t.pixel}};
    obs.insert(obs.end(), t.obs.begin(), t.obs.end());
    Eigen::Vector3d X;
    double error = 0;
    if (!TriangulateChecked(obs, o.max_reprojection_px, min_angle, &X, &error)) continue;
    const Eigen::Vector2d full = ScalePixel(t.pixel, 1 / result->working_scale);
    const cv::Vec3b bgr = reference_bgr.at<cv::Vec3b>(
        std::clamp(int(std::lround(full.y())), 0, reference_bgr.rows - 1),
        std::clamp(int(std::lround(full.x())), 0, reference_bgr.cols - 1));
    AppendPoint(X, {bgr[2], bgr[1], bgr[0]}, int(obs.size()), error, kTexture, &result->points);
    t.done = true;
    ++added;
  }
  return added;
}

// First pass: each view brought onto the reference by the homography of the
// page's SfM points; what is left for the flow is the page's relief.
void FollowByHomography(const View& ref, const std::vector<View>& others,
                        const std::vector<Eigen::Vector3d>& page_points, const TextureOptions& o,
                        std::vector<Track>* tracks, DensifyResult* result) {
  for (const View& view : others) {
    ViewStats& stats = result->views[view.index];
    const cv::Mat H = PageHomography(ref, view, page_points, &stats.page_points);
    if (H.empty()) continue;
    const Eigen::Matrix3d He =
        Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(H.ptr<double>());
    cv::Mat1b warped, covered;
    cv::warpPerspective(view.grey, warped, H, ref.grey.size(),
                        cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT, 0);
    cv::warpPerspective(cv::Mat1b(view.grey.size(), uchar(255)), covered, H, ref.grey.size(),
                        cv::INTER_NEAREST | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT, 0);
    auto to_view = [&](double x, double y, Eigen::Vector2d* p) {
      const Eigen::Vector3d h = He * Eigen::Vector3d(x, y, 1);
      *p = h.head<2>() / h.z();
      return true;
    };
    stats.flow_matches += FollowFlow(ref, view, warped, covered, to_view, o, tracks);
  }
}

// Second pass, for the samples the first left without a point: each view
// brought onto the reference through the depth that the points found so far
// give every pixel of the region (DepthField, planar: a panel between known
// points is carried on as a plane). One homography fits one panel; a flap or
// the far side of a fold stands at another angle, and the flow cannot bridge
// the difference.
void FollowBySurface(const View& ref, const std::vector<View>& others, const cv::Mat1b& region,
                     const std::vector<Eigen::Vector3d>& known, const TextureOptions& o,
                     std::vector<Track>* tracks, DensifyResult* result) {
  std::vector<Eigen::Vector2d> pixels;
  std::vector<double> depths;
  for (const Eigen::Vector3d& X : known) {
    const Eigen::Vector3d xc = ref.camera.CamFromWorld(X);
    if (!(xc.z() > 0)) continue;
    pixels.push_back(ref.camera.ProjectCam(xc));
    depths.push_back(xc.z());
  }
  if (pixels.size() < 16) return;
  const DepthField depth(pixels, depths, o.surface_neighbours, 2 * o.surface_grid_px,
                         DepthModel::kPlanar, o.surface_neighbours);
  // Inverse depth on a coarse grid over the region's box, interpolated
  // bilinearly in between.
  const cv::Rect box = cv::boundingRect(region);
  if (box.empty()) return;
  const int g = std::max(1, int(o.surface_grid_px));
  const int gw = box.width / g + 2, gh = box.height / g + 2;
  cv::Mat1f inverse_depth(gh, gw);
  for (int j = 0; j < gh; ++j)
    for (int i = 0; i < gw; ++i)
      inverse_depth(j, i) = float(1 / depth.At(Eigen::Vector2d(box.x + i * g, box.y + j * g)));
  cv::Mat1b grown;
  cv::dilate(region, grown, cv::Mat(), cv::Point(-1, -1), 2 * g);
  for (const View& view : others) {
    cv::Mat2f map(ref.grey.size(), cv::Vec2f(-1, -1));
    for (int y = box.y; y < box.y + box.height; ++y)
      for (int x = box.x; x < box.x + box.width; ++x) {
        if (!grown(y, x)) continue;
        const float inv = Sample(inverse_depth, double(x - box.x) / g, double(y - box.y) / g);
        if (!(inv > 0)) continue;
        const Eigen::Vector3d xc =
            view.camera.CamFromWorld(RayPoint(ref.camera, Eigen::Vector2d(x, y), 1 / inv));
        if (!(xc.z() > 0)) continue;
        const Eigen::Vector2d p = view.camera.ProjectCam(xc);
        if (view.Inside(p, 0)) map(y, x) = cv::Vec2f(float(p.x()), float(p.y()));
      }
    cv::Mat1b warped;
    cv::remap(view.grey, warped, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
    cv::Mat1b covered;
    cv::inRange(map, cv::Scalar(0, 0), cv::Scalar(view.grey.cols - 1, view.grey.rows - 1), covered);
    auto to_view = [&](double x, double y, Eigen::Vector2d* p) {
      const int x0 = int(x), y0 = int(y);
      const float fx = float(x - x0), fy = float(y - y0);
      cv::Vec2f sum(0, 0);
      for (int dy = 0; dy <= 1; ++dy)
        for (int dx = 0; dx <= 1; ++dx) {
          const cv::Vec2f m = map(y0 + dy, x0 + dx);
          if (m[0] < 0) return false;
          sum += m * ((dx ? fx : 1 - fx) * (dy ? fy : 1 - fy));
        }
      *p = Eigen::Vector2d(sum[0], sum[1]);
      return true;
    };
    result->views[view.index].surface_flow_matches +=
        FollowFlow(ref, view, warped, covered, to_view, o, tracks);
  }
}

// --- outline points -------------------------------------------------------

// Strongest step of sign `sign` (grey rising along +n) within +-reach of c
// along the unit normal n; returns its offset (sub-pixel) and strength.
bool FindStep(const View& view, const Eigen::Vector2d& c, const Eigen::Vector2d& n, double reach,
              int sign, double* offset, double* strength) {
  const int count = int(2 * reach / 0.5) + 1;
  std::vector<double> g(count, 0);
  int best = -1;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector2d p = c + (-reach + 0.5 * i) * n;
    if (!view.Inside(p)) continue;
    g[i] = sign * view.Gradient(p).dot(n);
    if (best < 0 || g[i] > g[best]) best = i;
  }
  if (best <= 0 || best >= count - 1 || g[best] <= 0) return false;
  *offset = -reach + 0.5 * (best + ParabolaPeak(g, best));
  *strength = g[best];
  return true;
}

// Whether the step at c (grey rising along the unit `normal`) continues
// straight along the edge: a step of the same sign of at least
// `min_strength` within 1.5 px of the line through c, half and all of
// `reach` to either side. Texture of a table or carpet gives short gradient
// blobs, a page's edge or a fold a straight step.
bool StepContinues(const View& view, const Eigen::Vector2d& c, const Eigen::Vector2d& normal,
                   double reach, double min_strength) {
  const Eigen::Vector2d tangent(-normal.y(), normal.x());
  for (double along : {-reach, -reach / 2, reach / 2, reach}) {
    double offset = 0, strength = 0;
    if (!FindStep(view, c + along * tangent, normal, 1.5, 1, &offset, &strength) ||
        strength < min_strength)
      return false;
  }
  return true;
}

// A crossing of an edge found in another view: where, and the edge's unit
// normal there (from that image's gradient).
struct EdgeMatch {
  Eigen::Vector2d pixel;
  Eigen::Vector2d normal;
};

struct EdgeSample {
  Eigen::Vector2d pixel;   // on the edge, reference working copy
  Eigen::Vector2d normal;  // unit, pointing out of the page
  int sign = 1;            // grey rises (+1) or falls (-1) going out
  double near_depth = 0, far_depth = 0;
  std::vector<std::vector<EdgeMatch>> candidates;  // per view index
};

std::vector<EdgeSample> EdgeSamples(const View& ref, const Boundary& boundary,
                                    const cv::Mat1b& page, double scale, const OutlineOptions& o) {
  std::vector<EdgeSample> samples;
  std::array<Eigen::Vector2d, 4> corners;
  for (int i = 0; i < 4; ++i) corners[i] = ScalePixel(boundary.corners[i], scale);
  for (int s = 0; s < 4; ++s) {
    if (!boundary.sides[s].real) continue;
    const auto& side = boundary.sides[s].points;
    double walked = 0;  // arc length of the side before segment k
    for (size_t k = 0; k + 1 < side.size(); ++k) {
      const Eigen::Vector2d a = ScalePixel(side[k], scale), b = ScalePixel(side[k + 1], scale);
      const double length = (b - a).norm();
      if (length < 1e-9) continue;
      const Eigen::Vector2d t = (b - a) / length;
      // Samples every step_px of arc length along the whole side.
      for (double u = std::fmod(o.step_px - std::fmod(walked, o.step_px), o.step_px); u < length;
           u += o.step_px) {
        const Eigen::Vector2d p = a + u * t;
        bool near_corner = false;
        for (const auto& c : corners) near_corner |= (p - c).norm() < o.corner_gap_px;
        if (near_corner) continue;
        Eigen::Vector2d n(-t.y(), t.x());
        const Eigen::Vector2d probe = p + 4 * n;
        if (ref.Inside(probe, 0) && page(int(probe.y()), int(probe.x()))) n = -n;
        double off_up = 0, up = 0, off_down = 0, down = 0;
        const bool rises = FindStep(ref, p, n, 5, 1, &off_up, &up);
        const bool falls = FindStep(ref, p, n, 5, -1, &off_down, &down);
        if (!rises && !falls) continue;
        const bool use_rise = rises && (!falls || up >= down);
        if ((use_rise ? up : down) < o.min_contrast) continue;
        EdgeSample e;
        e.pixel = p + (use_rise ? off_up : off_down) * n;
        e.normal = n;
        e.sign = use_rise ? 1 : -1;
        samples.push_back(e);
      }
      walked += length;
    }
  }
  return samples;
}

// The depth along the reference ray through `pixel` at which its projection
// crosses the edge found in each other view (obs[1...], edge normals
// `normals`), by Gauss-Newton from *depth: residuals across the edge only
// (along it a match is no evidence), so a view whose edge nearly follows its
// epipolar line weighs little. False when the fit fails; else the largest
// and mean absolute residual (pixels).
bool DepthAcrossEdges(const PinholeCamera& ref, const Eigen::Vector2d& pixel,
                      const std::vector<Observation>& obs,
                      const std::vector<Eigen::Vector2d>& normals, double* depth, double* worst,
                      double* mean) {
  auto residuals = [&](double d, std::vector<double>* r) {
    r->clear();
    const Eigen::Vector3d X = RayPoint(ref, pixel, d);
    for (size_t k = 1; k < obs.size(); ++k) {
      const Eigen::Vector3d xc = obs[k].camera->CamFromWorld(X);
      if (!(xc.z() > 0)) return false;
      r->push_back(normals[k - 1].dot(obs[k].camera->ProjectCam(xc) - obs[k].pixel));
    }
    return true;
  };
  std::vector<double> r0, r1;
  if (!(*depth > 0)) return false;
  for (int iteration = 0; iteration < 8; ++iteration) {
    const double step = 1e-6 * *depth;
    if (!residuals(*depth, &r0) || !residuals(*depth + step, &r1)) return false;
    double jtj = 0, jtr = 0;
    for (size_t k = 0; k < r0.size(); ++k) {
      const double j = (r1[k] - r0[k]) / step;
      jtj += j * j;
      jtr += j * r0[k];
    }
    if (!(jtj > 0)) return false;
    const double delta = -jtr / jtj;
    *depth += delta;
    if (!(*depth > 0) || std::abs(delta) < 1e-9 * *depth) break;
  }
  if (!(*depth > 0) || !residuals(*depth, &r0)) return false;
  *worst = *mean = 0;
  for (const double r : r0) {
    *worst = std::max(*worst, std::abs(r));
    *mean += std::abs(r) / double(r0.size());
  }
  return true;
}

// Affine fit of 1/depth to the known points within `radius` of `pixel` that
// `keep` accepts (given their offset from it): 1/depth = c0 du + c1 dv + c2.
// False when fewer than 6 points there span an area.
template <class Keep>
bool FitInverseDepth(const Eigen::Vector2d& pixel, double radius,
                     const std::vector<Eigen::Vector2d>& known_pixels,
                     const std::vector<double>& known_depths, const Keep& keep,
                     Eigen::Vector3d* c) {
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  int near = 0;
  for (size_t i = 0; i < known_pixels.size(); ++i) {
    const Eigen::Vector2d d = known_pixels[i] - pixel;
    if (d.squaredNorm() > radius * radius || !keep(d)) continue;
    const Eigen::Vector3d a(d.x(), d.y(), 1);
    ata += a * a.transpose();
    atb += a / known_depths[i];
    ++near;
  }
  if (near < 6 || !(std::abs(ata.determinant()) > 1e-6 * std::pow(ata.trace(), 3))) return false;
  *c = ata.ldlt().solve(atb);
  return true;
}

// Whether `depth` at `pixel` continues the surface of the known points
// within continuity_radius_px (an affine fit of 1/depth, when at least 6 are
// there and they span an area) to max_depth_jump of the depth.
bool ContinuesSurface(const Eigen::Vector2d& pixel, double depth,
                      const std::vector<Eigen::Vector2d>& known_pixels,
                      const std::vector<double>& known_depths, const OutlineOptions& o) {
  Eigen::Vector3d c;
  if (!FitInverseDepth(
          pixel, o.continuity_radius_px, known_pixels, known_depths,
          [](const Eigen::Vector2d&) { return true; }, &c))
    return true;
  const double inverse_depth = c(2);
  return !(inverse_depth > 0 && std::abs(1 / inverse_depth - depth) > o.max_depth_jump * depth);
}

// Whether a triangulated edge sample at `depth` (reference camera) may be kept.
using EdgeCheck = std::function<bool(const EdgeSample&, double depth)>;

// Matches edge samples of the reference along their epipolar segments in the
// other views (steps of the same sign crossing them, continuing straight
// along the edge), triangulates those enough views agree on unambiguously,
// and appends the points `check` accepts, with `source` and `colour`.
// `stats`, when given, counts candidates and votes per view.
void MatchEdgeSamples(const View& ref, const std::vector<View>& others, int num_views,
                      std::vector<EdgeSample>* samples_in,
                      const std::vector<Eigen::Vector2d>& known_pixels,
                      const std::vector<double>& known_depths, const OutlineOptions& o,
                      const EdgeCheck& check, PointSource source,
                      const std::array<uint8_t, 3>& colour, EdgeCounts* counts,
                      std::vector<ViewStats>* stats, PlyData* points) {
  std::vector<EdgeSample>& samples = *samples_in;
  // Depth range of each sample from its nearest known points.
  {
    std::vector<std::pair<double, double>> by_distance(known_pixels.size());
    const size_t k = std::min<size_t>(std::max(1, o.depth_neighbours), known_pixels.size());
    for (EdgeSample& e : samples) {
      for (size_t i = 0; i < known_pixels.size(); ++i)
        by_distance[i] = {(known_pixels[i] - e.pixel).squaredNorm(), known_depths[i]};
      std::partial_sort(by_distance.begin(), by_distance.begin() + k, by_distance.end());
      double lo = std::numeric_limits<double>::infinity(), hi = 0;
      for (size_t i = 0; i < k; ++i) {
        lo = std::min(lo, by_distance[i].second);
        hi = std::max(hi, by_distance[i].second);
      }
      e.near_depth = lo * (1 - o.depth_margin);
      e.far_depth = hi * (1 + o.depth_margin);
      e.candidates.assign(num_views, {});
    }
  }

  const double min_cos = std::sin(o.min_epipolar_angle_deg * M_PI / 180);
  for (const View& view : others) {
    for (EdgeSample& e : samples) {
      const Eigen::Vector3d A =
          view.camera.CamFromWorld(RayPoint(ref.camera, e.pixel, e.near_depth));
      const Eigen::Vector3d B =
          view.camera.CamFromWorld(RayPoint(ref.camera, e.pixel, e.far_depth));
      if (!(A.z() > 0) || !(B.z() > 0)) continue;
      const Eigen::Vector2d a = view.camera.ProjectCam(A), b = view.camera.ProjectCam(B);
      const double length = (b - a).norm();
      if (length < 1) continue;
      const Eigen::Vector2d dir = (b - a) / length;
      // The sample's outward normal as this view sees it (at mid depth; only
      // for the crossing angle and the gradient's direction).
      const double mid = 0.5 * (e.near_depth + e.far_depth);
      const Eigen::Vector2d at = view.camera.Project(RayPoint(ref.camera, e.pixel, mid));
      const Eigen::Vector2d nj =
          (view.camera.Project(RayPoint(ref.camera, e.pixel + e.normal, mid)) - at).normalized();
      const double cos_cross = nj.dot(dir);
      if (!nj.allFinite() || std::abs(cos_cross) < min_cos) continue;
      const int sign_along = e.sign * (cos_cross > 0 ? 1 : -1);
      const int count = int(length / 0.5) + 1;
      std::vector<double> g(count, 0);
      for (int i = 0; i < count; ++i) {
        const Eigen::Vector2d p = a + 0.5 * i * dir;
        if (view.Inside(p)) g[i] = sign_along * view.Gradient(p).dot(dir);
      }
      const double floor = o.min_contrast * std::abs(cos_cross);
      for (int i = 1; i + 1 < count; ++i) {
        if (g[i] < floor || g[i] < g[i - 1] || g[i] <= g[i + 1]) continue;
        const Eigen::Vector2d c = a + 0.5 * (i + ParabolaPeak(g, i)) * dir;
        const Eigen::Vector2d grad = view.Gradient(c);
        if (e.sign * grad.normalized().dot(nj) < 0.85) continue;  // not this edge's direction
        // The step continues along the edge as this image shows it (a
        // tangent predicted from the reference is off where the edge
        // recedes in depth: set07's tilted panel).
        const Eigen::Vector2d normal = grad.normalized();  // grey rises along it
        if (!StepContinues(view, c, normal, o.straight_px, 0.5 * g[i] * std::abs(cos_cross)))
          continue;
        e.candidates[view.index].push_back({c, normal});
        if (stats) ++(*stats)[view.index].outline_candidates;
      }
    }
  }

  const std::vector<const View*> view_of = [&] {
    std::vector<const View*> v(num_views, nullptr);
    for (const View& view : others) v[view.index] = &view;
    return v;
  }();
  for (const EdgeSample& e : samples) {
    // Every candidate is a depth hypothesis; its support is the number of
    // other views with a candidate where that depth projects.
    struct Hypothesis {
      Eigen::Vector3d point;
      std::vector<Observation> obs;          // the reference first
      std::vector<int> views;                // of obs[1...]
      std::vector<Eigen::Vector2d> normals;  // of obs[1...]
    };
    std::vector<Hypothesis> hypotheses;
    for (int vi = 0; vi < num_views; ++vi) {
      for (const EdgeMatch& c : e.candidates[vi]) {
        Hypothesis h;
        h.point = Triangulate({&ref.camera, &view_of[vi]->camera}, {e.pixel, c.pixel});
        if (!h.point.allFinite()) continue;
        h.obs = {{&ref.camera, e.pixel}, {&view_of[vi]->camera, c.pixel}};
        h.views = {vi};
        h.normals = {c.normal};
        for (int vk = 0; vk < num_views; ++vk) {
          if (vk == vi || e.candidates[vk].empty()) continue;
          const Eigen::Vector3d xc = view_of[vk]->camera.CamFromWorld(h.point);
          if (!(xc.z() > 0)) continue;
          const Eigen::Vector2d expected = view_of[vk]->camera.ProjectCam(xc);
          const EdgeMatch* nearest = nullptr;
          double nearest_distance = o.agree_px;
          for (const EdgeMatch& ck : e.candidates[vk]) {
            const double d = (ck.pixel - expected).norm();
            if (d < nearest_distance) {
              nearest_distance = d;
              nearest = &ck;
            }
          }
          if (nearest) {
            h.obs.push_back({&view_of[vk]->camera, nearest->pixel});
            h.views.push_back(vk);
            h.normals.push_back(nearest->normal);
          }
        }
        hypotheses.push_back(std::move(h));
      }
    }
    int best = -1;
    for (size_t h = 0; h < hypotheses.size(); ++h)
      if (best < 0 || hypotheses[h].obs.size() > hypotheses[best].obs.size()) best = int(h);
    if (best < 0 || int(hypotheses[best].obs.size()) < o.min_views) {
      ++counts->unmatched;
      continue;
    }
    // Unambiguous: no hypothesis at a clearly different depth (its points
    // 3 px apart in some view) is as well supported.
    bool ambiguous = false;
    for (size_t h = 0; h < hypotheses.size() && !ambiguous; ++h) {
      if (hypotheses[h].obs.size() < hypotheses[best].obs.size()) continue;
      double apart = 0;
      for (const View& view : others) {
        const Eigen::Vector3d p = view.camera.CamFromWorld(hypotheses[h].point);
        const Eigen::Vector3d q = view.camera.CamFromWorld(hypotheses[best].point);
        if (p.z() > 0 && q.z() > 0)
          apart = std::max(apart, (view.camera.ProjectCam(p) - view.camera.ProjectCam(q)).norm());
      }
      ambiguous = apart > 3;
    }
    if (ambiguous) {
      ++counts->ambiguous;
      continue;
    }
    const Hypothesis& h = hypotheses[best];
    double depth = ref.camera.CamFromWorld(h.point).z(), worst = 0, error = 0;
    if (!DepthAcrossEdges(ref.camera, e.pixel, h.obs, h.normals, &depth, &worst, &error) ||
        worst > o.max_reprojection_px) {
      ++counts->unmatched;
      continue;
    }
    if (!check(e, depth)) {
      ++counts->off_surface;
      continue;
    }
    AppendPoint(RayPoint(ref.camera, e.pixel, depth), colour, int(h.obs.size()), error, source,
                points);
    if (stats)
      for (int vi : h.views) ++(*stats)[vi].outline_votes;
    ++counts->points;
  }
}

void AddOutlinePoints(const View& ref, const std::vector<View>& others, int num_views,
                      const Boundary& boundary, const cv::Mat1b& page,
                      const std::vector<Eigen::Vector2d>& known_pixels,
                      const std::vector<double>& known_depths, const OutlineOptions& o,
                      DensifyResult* result) {
  if (known_pixels.empty()) return;
  std::vector<EdgeSample> samples = EdgeSamples(ref, boundary, page, result->working_scale, o);
  result->outline.samples = int(samples.size());
  MatchEdgeSamples(
      ref, others, num_views, &samples, known_pixels, known_depths, o,
      [&](const EdgeSample& e, double depth) {
        return ContinuesSurface(e.pixel, depth, known_pixels, known_depths, o);
      },
      kOutline, {255, 0, 255}, &result->outline, &result->views, &result->points);
}

// Pixels and depths in `camera` of `page_points` and of the points made so far
// (`points` from `first_new` on): what the edge matching searches around.
void KnownPoints(const PinholeCamera& camera, const std::vector<Eigen::Vector3d>& page_points,
                 const PlyData& points, size_t first_new, std::vector<Eigen::Vector2d>* pixels,
                 std::vector<double>* depths) {
  auto add = [&](const Eigen::Vector3d& X) {
    const Eigen::Vector3d xc = camera.CamFromWorld(X);
    if (!(xc.z() > 0)) return;
    pixels->push_back(camera.ProjectCam(xc));
    depths->push_back(xc.z());
  };
  for (const Eigen::Vector3d& X : page_points) add(X);
  for (size_t i = first_new; i < points.vertices.size(); ++i) add(points.vertices[i]);
}

// --- shading-step points ----------------------------------------------------

// `view` with the gradient of a copy blurred by `sigma` instead: print is
// gone from it, the shading of folds is not.
View BlurredView(const View& view, double sigma) {
  View v = view;
  // New buffers: the copy's gx and gy share the original's, which Sobel
  // would otherwise overwrite.
  v.gx = cv::Mat1f();
  v.gy = cv::Mat1f();
  cv::Mat blurred;
  cv::GaussianBlur(view.grey, blurred, cv::Size(0, 0), sigma);
  cv::Sobel(blurred, v.gx, CV_32F, 1, 0, 3, 0.125);
  cv::Sobel(blurred, v.gy, CV_32F, 0, 1, 3, 0.125);
  return v;
}

// Steps of the blurred reference inside the page, at least
// `outline_gap_px` from its outline: the strongest ridge pixel of the
// gradient (non-maximum suppressed across the step) in each `step_px` cell,
// where it reaches `min_contrast` and continues as a step along its
// direction. Normals point the way grey rises (sign +1).
std::vector<EdgeSample> StepSamples(const View& blurred_ref, const cv::Mat1b& page,
                                    const std::vector<Eigen::Vector2d>& known_pixels,
                                    const StepOptions& o, double straight_px) {
  std::unique_ptr<PointIndex2d> known;
  if (o.min_point_gap_px > 0 && !known_pixels.empty())
    known = std::make_unique<PointIndex2d>(known_pixels);
  cv::Mat1b inside;
  const int gap = std::max(1, int(std::lround(o.outline_gap_px)));
  cv::erode(page, inside,
            cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * gap + 1, 2 * gap + 1)));
  const cv::Mat1f &gx = blurred_ref.gx, &gy = blurred_ref.gy;
  cv::Mat1f magnitude;
  cv::magnitude(gx, gy, magnitude);
  const int cell = std::max(1, int(std::lround(o.step_px)));
  const int cells_x = (page.cols + cell - 1) / cell;
  std::vector<std::pair<float, cv::Point>> best(size_t(cells_x) * ((page.rows + cell - 1) / cell),
                                                {0.f, cv::Point(-1, -1)});
  for (int y = 1; y + 1 < page.rows; ++y)
    for (int x = 1; x + 1 < page.cols; ++x) {
      const float m = magnitude(y, x);
      if (m < o.min_contrast || !inside(y, x)) continue;
      // Neighbours across the step: the gradient's direction rounded to 45
      // degrees, modulo 180 (0, 45, 90, 135 degrees).
      static constexpr int kAcross[4][2] = {{1, 0}, {1, 1}, {0, 1}, {1, -1}};
      const double angle = std::atan2(gy(y, x), gx(y, x));
      const int q = int(std::lround(angle / (M_PI / 4))) & 3;
      const int dx = kAcross[q][0], dy = kAcross[q][1];
      if (m < magnitude(y + dy, x + dx) || m < magnitude(y - dy, x - dx)) continue;
      auto& b = best[size_t(y / cell) * cells_x + x / cell];
      if (m > b.first) b = {m, cv::Point(x, y)};
    }
  std::vector<EdgeSample> samples;
  for (const auto& [m, p] : best) {
    if (p.x < 0) continue;
    const Eigen::Vector2d c(p.x, p.y);
    if (known && known->Nearest(c, 1).front().second < o.min_point_gap_px * o.min_point_gap_px)
      continue;
    const Eigen::Vector2d n = blurred_ref.Gradient(c).normalized();
    if (!n.allFinite()) continue;
    double offset = 0, strength = 0;
    if (!FindStep(blurred_ref, c, n, 2, 1, &offset, &strength)) continue;
    const Eigen::Vector2d at = c + offset * n;
    if (!StepContinues(blurred_ref, at, n, straight_px, 0.5 * strength)) continue;
    EdgeSample e;
    e.pixel = at;
    e.normal = n;
    e.sign = 1;
    samples.push_back(e);
  }
  return samples;
}

// The surface of the known points within `radius` of `pixel` on one side of
// the line through it with normal `normal` (side +1 or -1), by an affine
// fit of 1/depth (exact on a plane): its depth at `pixel` and |cos| of the
// angle between the reference ray there and the fitted plane's normal.
// False when fewer than 6 points there span an area.
bool SideSurface(const PinholeCamera& camera, const Eigen::Vector2d& pixel,
                 const Eigen::Vector2d& normal, int side, double radius,
                 const std::vector<Eigen::Vector2d>& known_pixels,
                 const std::vector<double>& known_depths, double* depth, double* cos_ray) {
  Eigen::Vector3d c;  // 1/z = c0 du + c1 dv + c2
  if (!FitInverseDepth(
          pixel, radius, known_pixels, known_depths,
          [&](const Eigen::Vector2d& d) { return side * d.dot(normal) >= 1; }, &c))
    return false;
  if (!(c(2) > 0)) return false;
  *depth = 1 / c(2);
  // 1/z = n.(K^-1 [u v 1]) / d for the plane n.X = d: n ~ K^T (c0, c1, c2 - c0 u - c1 v).
  const Eigen::Vector3d plane =
      camera.K.transpose() *
      Eigen::Vector3d(c(0), c(1), c(2) - c(0) * pixel.x() - c(1) * pixel.y());
  const Eigen::Vector3d ray = camera.K.inverse() * Eigen::Vector3d(pixel.x(), pixel.y(), 1);
  *cos_ray = std::abs(plane.normalized().dot(ray.normalized()));
  return true;
}

void AddStepPoints(const View& ref, const std::vector<View>& others, int num_views,
                   const cv::Mat1b& page, const std::vector<Eigen::Vector2d>& known_pixels,
                   const std::vector<double>& known_depths, const StepOptions& so,
                   const OutlineOptions& outline, DensifyResult* result) {
  if (known_pixels.empty()) return;
  const View blurred_ref = BlurredView(ref, so.blur_px);
  std::vector<View> blurred;
  for (const View& v : others) blurred.push_back(BlurredView(v, so.blur_px));
  // The outline's matching, but with the step's own contrast and views.
  OutlineOptions o = outline;
  o.min_contrast = so.min_contrast;
  o.min_views = so.min_views;
  std::vector<EdgeSample> samples = StepSamples(blurred_ref, page, known_pixels, so, o.straight_px);
  result->steps.samples = int(samples.size());
  MatchEdgeSamples(
      blurred_ref, blurred, num_views, &samples, known_pixels, known_depths, o,
      [&](const EdgeSample& e, double depth) {
        // On the surface of the points on each side of the step that has
        // them (a fold's crease lies on both panels; a silhouette does not),
        // and neither side seen edge-on (a fold seen edge-on in the
        // reference is its silhouette there, matched elsewhere in the
        // others). Without points on either side there is nothing to check
        // it against.
        auto on_sides = [&](double radius, int* fitted) {
          *fitted = 0;
          for (const int side : {1, -1}) {
            double d = 0, cos_ray = 0;
            if (!SideSurface(ref.camera, e.pixel, e.normal, side, radius, known_pixels,
                             known_depths, &d, &cos_ray))
              continue;
            ++*fitted;
            if (std::abs(d - depth) > so.max_depth_jump * depth || cos_ray < so.min_side_cos)
              return false;
          }
          return true;
        };
        int fitted = 0;
        if (!on_sides(so.side_radius_px, &fitted)) return false;
        if (fitted > 0) return true;
        if (!so.unsupported) return false;
        // Without points next to it, against the surface further out.
        return on_sides(so.unsupported_radius_factor * so.side_radius_px, &fitted);
      },
      kStep, {255, 255, 0}, &result->steps, nullptr, &result->points);
}

// "N <what> from M <samples> (U unmatched, A ambiguous, S off the surface), T s"
std::string CountsLine(const EdgeCounts& c, const std::string& what, const std::string& samples,
                       double seconds) {
  return std::to_string(c.points) + " " + what + " from " + std::to_string(c.samples) + " " +
         samples + " (" + std::to_string(c.unmatched) + " unmatched, " +
         std::to_string(c.ambiguous) + " ambiguous, " + std::to_string(c.off_surface) +
         " off the surface), " + std::to_string(seconds).substr(0, 4) + " s";
}

Json CountsJson(const EdgeCounts& c) {
  return {{"samples", c.samples},
          {"unmatched", c.unmatched},
          {"ambiguous", c.ambiguous},
          {"off_surface", c.off_surface}};
}

}  // namespace

PinholeCamera ScaleCamera(const PinholeCamera& camera, double scale) {
  PinholeCamera c = camera;
  if (scale == 1) return c;
  c.width = std::max(1, int(std::lround(camera.width * scale)));
  c.height = std::max(1, int(std::lround(camera.height * scale)));
  c.K(0, 0) *= scale;
  c.K(0, 1) *= scale;
  c.K(1, 1) *= scale;
  c.K(0, 2) = (camera.K(0, 2) + 0.5) * scale - 0.5;
  c.K(1, 2) = (camera.K(1, 2) + 0.5) * scale - 0.5;
  return c;
}

Eigen::Vector3d Triangulate(const std::vector<const PinholeCamera*>& cameras,
                            const std::vector<Eigen::Vector2d>& pixels) {
  const int n = int(cameras.size());
  Eigen::MatrixXd A(2 * n, 4);
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix<double, 3, 4> P;
    P.leftCols<3>() = cameras[i]->K * cameras[i]->R;
    P.col(3) = cameras[i]->K * cameras[i]->t;
    A.row(2 * i) = pixels[i].x() * P.row(2) - P.row(0);
    A.row(2 * i + 1) = pixels[i].y() * P.row(2) - P.row(1);
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d X = svd.matrixV().col(3);
  if (std::abs(X(3)) < 1e-12)
    return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  return X.head<3>() / X(3);
}

std::vector<bool> HiddenInReference(const std::vector<Eigen::Vector3d>& points,
                                    const std::vector<std::array<uint8_t, 3>>& colours,
                                    const std::vector<int>& indices, const PinholeCamera& camera,
                                    const cv::Mat& reference, const HiddenOptions& o) {
  std::vector<bool> hidden(indices.size(), false);
  if (colours.size() != points.size() || reference.empty() || indices.empty()) return hidden;
  // A cloud whose points all carry one colour (a writer's default) tells nothing.
  if (std::all_of(indices.begin(), indices.end(),
                  [&](int i) { return colours[i] == colours[indices[0]]; }))
    return hidden;
  // Projections and the exposure gain (median of reference / point, per channel).
  std::vector<cv::Point> pixel(indices.size(), cv::Point(-1, -1));
  std::array<std::vector<double>, 3> ratios;
  for (size_t k = 0; k < indices.size(); ++k) {
    const Eigen::Vector3d xc = camera.CamFromWorld(points[indices[k]]);
    if (!(xc.z() > 0)) continue;
    const Eigen::Vector2d p = camera.ProjectCam(xc);
    const long u = std::lround(p.x()), v = std::lround(p.y());
    if (u < 0 || v < 0 || u >= reference.cols || v >= reference.rows) continue;
    pixel[k] = cv::Point(int(u), int(v));
    const cv::Vec3b bgr = reference.at<cv::Vec3b>(pixel[k]);
    const std::array<uint8_t, 3>& rgb = colours[indices[k]];
    for (int c = 0; c < 3; ++c) ratios[c].push_back((bgr[2 - c] + 1.0) / (rgb[c] + 1.0));
  }
  if (ratios[0].empty()) return hidden;
  std::array<double, 3> gain{};
  for (int c = 0; c < 3; ++c) {
    std::vector<double>& r = ratios[c];
    std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
    gain[c] = r[r.size() / 2];
  }
  cv::Mat lab;
  cv::cvtColor(reference, lab, cv::COLOR_BGR2Lab);
  // The points' colours at the reference's exposure, in Lab (one conversion).
  cv::Mat3b point_lab(int(indices.size()), 1);
  for (size_t k = 0; k < indices.size(); ++k) {
    const std::array<uint8_t, 3>& rgb = colours[indices[k]];
    for (int c = 0; c < 3; ++c)
      point_lab(int(k), 0)[2 - c] = cv::saturate_cast<uint8_t>(rgb[c] * gain[c]);
  }
  cv::cvtColor(point_lab, point_lab, cv::COLOR_BGR2Lab);
  const int w = std::max(0, o.window_px);
  for (size_t k = 0; k < indices.size(); ++k) {
    if (pixel[k].x < 0) continue;
    const cv::Vec3d a = point_lab(int(k), 0);
    double nearest = std::numeric_limits<double>::infinity();
    for (int v = std::max(0, pixel[k].y - w); v <= std::min(lab.rows - 1, pixel[k].y + w); ++v)
      for (int u = std::max(0, pixel[k].x - w); u <= std::min(lab.cols - 1, pixel[k].x + w); ++u)
        nearest = std::min(nearest, cv::norm(a - cv::Vec3d(lab.at<cv::Vec3b>(v, u))));
    hidden[k] = nearest > o.max_colour_distance;
  }
  return hidden;
}

Json DensifyOptions::ToJson() const {
  return {{"max_image_size", max_image_size},
          {"region_margin_px", region_margin_px},
          {"texture",
           {{"enabled", texture.enabled},
            {"step_px", texture.step_px},
            {"min_texture", texture.min_texture},
            {"max_flow_disagreement_px", texture.max_flow_disagreement_px},
            {"max_reprojection_px", texture.max_reprojection_px},
            {"min_views", texture.min_views},
            {"min_triangulation_angle_deg", texture.min_triangulation_angle_deg},
            {"surface_prewarp", texture.surface_prewarp},
            {"surface_grid_px", texture.surface_grid_px},
            {"surface_neighbours", texture.surface_neighbours},
            {"surface_hole_px", texture.surface_hole_px}}},
          {"outline",
           {{"enabled", outline.enabled},
            {"step_px", outline.step_px},
            {"corner_gap_px", outline.corner_gap_px},
            {"min_contrast", outline.min_contrast},
            {"depth_neighbours", outline.depth_neighbours},
            {"depth_margin", outline.depth_margin},
            {"min_epipolar_angle_deg", outline.min_epipolar_angle_deg},
            {"straight_px", outline.straight_px},
            {"agree_px", outline.agree_px},
            {"max_reprojection_px", outline.max_reprojection_px},
            {"continuity_radius_px", outline.continuity_radius_px},
            {"max_depth_jump", outline.max_depth_jump},
            {"min_views", outline.min_views}}},
          {"steps",
           {{"enabled", steps.enabled},
            {"blur_px", steps.blur_px},
            {"step_px", steps.step_px},
            {"min_contrast", steps.min_contrast},
            {"outline_gap_px", steps.outline_gap_px},
            {"min_point_gap_px", steps.min_point_gap_px},
            {"side_radius_px", steps.side_radius_px},
            {"max_depth_jump", steps.max_depth_jump},
            {"min_side_cos", steps.min_side_cos},
            {"unsupported", steps.unsupported},
            {"unsupported_radius_factor", steps.unsupported_radius_factor},
            {"min_views", steps.min_views}}},
          {"hidden",
           {{"enabled", hidden.enabled},
            {"max_colour_distance", hidden.max_colour_distance},
            {"window_px", hidden.window_px}}}};
}

DensifyInputs ReadInputs(const DensifyOptions& o) {
  DensifyInputs in;
  const fs::path cameras_path = o.sfm_dir / "cameras.json";
  in.cameras = ReadCameras(cameras_path);
  const PinholeCamera* ref = in.cameras.Find(in.cameras.reference);
  if (!ref) throw InputError(cameras_path.string() + ": no reference view (not written by sfm?)");
  {
    const Json doc = ReadJsonFile(cameras_path);
    const JsonReader r(doc, cameras_path);
    for (size_t i = 0; i < in.cameras.views.size(); ++i)
      in.distortion.push_back(ReadDistortion(r, "/views/" + std::to_string(i)));
  }
  in.reference = ReadImage(o.sfm_dir / "reference.png", cv::IMREAD_COLOR);
  if (in.reference.cols != ref->width || in.reference.rows != ref->height)
    throw InputError((o.sfm_dir / "reference.png").string() + ": " +
                     std::to_string(in.reference.cols) + "x" + std::to_string(in.reference.rows) +
                     " differs from the reference camera's " + std::to_string(ref->width) + "x" +
                     std::to_string(ref->height));
  const fs::path images = o.data_dir / "images";
  for (const PinholeCamera& view : in.cameras.views) {
    if (view.image == in.cameras.reference) {
      in.photos.emplace_back();
      continue;
    }
    in.photos.push_back(
        ReadViewPhoto(images / view.image, view, cameras_path, cv::IMREAD_GRAYSCALE));
  }
  const fs::path boundary_file =
      fs::is_directory(o.boundary) ? o.boundary / "boundary.json" : o.boundary;
  in.boundary = ReadBoundary(boundary_file);
  in.region = ReadDocumentMask(boundary_file.parent_path() / "mask.png", ref->width, ref->height);
  in.points = ReadPly(o.sfm_dir / "points.ply");
  if (in.points.vertices.empty())
    throw InputError((o.sfm_dir / "points.ply").string() + ": no points");
  return in;
}

DensifyResult Run(const DensifyInputs& in, const DensifyOptions& o) {
  const auto start = Clock::now();
  if (o.max_image_size < 64) throw UsageError("--max-image-size must be at least 64");
  if (o.texture.step_px < 1 || o.outline.step_px < 1)
    throw UsageError("--texture-step and --outline-step must be at least 1 pixel");
  DensifyResult r;
  const PinholeCamera& ref_camera = *in.cameras.Find(in.cameras.reference);
  const int num_views = int(in.cameras.views.size());
  r.views.resize(num_views);
  for (int i = 0; i < num_views; ++i) r.views[i].image = in.cameras.views[i].image;

  // sfm's points of the region, less those the reference view shows in another colour.
  const cv::Mat1b full_region = GrowRegion(in.region, o.region_margin_px);
  const std::vector<int> in_region = PointsInRegion(in.points.vertices, ref_camera, full_region);
  r.sfm_points_in_region = int(in_region.size());
  std::vector<bool> keep(in.points.vertices.size(), true);
  if (o.hidden.enabled) {
    const std::vector<bool> hidden = HiddenInReference(
        in.points.vertices, in.points.colors, in_region, ref_camera, in.reference, o.hidden);
    for (size_t k = 0; k < in_region.size(); ++k)
      if (hidden[k]) {
        keep[in_region[k]] = false;
        r.hidden.push_back(in.points.vertices[in_region[k]]);
      }
  }
  // The texture's prewarp (a homography, RANSAC) takes every point of the
  // region, hidden ones included: they are its outliers anyway, and a
  // different sample of points moved which texture points a curl kept
  // (set06: 0.88 -> 0.54 MS-SSIM). Fitted points and the outline's depths
  // take only the points the reference view sees.
  std::vector<Eigen::Vector3d> region_points, page_points;
  for (const int i : in_region) {
    region_points.push_back(in.points.vertices[i]);
    if (keep[i]) page_points.push_back(in.points.vertices[i]);
  }

  // Output cloud: sfm's points first (those kept, in order, with their
  // properties), then ours.
  r.sfm_points = int(in.points.vertices.size());
  auto sfm_property = [&](const char* name, double fallback) {
    const PlyProperty* p = in.points.FindProperty(name);
    return p ? p->values : std::vector<double>(in.points.vertices.size(), fallback);
  };
  const std::vector<double> track_length = sfm_property("track_length", 2);
  const std::vector<double> reprojection_error = sfm_property("reprojection_error", 0);
  const bool has_colours = in.points.colors.size() == in.points.vertices.size();
  r.points.properties = {{"track_length", PlyScalar::kUint32, {}},
                         {"reprojection_error", PlyScalar::kFloat32, {}},
                         {"source", PlyScalar::kUint8, {}}};
  for (size_t i = 0; i < in.points.vertices.size(); ++i) {
    if (!keep[i]) continue;
    AppendPoint(in.points.vertices[i],
                has_colours ? in.points.colors[i] : std::array<uint8_t, 3>{200, 200, 200},
                int(track_length[i]), reprojection_error[i], kSfm, &r.points);
  }
  const size_t first_new_point = r.points.vertices.size();
  r.points.comments = {
      "docunfold densify: sfm's points (source 0; those the reference view " +
          in.cameras.reference +
          " shows in another colour, behind the page, left out), then points triangulated "
          "from the texture of the page (1), from its outline (2) and from shading steps of "
          "blank paper (3), cameras of 10_sfm held fixed",
      "frame: that of 10_sfm/cameras.json (camera of the reference view " + in.cameras.reference +
          ")"};

  // Working copies.
  auto t = Clock::now();
  const int long_side = std::max(ref_camera.width, ref_camera.height);
  r.working_scale = std::min(1.0, double(o.max_image_size) / long_side);
  cv::Mat ref_grey;
  cv::cvtColor(in.reference, ref_grey, cv::COLOR_BGR2GRAY);
  const int ref_index = int(in.cameras.Find(in.cameras.reference) - in.cameras.views.data());
  const View ref = MakeView(ref_index, ref_camera, ref_grey, {}, r.working_scale);
  std::vector<View> others;
  for (int i = 0; i < num_views; ++i) {
    if (i == ref_index) continue;
    others.push_back(
        MakeView(i, in.cameras.views[i], in.photos[i], in.distortion[i], r.working_scale));
  }
  cv::Mat1b region, page;
  cv::resize(full_region, region, ref.grey.size(), 0, 0, cv::INTER_NEAREST);
  cv::resize(in.region, page, ref.grey.size(), 0, 0, cv::INTER_NEAREST);
  r.seconds_reading = SecondsSince(t);
  if (others.empty()) r.warnings.push_back("only one view: nothing to match, no points added");

  t = Clock::now();
  std::vector<Track> tracks;
  if (o.texture.enabled && !others.empty()) {
    tracks = TextureSamples(ref, region, o.texture);
    r.texture_samples = int(tracks.size());
    FollowByHomography(ref, others, region_points, o.texture, &tracks, &r);
    r.texture_points = TriangulateTracks(ref, in.reference, o.texture, &tracks, &r);
  }
  r.seconds_texture = SecondsSince(t);
  Log(std::to_string(r.texture_points) + " texture points from " +
      std::to_string(r.texture_samples) + " textured samples, " +
      std::to_string(r.seconds_texture).substr(0, 4) + " s");

  t = Clock::now();
  if (o.outline.enabled && !others.empty()) {
    // Known depths for the outline's search: the page's sfm points and the
    // texture points just made.
    std::vector<Eigen::Vector2d> pixels;
    std::vector<double> depths;
    KnownPoints(ref.camera, page_points, r.points, first_new_point, &pixels, &depths);
    if (in.boundary.RealSides() == 0)
      r.warnings.push_back("no real boundary side: no outline points");
    AddOutlinePoints(ref, others, num_views, in.boundary, page, pixels, depths, o.outline, &r);
  }
  r.seconds_outline = SecondsSince(t);
  Log(CountsLine(r.outline, "outline points", "edge samples", r.seconds_outline));

  t = Clock::now();
  if (o.steps.enabled && !others.empty()) {
    // Known depths: the page's sfm points and every point made so far.
    std::vector<Eigen::Vector2d> pixels;
    std::vector<double> depths;
    KnownPoints(ref.camera, page_points, r.points, first_new_point, &pixels, &depths);
    AddStepPoints(ref, others, num_views, page, pixels, depths, o.steps, o.outline, &r);
    r.seconds_steps = SecondsSince(t);
    Log(CountsLine(r.steps, "shading-step points", "step samples", r.seconds_steps));
  }

  t = Clock::now();
  if (o.texture.enabled && o.texture.surface_prewarp && !others.empty()) {
    std::vector<Eigen::Vector3d> known = page_points;
    known.insert(known.end(), r.points.vertices.begin() + first_new_point, r.points.vertices.end());
    for (Track& track : tracks) track.obs.clear();
    if (o.texture.surface_hole_px > 0) {
      std::vector<Eigen::Vector2d> found;
      for (const Track& track : tracks)
        if (track.done) found.push_back(track.pixel);
      if (!found.empty()) {
        const PointIndex2d index(found);
        const double hole2 = o.texture.surface_hole_px * o.texture.surface_hole_px;
        for (Track& track : tracks)
          if (!track.done && index.Nearest(track.pixel, 1).front().second < hole2)
            track.done = true;  // next to what the first pass found: left alone
      }
    }
    FollowBySurface(ref, others, region, known, o.texture, &tracks, &r);
    r.texture_points_surface = TriangulateTracks(ref, in.reference, o.texture, &tracks, &r);
    r.texture_points += r.texture_points_surface;
  }
  r.seconds_surface = SecondsSince(t);
  if (o.texture.surface_prewarp)
    Log(std::to_string(r.texture_points_surface) +
        " texture points more with the other photos brought onto the reference through the "
        "points' surface, " +
        std::to_string(r.seconds_surface).substr(0, 4) + " s");
  r.seconds_total = SecondsSince(start);
  return r;
}

void WriteOutputs(const DensifyInputs& in, const DensifyResult& r, const DensifyOptions& o) {
  EnsureDirectory(o.out_dir);
  WritePly(o.out_dir / "points.ply", r.points);

  // Overlay: the reference image dimmed, points by source.
  cv::Mat overlay = in.reference * 0.55;
  const PinholeCamera& ref = *in.cameras.Find(in.cameras.reference);
  const double radius_scale = std::max(1.0, std::max(ref.width, ref.height) / 1600.0);
  const cv::Scalar colours[4] = {cv::Scalar(255, 200, 0), cv::Scalar(80, 220, 80),
                                 cv::Scalar(255, 0, 255), cv::Scalar(0, 230, 255)};
  const std::vector<double>& source = r.points.properties[2].values;
  for (int pass = 0; pass < 4; ++pass)
    for (size_t i = 0; i < r.points.vertices.size(); ++i) {
      if (int(source[i]) != pass) continue;
      const Eigen::Vector3d xc = ref.CamFromWorld(r.points.vertices[i]);
      if (!(xc.z() > 0)) continue;
      const Eigen::Vector2d p = ref.ProjectCam(xc);
      if (p.x() < 0 || p.y() < 0 || p.x() >= ref.width || p.y() >= ref.height) continue;
      cv::circle(overlay, cv::Point(int(std::lround(p.x())), int(std::lround(p.y()))),
                 int(std::lround(radius_scale * (pass == 2 ? 3 : 2))), colours[pass], -1,
                 cv::LINE_AA);
    }
  // Left out as hidden behind the page: red crosses.
  const cv::Scalar hidden_colour(0, 0, 255);
  const int arm = int(std::lround(4 * radius_scale));
  for (const Eigen::Vector3d& X : r.hidden) {
    const Eigen::Vector3d xc = ref.CamFromWorld(X);
    if (!(xc.z() > 0)) continue;
    const Eigen::Vector2d p = ref.ProjectCam(xc);
    const cv::Point c(int(std::lround(p.x())), int(std::lround(p.y())));
    cv::line(overlay, c - cv::Point(arm, arm), c + cv::Point(arm, arm), hidden_colour,
             int(std::lround(radius_scale)), cv::LINE_AA);
    cv::line(overlay, c - cv::Point(arm, -arm), c + cv::Point(arm, -arm), hidden_colour,
             int(std::lround(radius_scale)), cv::LINE_AA);
  }
  const double font = 0.8 * radius_scale;
  const int thick = int(std::lround(2 * radius_scale));
  const int sfm_kept = r.sfm_points_in_region - int(r.hidden.size());
  const std::string legend[5] = {"sfm " + std::to_string(sfm_kept),
                                 "texture " + std::to_string(r.texture_points),
                                 "outline " + std::to_string(r.outline.points),
                                 "shading steps " + std::to_string(r.steps.points),
                                 "hidden (left out) " + std::to_string(r.hidden.size())};
  const cv::Scalar legend_colours[5] = {colours[0], colours[1], colours[2], colours[3],
                                        hidden_colour};
  for (int i = 0, row = 0; i < 5; ++i) {
    if (i == 3 && !o.steps.enabled) continue;
    cv::putText(overlay, legend[i],
                cv::Point(int(20 * radius_scale), int((40 + 34 * row++) * radius_scale)),
                cv::FONT_HERSHEY_SIMPLEX, font, legend_colours[i], thick, cv::LINE_AA);
  }
  WriteImageAtomic(o.out_dir / "overlay.png", overlay, {cv::IMWRITE_PNG_COMPRESSION, 1});

  Json doc = MakeHeader("docunfold.points", 1, "densify", o.ToJson());
  doc["reference"] = in.cameras.reference;
  doc["working_scale"] = r.working_scale;
  doc["points"] = {{"sfm", r.sfm_points},
                   {"sfm_in_region", r.sfm_points_in_region},
                   {"sfm_hidden", r.hidden.size()},
                   {"texture", r.texture_points},
                   {"texture_surface_prewarp", r.texture_points_surface},
                   {"outline", r.outline.points},
                   {"steps", r.steps.points},
                   {"total", r.points.vertices.size()}};
  doc["texture"] = {{"samples", r.texture_samples}};
  doc["outline"] = CountsJson(r.outline);
  doc["steps"] = CountsJson(r.steps);
  doc["views"] = Json::array();
  for (const ViewStats& v : r.views)
    doc["views"].push_back({{"image", v.image},
                            {"page_points", v.page_points},
                            {"flow_matches", v.flow_matches},
                            {"surface_flow_matches", v.surface_flow_matches},
                            {"outline_candidates", v.outline_candidates},
                            {"outline_votes", v.outline_votes}});
  doc["warnings"] = r.warnings;
  doc["seconds"] = {{"reading", r.seconds_reading}, {"texture", r.seconds_texture},
                    {"outline", r.seconds_outline}, {"texture_surface_prewarp", r.seconds_surface},
                    {"steps", r.seconds_steps},     {"total", r.seconds_total}};
  WriteJsonAtomic(o.out_dir / "points.json", doc);
}

}  // namespace docunfold::densify
