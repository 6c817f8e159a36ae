#include "stages/densify/densify.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include "common/errors.h"
#include "common/option_table.h"
#include "common/program.h"
#include "stages/densify/densify_internal.h"

namespace docunfold::densify {

void DeclareOptions(OptionTable& table, DensifyOptions* o) {
  table.Value("max-image-size", &o->max_image_size, 64, 100000,
              "long side of the working copies of the photos (px)");
  table.Value("region-margin-px", &o->region_margin_px, 0.0, 1000.0,
              "document region (mask.png) grown by this many pixels");
  table.Switch("texture", &o->texture.enabled,
               "texture points: print followed from the reference view by optical flow");
  table.Value("texture-step", &o->texture.step_px, 1.0, 1000.0,
              "texture: grid spacing (working-copy px)");
  table.Value("min-texture", &o->texture.min_texture, 0.0, 1.0,
              "texture: skip pixels whose structure-tensor minimum eigenvalue is below this "
              "fraction of the region's 95th percentile");
  table.Value("texture-min-views", &o->texture.min_views, 2, 1000,
              "texture: photos a point needs, the reference included");
  table.Switch("surface-prewarp", &o->texture.surface_prewarp,
               "texture: a second pass for the samples the first left without a point, the "
               "photos brought onto the reference through the surface of the points found "
               "first instead of the page's homography (the far side of a fold)");
  table.Value("surface-hole-px", &o->texture.surface_hole_px, 0.0, 10000.0,
              "texture, second pass: only samples at least this far from every point the "
              "first pass made (working-copy px; 0 = every sample it left)");
  table.Value("surface-grid", &o->texture.surface_grid_px, 1.0, 100.0,
              "texture, second pass: the surface's depth is fitted every this many "
              "working-copy px and interpolated in between");
  table.Switch("outline", &o->outline.enabled,
               "outline points: the page's real sides matched along epipolar lines");
  table.Value("outline-step", &o->outline.step_px, 1.0, 1000.0,
              "outline: spacing of the samples along the real sides (working-copy px)");
  table.Value("outline-min-views", &o->outline.min_views, 2, 1000,
              "outline: photos that must agree on a point, the reference included");
  table.Value("outline-agree-px", &o->outline.agree_px, 0.1, 100.0,
              "outline: other photos agree when their edge is within this distance (px)");
  table.Switch("outline-side-lines", &o->outline.side_lines,
               "outline: samples of a straight side the matching left get points where their rays "
               "meet the planes through the other photos' cameras and the side's straight image "
               "in them (a standing end every photo's rays graze)");
  table.Switch("steps", &o->steps.enabled,
               "shading-step points (steps of blank paper such as a fold's crease, matched "
               "on copies blurred so that print is gone)");
  table.Value("step-blur", &o->steps.blur_px, 0.5, 50.0,
              "steps: Gaussian sigma of the blurred copies (working-copy px)");
  table.Value("step-min-contrast", &o->steps.min_contrast, 0.01, 255.0,
              "steps: grey levels per pixel across a step on the blurred copy");
  table.Value("step-min-views", &o->steps.min_views, 2, 1000,
              "steps: photos that must agree on a point, the reference included");
  table.Value("step-point-gap", &o->steps.min_point_gap_px, 0.0, 10000.0,
              "steps: only where no point is this close already, blank paper (working-copy "
              "px; 0 = in print too)");
  table.Value("step-max-depth-jump", &o->steps.max_depth_jump, 0.0, 1.0,
              "steps: a point's depth may differ this much (fraction) from the surface of "
              "the points on either side of its step");
  table.Value("step-min-side-cos", &o->steps.min_side_cos, 0.0, 1.0,
              "steps: refused where the surface on either side is seen this edge-on from the "
              "reference (|cos| between ray and normal)");
  table.Value("step-unsupported-radius", &o->steps.unsupported_radius_factor, 1.0, 100.0,
              "steps: points without known points next to them are checked against those "
              "within this many times the side radius");
  table.Value("step-side-radius", &o->steps.side_radius_px, 1.0, 10000.0,
              "steps: a point must lie on the surface of the known points within this "
              "radius on each side of its step (working-copy px)");
  table.Switch("sweep", &o->sweep.enabled,
               "swept points: print no other pass reached, found by sweeping depth along the "
               "reference's rays around the surface of the points so far (NCC in the other "
               "photos)");
  table.Value("sweep-rounds", &o->sweep.rounds, 1, 100,
              "sweep: rounds, each around the surface of the points so far");
  table.Value("sweep-min-ncc", &o->sweep.min_ncc, -1.0, 1.0,
              "sweep: NCC each of the two best photos must reach at the chosen depth");
  table.Switch("keep-hidden", &o->keep_hidden,
               "keep sfm points of the document region that the reference view shows in "
               "another colour (else they are left out as behind the page)");
  table.Value("hidden-colour-distance", &o->hidden.max_colour_distance, 0.0, 500.0,
              "hidden: colour difference (CIE76, OpenCV 8-bit Lab) beyond which an sfm point "
              "is not what the reference view shows");
}

namespace detail {

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

void AppendPoint(const Eigen::Vector3d& X, const std::array<uint8_t, 3>& rgb, int views,
                 double reprojection_error, PointSource source, PlyData* points) {
  points->vertices.push_back(X);
  points->colors.push_back(rgb);
  points->properties[0].values.push_back(views);
  points->properties[1].values.push_back(reprojection_error);
  points->properties[2].values.push_back(double(source));
}

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

}  // namespace detail

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

namespace {

using detail::View;

// sfm's points of the document region as the steps after use them.
struct SfmPoints {
  // Every one (the texture's prewarp takes them all, see
  // docs/decisions/densify.md, "The prewarp takes the hidden points too")...
  std::vector<Eigen::Vector3d> region_points;
  // ...and those not hidden behind the page: fitted, and the depths the
  // edge matching searches around.
  std::vector<Eigen::Vector3d> page_points;
};

// Judges which sfm points of the region the reference view shows in another
// colour (unless keep_hidden) and starts the output cloud with sfm's other
// points, in order, with their properties.
SfmPoints StartWithSfmPoints(const DensifyInputs& in, const DensifyOptions& o,
                             const PinholeCamera& ref_camera, const cv::Mat1b& full_region,
                             DensifyResult* result) {
  DensifyResult& r = *result;
  const std::vector<int> in_region = PointsInRegion(in.points.vertices, ref_camera, full_region);
  r.sfm_points_in_region = int(in_region.size());
  std::vector<bool> keep(in.points.vertices.size(), true);
  if (!o.keep_hidden) {
    const std::vector<bool> hidden = HiddenInReference(
        in.points.vertices, in.points.colors, in_region, ref_camera, in.reference, o.hidden);
    for (size_t k = 0; k < in_region.size(); ++k)
      if (hidden[k]) {
        keep[in_region[k]] = false;
        r.hidden.push_back(in.points.vertices[in_region[k]]);
      }
  }
  SfmPoints sfm;
  for (const int i : in_region) {
    sfm.region_points.push_back(in.points.vertices[i]);
    if (keep[i]) sfm.page_points.push_back(in.points.vertices[i]);
  }

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
    detail::AppendPoint(in.points.vertices[i],
                        has_colours ? in.points.colors[i] : std::array<uint8_t, 3>{200, 200, 200},
                        int(track_length[i]), reprojection_error[i], PointSource::kSfm, &r.points);
  }
  r.points.comments = {
      "docunfold densify: sfm's points (source 0; those the reference view " +
          in.cameras.reference +
          " shows in another colour, behind the page, left out), then points triangulated "
          "from the texture of the page (1), from its outline (2), from shading steps of "
          "blank paper (3) and found by sweeping depth (4), cameras of 10_sfm held fixed",
      "frame: that of 10_sfm/cameras.json (camera of the reference view " + in.cameras.reference +
          ")"};
  return sfm;
}

// The photos as the matching works on them, and the document region at
// their size.
struct WorkingCopies {
  View ref;
  std::vector<View> others;  // every other view
  cv::Mat1b region;          // grown by region_margin_px
  cv::Mat1b page;            // as segment-boundary found it
};

// Sets result->working_scale and makes the working copies.
WorkingCopies MakeWorkingCopies(const DensifyInputs& in, const DensifyOptions& o,
                                const PinholeCamera& ref_camera, const cv::Mat1b& full_region,
                                DensifyResult* result) {
  const int num_views = int(in.cameras.views.size());
  // Every view at most max_image_size long: a photo from a larger sensor is
  // brought down to about the reference's resolution, not kept at its own.
  const auto scale_of = [&](const PinholeCamera& camera) {
    return std::min(1.0, double(o.max_image_size) / std::max(camera.width, camera.height));
  };
  result->working_scale = scale_of(ref_camera);
  cv::Mat ref_grey;
  cv::cvtColor(in.reference, ref_grey, cv::COLOR_BGR2GRAY);
  const int ref_index = int(in.cameras.Find(in.cameras.reference) - in.cameras.views.data());
  WorkingCopies w;
  w.ref = detail::MakeView(ref_index, ref_camera, ref_grey, {}, result->working_scale);
  for (int i = 0; i < num_views; ++i) {
    if (i == ref_index) continue;
    const PinholeCamera& camera = in.cameras.views[i];
    w.others.push_back(
        detail::MakeView(i, camera, in.photos[i], in.distortion[i], scale_of(camera)));
  }
  cv::resize(full_region, w.region, w.ref.grey.size(), 0, 0, cv::INTER_NEAREST);
  cv::resize(in.region, w.page, w.ref.grey.size(), 0, 0, cv::INTER_NEAREST);
  return w;
}

// "N <what> from M <samples> (U unmatched, A ambiguous, S off the surface), T s"
std::string CountsLine(const EdgeCounts& c, const std::string& what, const std::string& samples,
                       double seconds) {
  return std::to_string(c.points) + " " + what + " from " + std::to_string(c.samples) + " " +
         samples + " (" + std::to_string(c.unmatched) + " unmatched, " +
         std::to_string(c.ambiguous) + " ambiguous, " + std::to_string(c.off_surface) +
         " off the surface" +
         (c.side_line_points + c.side_line_weak > 0
              ? "; " + std::to_string(c.side_line_points) + " of those from the sides' lines, " +
                    std::to_string(c.side_line_weak) + " too weakly determined by them"
              : std::string()) +
         "), " + Fixed(seconds, 2) + " s";
}

}  // namespace

DensifyResult Run(const DensifyInputs& in, const DensifyOptions& o) {
  StepTimer timer;
  if (o.max_image_size < 64) throw UsageError("--max-image-size must be at least 64");
  if (o.texture.step_px < 1 || o.outline.step_px < 1)
    throw UsageError("--texture-step and --outline-step must be at least 1 pixel");
  DensifyResult r;
  const PinholeCamera& ref_camera = *in.cameras.Find(in.cameras.reference);
  const int num_views = int(in.cameras.views.size());
  r.views.resize(num_views);
  for (int i = 0; i < num_views; ++i) r.views[i].image = in.cameras.views[i].image;

  // sfm's points first (less the hidden ones), then ours.
  const cv::Mat1b full_region = GrowRegion(in.region, o.region_margin_px);
  const SfmPoints sfm = StartWithSfmPoints(in, o, ref_camera, full_region, &r);
  const size_t first_new_point = r.points.vertices.size();
  timer.Mark("sfm points");

  const WorkingCopies w = MakeWorkingCopies(in, o, ref_camera, full_region, &r);
  // The page's sfm points and every point made so far: the surface the later
  // passes work around.
  const auto points_so_far = [&] {
    std::vector<Eigen::Vector3d> known = sfm.page_points;
    known.insert(known.end(), r.points.vertices.begin() + first_new_point, r.points.vertices.end());
    return known;
  };
  r.seconds_reading = timer.Mark("working copies");
  const bool matching = !w.others.empty();
  if (!matching) r.warnings.push_back("only one view: nothing to match, no points added");

  std::vector<detail::Track> tracks;
  if (o.texture.enabled && matching)
    tracks = detail::AddTexturePoints(w.ref, w.others, w.region, sfm.region_points, in.reference,
                                      o.texture, &r);
  r.seconds_texture = timer.Mark("texture");
  Log(std::to_string(r.texture_points) + " texture points from " +
      std::to_string(r.texture_samples) + " textured samples, " + Fixed(r.seconds_texture, 2) +
      " s");

  if (o.outline.enabled && matching) {
    // Known depths for the outline's search: the page's sfm points and the
    // texture points just made.
    std::vector<Eigen::Vector2d> pixels;
    std::vector<double> depths;
    detail::KnownPoints(w.ref.camera, sfm.page_points, r.points, first_new_point, &pixels, &depths);
    if (in.boundary.RealSides() == 0)
      r.warnings.push_back("no real boundary side: no outline points");
    detail::AddOutlinePoints(w.ref, w.others, num_views, in.boundary, w.page, pixels, depths,
                             o.outline, &r);
  }
  r.seconds_outline = timer.Mark("outline");
  Log(CountsLine(r.outline, "outline points", "edge samples", r.seconds_outline));

  if (o.steps.enabled && matching) {
    // Known depths: the page's sfm points and every point made so far.
    std::vector<Eigen::Vector2d> pixels;
    std::vector<double> depths;
    detail::KnownPoints(w.ref.camera, sfm.page_points, r.points, first_new_point, &pixels, &depths);
    detail::AddStepPoints(w.ref, w.others, num_views, w.page, pixels, depths, o.steps, o.outline,
                          &r);
    r.seconds_steps = timer.Mark("steps");
    Log(CountsLine(r.steps, "shading-step points", "step samples", r.seconds_steps));
  }

  if (o.texture.enabled && o.texture.surface_prewarp && matching) {
    detail::AddSurfaceTexturePoints(w.ref, w.others, w.region, points_so_far(), in.reference,
                                    o.texture, &tracks, &r);
  }
  r.seconds_surface = timer.Mark("texture, second pass");
  if (o.texture.surface_prewarp)
    Log(std::to_string(r.texture_points_surface) +
        " texture points more with the other photos brought onto the reference through the "
        "points' surface, " +
        Fixed(r.seconds_surface, 2) + " s");
  if (o.sweep.enabled && matching) {
    detail::AddSweptPoints(w.ref, w.others, w.region, w.page, points_so_far(), in.reference,
                           o.sweep, &r);
    r.seconds_sweep = timer.Mark("sweep");
    Log(std::to_string(r.sweep.points) + " swept points from " +
        std::to_string(r.sweep.candidates) + " candidates, " + Fixed(r.seconds_sweep, 2) + " s");
  }
  r.seconds_total = timer.Total();
  return r;
}

}  // namespace docunfold::densify
