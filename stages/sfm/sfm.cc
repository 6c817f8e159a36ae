#include "stages/sfm/sfm.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "common/atomic_file.h"
#include "common/cli.h"
#include "common/dataset.h"
#include "common/errors.h"
#include "common/ply.h"
#include "common/statistics.h"
#include "stages/sfm/sfm_internal.h"

namespace docunfold::sfm {

using namespace detail;

namespace {

// "a, b, c" of at most `max` names, then ", ...".
std::string JoinNames(const std::vector<std::string>& names, size_t max = 8) {
  std::string s;
  for (size_t i = 0; i < names.size() && i < max; ++i) s += (i ? ", " : "") + names[i];
  if (names.size() > max) s += ", ...";
  return s;
}

cv::Mat ReadPhoto(const fs::path& path) {
  // COLMAP ignores EXIF orientation; so must we, or reference.png and its K
  // would disagree.
  return cv::imread(path.string(), cv::IMREAD_COLOR | cv::IMREAD_IGNORE_ORIENTATION);
}

}  // namespace

void DeclareOptions(OptionTable& table, SfmOptions* o) {
  table.Value("ref", &o->reference,
              "image name of the reference view (e.g. view_02.jpg); empty: automatic");
  table.Value("max-image-size", &o->max_image_size, 100, 100000,
              "long side (px) of the copies features are found on; keypoints and "
              "reference.png stay at full resolution");
  table.Value("max-features", &o->max_num_features, 100, 1000000, "SIFT features per image");
  table.Choice<std::string>("camera-model", &o->camera_model,
                            {{"SIMPLE_PINHOLE", "SIMPLE_PINHOLE"},
                             {"PINHOLE", "PINHOLE"},
                             {"SIMPLE_RADIAL", "SIMPLE_RADIAL"},
                             {"RADIAL", "RADIAL"}},
                            "COLMAP camera model shared by all photos");
  table.Switch("refine-distortion", &o->refine_distortion,
               "refine the radial distortion in bundle adjustment (off keeps it at 0)");
  table.Value("max-reprojection-error", &o->max_reprojection_error, 0.1, 100.0,
              "the mapper drops observations farther than this from their point "
              "(px at matching resolution; COLMAP's own default is 4)");
  table.Switch("two-view-tracks", &o->two_view_tracks,
               "also triangulate points only two views see (COLMAP's own default is off)");
  table.Choice<std::string>("matcher", &o->matcher, {{"exact", "exact"}, {"colmap", "colmap"}},
                            "exact: brute-force SIFT matching under COLMAP's criteria, verified "
                            "by COLMAP (the same photos give the same result on every run); "
                            "colmap: COLMAP's exhaustive_matcher (FLANN: a few matches differ "
                            "between runs)");
  table.Switch("retry", &o->retry,
               "retry the mapper with other settings when its result is implausible (views "
               "missing, focal length off, too few points)");
  table.Value("min-points", &o->min_points, 0, 100000000,
              "fewer 3D points than this is an error (exit 3)");
  table.Value("threads", &o->threads, -1, 1024, "threads COLMAP may use; -1 = all cores");
  table.Value("timeout", &o->timeout_seconds, 1.0, 1e6,
              "seconds each COLMAP command may take before it is stopped");
  table.Value("colmap", &o->colmap, "COLMAP executable (name in PATH or a path)");
  table.Switch("verbose", &o->verbose,
               "echo COLMAP's output on stderr (it always goes to colmap/*.log)");
}

std::vector<std::string> CheckImages(const fs::path& data_dir, int* width, int* height,
                                     std::vector<cv::Mat>* thumbnails) {
  const DataSet set = OpenDataSet(data_dir);
  const fs::path images_dir = data_dir / "images";
  if (set.images.size() < 2)
    throw InputError(images_dir.string() + ": " + std::to_string(set.images.size()) + " photo" +
                     (set.images.size() == 1 ? "" : "s") +
                     " (jpg, png or tif); sfm needs at least 2 views of the page");
  std::vector<std::string> names;
  Progress progress("checking images", long(set.images.size()));
  for (size_t i = 0; i < set.images.size(); ++i) {
    const fs::path& path = set.images[i];
    const cv::Mat image = ReadPhoto(path);
    if (image.empty()) throw InputError(path.string() + ": cannot be decoded as an image");
    if (i == 0) {
      *width = image.cols;
      *height = image.rows;
    } else if (image.cols != *width || image.rows != *height) {
      throw InputError(path.string() + ": " + std::to_string(image.cols) + "x" +
                       std::to_string(image.rows) + ", but " + set.images[0].filename().string() +
                       " is " + std::to_string(*width) + "x" + std::to_string(*height) +
                       "; all photos must come from one camera at one size");
    }
    names.push_back(path.filename().string());
    if (thumbnails) {
      const double f = std::min(1.0, 640.0 / std::max(image.cols, image.rows));
      cv::Mat small;
      cv::resize(image, small, cv::Size(), f, f, cv::INTER_AREA);
      thumbnails->push_back(small);
    }
    progress.Update(long(i + 1));
  }
  return names;
}

double ToReferenceFrame(const ColmapModel& model, const std::string& reference, CameraSet* cameras,
                        std::vector<Eigen::Vector3d>* points) {
  const ColmapImage* ref = nullptr;
  for (const auto& [id, im] : model.images)
    if (im.name == reference) ref = &im;
  if (!ref) throw std::invalid_argument(reference + " is not in the model");
  const Eigen::Matrix3d R_ref = ref->R();
  const Eigen::Vector3d t_ref = ref->t;
  std::vector<double> depths;
  for (const ColmapPoint& p : model.points)
    if (std::find(p.image_ids.begin(), p.image_ids.end(), ref->id) != p.image_ids.end())
      depths.push_back((R_ref * p.xyz + t_ref).z());
  if (depths.empty())
    throw std::runtime_error("the reference view " + reference + " sees no 3D point");
  const double divisor = Median(std::move(depths));
  if (!(divisor > 0))
    throw std::runtime_error("the points seen by " + reference + " lie behind it (median depth " +
                             std::to_string(divisor) + ")");

  cameras->reference = reference;
  cameras->views.clear();
  for (const auto& [id, im] : model.images) {
    const ColmapCamera& c = model.cameras.at(im.camera_id);
    PinholeCamera cam;
    cam.image = im.name;
    cam.width = c.width;
    cam.height = c.height;
    cam.K = c.PinholeK();
    // x_j = R_j x + t_j and x = R_ref^T (d x' - t_ref), so
    // x_j / d = R_j R_ref^T x' + (t_j - R_j R_ref^T t_ref) / d.
    cam.R = im.R() * R_ref.transpose();
    cam.t = (im.t - cam.R * t_ref) / divisor;
    if (im.id == ref->id) {  // exactly, not up to rounding
      cam.R.setIdentity();
      cam.t.setZero();
    }
    cameras->views.push_back(cam);
  }
  std::sort(cameras->views.begin(), cameras->views.end(),
            [](const PinholeCamera& a, const PinholeCamera& b) { return a.image < b.image; });
  points->clear();
  points->reserve(model.points.size());
  for (const ColmapPoint& p : model.points) points->push_back((R_ref * p.xyz + t_ref) / divisor);
  return divisor;
}

cv::Mat UndistortPhoto(const cv::Mat& photo, const ColmapCamera& camera) {
  if (!camera.HasDistortion()) return photo.clone();
  // Same K before and after: reference.png keeps the photo's size and pixel
  // grid, and cameras.json's K is exactly its pinhole camera.
  cv::Mat K;
  cv::eigen2cv(Eigen::Matrix3d(camera.PinholeK()), K);
  const auto d = camera.OpenCvDistortion();
  const cv::Mat dist = (cv::Mat_<double>(1, 4) << d[0], d[1], d[2], d[3]);
  cv::Mat map1, map2;
  cv::initUndistortRectifyMap(K, dist, cv::Mat(), K, photo.size(), CV_32FC1, map1, map2);
  cv::Mat out;
  // Where the map reaches past the photo (its last row and column, even for
  // a slight distortion), repeat the photo's edge: black there made a dark
  // frame that joined letters cut by the border to the table in
  // segment-boundary (set08: notches taken for page edge).
  cv::remap(photo, out, map1, map2, cv::INTER_CUBIC, cv::BORDER_REPLICATE);
  return out;
}

Json CamerasJson(const SfmResult& r, const Json& options_record) {
  Json doc = MakeHeader("docunfold.cameras", 1, "sfm", options_record);
  doc["reference"] = r.reference;
  doc["frame"] =
      "camera frame of the reference view (x right, y down, z forward), scaled so "
      "that the median depth of the points it sees is 1; x_cam = R x_world + t";
  const bool distorted =
      std::any_of(r.distortion.begin(), r.distortion.end(), [](double d) { return d != 0; });
  doc["views"] = Json::array();
  for (const PinholeCamera& c : r.cameras.views) {
    Json v = CameraToJson(c);
    if (distorted && c.image != r.reference)
      v["distortion"] = {
          {"model", "opencv"},
          {"coefficients", {r.distortion[0], r.distortion[1], r.distortion[2], r.distortion[3]}}};
    doc["views"].push_back(v);
  }
  doc["reference_undistorted"] = distorted;
  Json scores = Json::array();
  for (const ViewScore& s : r.view_scores)
    scores.push_back({{"image", s.image},
                      {"score", s.score},
                      {"coverage", s.coverage},
                      {"frontality", s.frontality},
                      {"page_pixels", s.page_pixels},
                      {"resolution", s.resolution},
                      {"hidden", s.hidden},
                      {"points_seen", s.points_seen}});
  doc["reference_selection"] = {
      {"method", r.reference_choice}, {"page_points", r.page_points}, {"views", scores}};
  Json attempts = Json::array();
  for (const MapperAttempt& a : r.attempts)
    attempts.push_back({{"setting", a.description},
                        {"registered", a.registered},
                        {"points", a.points},
                        {"mean_reprojection_error_px", a.mean_reprojection_error},
                        {"focal_px", a.focal},
                        {"plausible", a.plausible},
                        {"problem", a.problem},
                        {"seconds", a.seconds}});
  doc["colmap"] = {{"camera_model", r.camera_model},
                   {"params", r.colmap_params},
                   {"images", r.images.size()},
                   {"registered", r.cameras.views.size()},
                   {"unregistered", r.unregistered},
                   {"points", r.points.size()},
                   {"mean_reprojection_error_px", r.mean_reprojection_error},
                   {"scale_divisor", r.scale_divisor},
                   {"mapper_attempts", attempts}};
  doc["seconds"] = {{"checking_images", r.seconds_reading},
                    {"extracting", r.seconds_extracting},
                    {"matching", r.seconds_matching},
                    {"mapping", r.seconds_mapping},
                    {"total", r.seconds_total}};
  return doc;
}

namespace {

// The names of the views COLMAP registered; the others into
// result->unregistered, with a warning.
std::set<std::string> NoteRegistered(const ColmapModel& model, SfmResult* result) {
  std::set<std::string> registered;
  for (const auto& [id, im] : model.images) registered.insert(im.name);
  for (const std::string& name : result->images)
    if (!registered.count(name)) result->unregistered.push_back(name);
  if (!result->unregistered.empty())
    Log("warning: " + std::to_string(result->unregistered.size()) + " views not registered (" +
        JoinNames(result->unregistered) + "); going on with " +
        std::to_string(model.images.size()));
  return registered;
}

// Scores the registered views on the page's points and picks the reference
// view: --ref's, else the best scored.
void ChooseReference(const ColmapModel& model, const std::set<std::string>& registered,
                     const std::vector<cv::Mat>& thumbnails, const SfmOptions& o,
                     SfmResult* result) {
  std::map<std::string, cv::Mat1b> masks;
  for (size_t i = 0; i < result->images.size(); ++i)
    if (registered.count(result->images[i]))
      masks[result->images[i]] = RoughPageMask(thumbnails[i]);
  result->view_scores = ScoreReferenceViews(model, masks, o.reference_options);
  {
    const std::vector<bool> page = PagePoints(model, masks);
    result->page_points = int(std::count(page.begin(), page.end(), true));
  }
  if (!o.reference.empty()) {
    if (!registered.count(o.reference))
      throw InputError("--ref " + o.reference +
                       ": COLMAP could not register this view (registered: " +
                       JoinNames({registered.begin(), registered.end()}) + ")");
    result->reference = o.reference;
    result->reference_choice = "--ref";
  } else {
    result->reference = result->view_scores.front().image;
    result->reference_choice = "auto";
  }
}

// The cameras and points of `model` in the reference view's frame.
void ToResult(const ColmapModel& model, SfmResult* result) {
  result->scale_divisor =
      ToReferenceFrame(model, result->reference, &result->cameras, &result->points);
  const ColmapCamera& camera = model.cameras.begin()->second;
  result->camera_model = CameraModelName(camera.model_id);
  result->colmap_params = camera.params;
  result->distortion = camera.OpenCvDistortion();
  result->mean_reprojection_error = model.MeanReprojectionError();
  for (const ColmapPoint& p : model.points) {
    result->colors.push_back(p.rgb);
    result->track_lengths.push_back(int(p.image_ids.size()));
    result->reprojection_errors.push_back(p.error);
  }
}

// reference.png (the reference photo undistorted by `camera`) and
// points.ply into `dir`.
void WritePhotoAndPoints(const SfmResult& result, const ColmapCamera& camera, const SfmOptions& o,
                         const fs::path& dir) {
  {
    const fs::path photo = o.data_dir / "images" / result.reference;
    cv::Mat image = ReadPhoto(photo);
    if (image.empty()) throw InputError(photo.string() + ": cannot be decoded as an image");
    if (image.cols != camera.width || image.rows != camera.height)
      throw std::runtime_error(photo.string() + ": " + std::to_string(image.cols) + "x" +
                               std::to_string(image.rows) + " but COLMAP's camera is " +
                               std::to_string(camera.width) + "x" + std::to_string(camera.height));
    image = UndistortPhoto(image, camera);
    WriteImageAtomic(dir / "reference.png", image, {cv::IMWRITE_PNG_COMPRESSION, 1});
  }
  PlyData ply;
  ply.vertices = result.points;
  ply.colors = result.colors;
  ply.SetProperty("track_length",
                  std::vector<double>(result.track_lengths.begin(), result.track_lengths.end()),
                  PlyScalar::kUint32);
  ply.SetProperty("reprojection_error", result.reprojection_errors);
  ply.comments = {"docunfold sfm: sparse point cloud of the page (and what else COLMAP matched)",
                  "frame: camera of the reference view " + result.reference +
                      " (x right, y down, z forward), scaled so the median depth of the points "
                      "it sees is 1",
                  "track_length: number of views observing the point; reprojection_error: "
                  "COLMAP's mean over the track, pixels of the photos",
                  "camera model " + result.camera_model + "; cameras in cameras.json"};
  WritePly(dir / "points.ply", ply);
}

}  // namespace

SfmResult RunSfm(const SfmOptions& o, const Json& options_record) {
  StepTimer timer;
  const int model_id = CameraModelId(o.camera_model);
  if (model_id < 0)
    throw UsageError("--camera-model " + o.camera_model +
                     ": expected SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL or RADIAL");
  if (o.max_image_size < 100) throw UsageError("--max-image-size must be >= 100");
  if (!(o.max_reprojection_error > 0))
    throw UsageError("--max-reprojection-error must be positive");

  SfmResult result;
  int width = 0, height = 0;
  std::vector<cv::Mat> thumbnails;
  result.images = CheckImages(o.data_dir, &width, &height, &thumbnails);
  result.seconds_reading = timer.Mark("checking images");
  if (!o.reference.empty() &&
      std::find(result.images.begin(), result.images.end(), o.reference) == result.images.end())
    throw InputError("--ref " + o.reference + ": no such photo in " +
                     (o.data_dir / "images").string() + " (there are " + JoinNames(result.images) +
                     ")");
  CheckOutputDir(o.out_dir);

  // COLMAP's workspace, colmap/ in the staging directory.
  Colmap colmap;
  colmap.options = &o;
  colmap.exe = FindExecutable(o.colmap);
  if (colmap.exe.empty()) throw std::runtime_error(Colmap::NotFoundMessage(o.colmap));
  StagingDir staging(o.out_dir);
  colmap.dir = staging.path() / "colmap";
  EnsureDirectory(colmap.dir);
  colmap.database = colmap.dir / "database.db";
  colmap.image_dir = fs::absolute(o.data_dir / "images");
  colmap.threads = std::to_string(o.threads);
  {
    std::ofstream list(colmap.dir / "image_list.txt");
    for (const std::string& name : result.images) list << name << "\n";
    if (!list) throw OutputError((colmap.dir / "image_list.txt").string() + ": write failed");
  }
  Photos photos;
  photos.names = result.images;
  photos.long_side = std::max(width, height);
  photos.matching_scale = double(photos.long_side) / std::min(photos.long_side, o.max_image_size);
  const int n = int(result.images.size());
  timer.Mark("workspace");

  ExtractFeatures(colmap, photos);
  result.seconds_extracting = timer.Mark("extracting");
  MatchFeatures(colmap, photos);
  result.seconds_matching = timer.Mark("matching");
  Mapping mapping = MapWithRetries(colmap, photos);
  result.attempts = mapping.attempts;
  result.seconds_mapping = timer.Mark("mapping");
  if (!mapping.found)
    throw InputError("COLMAP could not reconstruct " + (o.data_dir / "images").string() +
                     ": no two of the " + std::to_string(n) +
                     " photos share enough matching features (fewer than 2 views "
                     "registered)");
  KeepModel(colmap, mapping.model_dir);
  const ColmapModel& model = mapping.model;
  if (model.images.size() < 2)
    throw InputError("only " + std::to_string(model.images.size()) + " of " + std::to_string(n) +
                     " views registered; sfm needs at least 2");

  const std::set<std::string> registered = NoteRegistered(model, &result);
  ChooseReference(model, registered, thumbnails, o, &result);
  if (int(model.points.size()) < o.min_points)
    throw InputError("only " + std::to_string(model.points.size()) +
                     " 3D points (fewer than --min-points " + std::to_string(o.min_points) +
                     "): the photos share too little texture");
  ToResult(model, &result);

  // Outputs, into the staging directory, which then replaces --out.
  WritePhotoAndPoints(result, model.cameras.begin()->second, o, staging.path());
  result.seconds_total = timer.Total();
  WriteJsonAtomic(staging.path() / "cameras.json", CamerasJson(result, options_record));
  staging.Commit();
  result.seconds_total = timer.Total();
  return result;
}

}  // namespace docunfold::sfm
