// Texture points: textured samples of the reference view followed into the
// other photos by optical flow and triangulated.
#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "common/depth_field.h"
#include "common/point_index.h"
#include "common/statistics.h"
#include "stages/densify/densify_internal.h"

namespace docunfold::densify::detail {

cv::Mat1f CornerStrength(const cv::Mat1b& grey, const cv::Mat1b& region, double fraction,
                         double* threshold) {
  cv::Mat1f strength;
  cv::cornerMinEigenVal(grey, strength, 7, 3);
  std::vector<float> values;
  for (int y = 0; y < region.rows; ++y)
    for (int x = 0; x < region.cols; ++x)
      if (region(y, x)) values.push_back(strength(y, x));
  if (values.empty()) return {};
  const size_t q95 = values.size() * 95 / 100;
  *threshold = fraction * NthSmallest(std::move(values), q95);
  return strength;
}

std::unique_ptr<DepthField> SurfaceOfPoints(const PinholeCamera& camera,
                                            const std::vector<Eigen::Vector3d>& known,
                                            int neighbours, double scale_px) {
  std::vector<Eigen::Vector2d> pixels;
  std::vector<double> depths;
  for (const Eigen::Vector3d& X : known) {
    const Eigen::Vector3d xc = camera.CamFromWorld(X);
    if (!(xc.z() > 0)) continue;
    pixels.push_back(camera.ProjectCam(xc));
    depths.push_back(xc.z());
  }
  if (pixels.size() < 16) return nullptr;
  return std::make_unique<DepthField>(pixels, depths, neighbours, scale_px, DepthModel::kPlanar,
                                      neighbours);
}

namespace {

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

// Every `step_px`-th pixel of the region with enough texture (text, print).
std::vector<Track> TextureSamples(const View& ref, const cv::Mat1b& region,
                                  const TextureOptions& o) {
  double threshold = 0;
  const cv::Mat1f texture = CornerStrength(ref.grey, region, o.min_texture, &threshold);
  if (texture.empty()) return {};
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
    AppendPoint(X, {bgr[2], bgr[1], bgr[0]}, int(obs.size()), error, PointSource::kTexture,
                &result->points);
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
  const std::unique_ptr<DepthField> surface =
      SurfaceOfPoints(ref.camera, known, o.surface_neighbours, 2 * o.surface_grid_px);
  if (!surface) return;
  const DepthField& depth = *surface;
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
        const float inv = SampleOrZero(inverse_depth, double(x - box.x) / g, double(y - box.y) / g);
        if (!(inv > 0)) continue;
        const Eigen::Vector3d xc =
            view.camera.CamFromWorld(ref.camera.LiftAtDepth(Eigen::Vector2d(x, y), 1 / inv));
        if (!(xc.z() > 0)) continue;
        const Eigen::Vector2d p = view.camera.ProjectCam(xc);
        if (view.Inside(p, 0)) map(y, x) = cv::Vec2f(float(p.x()), float(p.y()));
      }
    cv::Mat1b warped;
    cv::remap(view.grey, warped, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
    cv::Mat1b covered;
    cv::inRange(map, cv::Scalar(0, 0), cv::Scalar(view.grey.cols - 1, view.grey.rows - 1), covered);
    // Bilinear in the map, its four corners summed in this order (not
    // SampleBilinear's: other roundings), and false next to an unmapped pixel.
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

}  // namespace

std::vector<Track> AddTexturePoints(const View& ref, const std::vector<View>& others,
                                    const cv::Mat1b& region,
                                    const std::vector<Eigen::Vector3d>& region_points,
                                    const cv::Mat& reference_bgr, const TextureOptions& o,
                                    DensifyResult* result) {
  std::vector<Track> tracks = TextureSamples(ref, region, o);
  result->texture_samples = int(tracks.size());
  FollowByHomography(ref, others, region_points, o, &tracks, result);
  result->texture_points = TriangulateTracks(ref, reference_bgr, o, &tracks, result);
  return tracks;
}

void AddSurfaceTexturePoints(const View& ref, const std::vector<View>& others,
                             const cv::Mat1b& region, const std::vector<Eigen::Vector3d>& known,
                             const cv::Mat& reference_bgr, const TextureOptions& o,
                             std::vector<Track>* tracks_in, DensifyResult* result) {
  std::vector<Track>& tracks = *tracks_in;
  for (Track& track : tracks) track.obs.clear();
  if (o.surface_hole_px > 0) {
    std::vector<Eigen::Vector2d> found;
    for (const Track& track : tracks)
      if (track.done) found.push_back(track.pixel);
    if (!found.empty()) {
      const PointIndex2d index(found);
      const double hole2 = o.surface_hole_px * o.surface_hole_px;
      for (Track& track : tracks)
        if (!track.done && index.Nearest(track.pixel, 1).front().second < hole2)
          track.done = true;  // next to what the first pass found: left alone
    }
  }
  FollowBySurface(ref, others, region, known, o, &tracks, result);
  result->texture_points_surface = TriangulateTracks(ref, reference_bgr, o, &tracks, result);
  result->texture_points += result->texture_points_surface;
}

}  // namespace docunfold::densify::detail
