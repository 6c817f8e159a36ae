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
#include "common/dataset.h"
#include "common/errors.h"
#include "common/option_table.h"
#include "common/photo.h"
#include "common/ply.h"
#include "common/program.h"
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

}  // namespace

void DeclareOptions(OptionTable& table, SfmOptions* o) {
  table.Value("ref", &o->reference,
              "image name of the reference view (e.g. view_02.jpg); empty: automatic");
  table.Value("max-image-size", &o->max_image_size, 100, 100000,
              "long side (px) of the copies of the photos COLMAP works on; cameras.json and "
              "reference.png are at each photo's full resolution");
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
  table.Value("threads", &o->threads, -1, 1024,
              "threads COLMAP's feature extraction and matching may use (its mapper runs on "
              "one, so that a run repeats to the last bit); -1 = all cores");
  table.Value("timeout", &o->timeout_seconds, 1.0, 1e6,
              "seconds each COLMAP command may take before it is stopped");
  table.Value("colmap", &o->colmap, "COLMAP executable (name in PATH or a path)");
  table.Switch("verbose", &o->verbose,
               "echo COLMAP's output on stderr (it always goes to colmap/*.log)");
}

double ToReferenceFrame(const ColmapModel& model, const PhotoSet& photos,
                        const std::string& reference, CameraSet* cameras,
                        std::vector<Eigen::Vector3d>* points) {
  // Each image's camera in its own photo's pixels and frame (photo_set.h).
  struct PhotoView {
    const ColmapImage* image;
    const PhotoCopy* photo;
    PhotoFrame frame;
    Eigen::Matrix3d R;  // photo camera from COLMAP's world
    Eigen::Vector3d t;
  };
  std::vector<PhotoView> views;
  const PhotoView* ref = nullptr;
  for (const auto& [id, im] : model.images) {
    const PhotoCopy* photo = photos.Find(im.name);
    if (!photo) throw std::invalid_argument(im.name + " is not among the photos");
    PhotoView v{&im, photo, ToPhotoFrame(model.cameras.at(im.camera_id), *photo), im.R(), im.t};
    if (photo->turned) {
      v.R = v.frame.Q * v.R;
      v.t = v.frame.Q * v.t;
    }
    views.push_back(v);
  }
  for (const PhotoView& v : views)
    if (v.image->name == reference) ref = &v;
  if (!ref) throw std::invalid_argument(reference + " is not in the model");
  const Eigen::Matrix3d R_ref = ref->R;
  const Eigen::Vector3d t_ref = ref->t;
  std::vector<double> depths;
  for (const ColmapPoint& p : model.points)
    if (std::find(p.image_ids.begin(), p.image_ids.end(), ref->image->id) != p.image_ids.end())
      depths.push_back((R_ref * p.xyz + t_ref).z());
  if (depths.empty())
    throw std::runtime_error("the reference view " + reference + " sees no 3D point");
  const double divisor = Median(std::move(depths));
  if (!(divisor > 0))
    throw std::runtime_error("the points seen by " + reference + " lie behind it (median depth " +
                             std::to_string(divisor) + ")");

  cameras->reference = reference;
  cameras->views.clear();
  for (const PhotoView& v : views) {
    PinholeCamera cam;
    cam.image = v.image->name;
    cam.width = v.photo->width;
    cam.height = v.photo->height;
    cam.K = v.frame.K;
    // x_j = R_j x + t_j and x = R_ref^T (d x' - t_ref), so
    // x_j / d = R_j R_ref^T x' + (t_j - R_j R_ref^T t_ref) / d.
    cam.R = v.R * R_ref.transpose();
    cam.t = (v.t - cam.R * t_ref) / divisor;
    if (&v == ref) {  // exactly, not up to rounding
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

cv::Mat UndistortPhoto(const cv::Mat& photo, const Eigen::Matrix3d& K_photo,
                       const std::array<double, 4>& distortion) {
  if (std::all_of(distortion.begin(), distortion.end(), [](double d) { return d == 0; }))
    return photo.clone();
  // Same K before and after: reference.png keeps the photo's size and pixel
  // grid, and cameras.json's K is exactly its pinhole camera.
  cv::Mat K;
  cv::eigen2cv(K_photo, K);
  const auto& d = distortion;
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
  bool distorted = false;
  for (const auto& [name, d] : r.distortion)
    distorted = distorted || std::any_of(d.begin(), d.end(), [](double k) { return k != 0; });
  doc["views"] = Json::array();
  for (const PinholeCamera& c : r.cameras.views) {
    Json v = CameraToJson(c);
    const auto& d = r.distortion.at(c.image);
    if (distorted && c.image != r.reference)
      v["distortion"] = {{"model", "opencv"}, {"coefficients", {d[0], d[1], d[2], d[3]}}};
    doc["views"].push_back(v);
  }
  doc["reference_undistorted"] = distorted;
  doc["left_out"] = Json::array();
  for (const LeftOut& l : r.photos.left_out)
    doc["left_out"].push_back({{"image", l.name}, {"reason", l.reason}});
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
  Json cameras = Json::array();
  for (const auto& [g, params] : r.colmap_params) {
    const CameraGroup& group = r.photos.groups[size_t(g)];
    Json images = Json::array();
    for (const PhotoCopy& p : r.photos.photos)
      if (p.group == g)
        images.push_back({{"image", p.name},
                          {"copy", p.colmap_name},
                          {"turned", p.turned},
                          {"scale", double(p.copy_width) / (p.turned ? p.height : p.width)}});
    cameras.push_back({{"width", group.copy_width},
                       {"height", group.copy_height},
                       {"params", params},
                       {"exif_camera", group.camera},
                       {"exif_focal_35mm", group.focal_35mm},
                       {"focal_prior_px", group.focal_prior},
                       {"images", images}});
  }
  doc["colmap"] = {{"camera_model", r.camera_model},
                   {"cameras", cameras},
                   {"images", r.photos.photos.size()},
                   {"registered", r.cameras.views.size()},
                   {"unregistered", r.unregistered},
                   {"points", r.points.size()},
                   {"mean_reprojection_error_px", r.mean_reprojection_error},
                   {"scale_divisor", r.scale_divisor},
                   {"mapper_attempts", attempts}};
  doc["colmap"]["not_mapped"] = r.not_mapped;
  doc["colmap"]["other_pages"] = r.other_pages;
  doc["seconds"] = {{"checking_images", r.seconds_reading},
                    {"extracting", r.seconds_extracting},
                    {"matching", r.seconds_matching},
                    {"mapping", r.seconds_mapping},
                    {"total", r.seconds_total}};
  return doc;
}

namespace {

// The names of the views COLMAP registered; the others into
// result->unregistered, with a warning for those the mapper was given.
std::set<std::string> NoteRegistered(const ColmapModel& model, SfmResult* result) {
  std::set<std::string> registered;
  for (const auto& [id, im] : model.images) registered.insert(im.name);
  const std::set<std::string> set_aside(result->not_mapped.begin(), result->not_mapped.end());
  std::vector<std::string> lost;  // given to the mapper, and not registered
  for (const std::string& name : result->photos.Names()) {
    if (registered.count(name)) continue;
    result->unregistered.push_back(name);
    if (!set_aside.count(name)) lost.push_back(name);
  }
  if (!lost.empty())
    Log("warning: " + std::to_string(lost.size()) + " views not registered (" + JoinNames(lost) +
        "); going on with " + std::to_string(model.images.size()));
  return registered;
}

// Scores the registered views on the page's points and picks the reference
// view: --ref's, else the best scored.
void ChooseReference(const ColmapModel& model, const std::set<std::string>& registered,
                     const std::vector<cv::Mat>& thumbnails, const SfmOptions& o,
                     SfmResult* result) {
  std::map<std::string, cv::Mat1b> masks;
  for (size_t i = 0; i < result->photos.photos.size(); ++i) {
    const std::string& name = result->photos.photos[i].name;
    if (registered.count(name)) masks[name] = RoughPageMask(thumbnails[i]);
  }
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
      ToReferenceFrame(model, result->photos, result->reference, &result->cameras, &result->points);
  result->camera_model = CameraModelName(model.cameras.begin()->second.model_id);
  for (const auto& [id, image] : model.images) {
    const ColmapCamera& camera = model.cameras.at(image.camera_id);
    result->distortion[image.name] = camera.OpenCvDistortion();
    result->colmap_params[result->photos.Find(image.name)->group] = camera.params;
  }
  result->mean_reprojection_error = model.MeanReprojectionError();
  for (const ColmapPoint& p : model.points) {
    result->colors.push_back(p.rgb);
    result->track_lengths.push_back(int(p.image_ids.size()));
    result->reprojection_errors.push_back(p.error);
  }
}

// reference.png (the reference photo, upright and undistorted) and
// points.ply into `dir`.
void WritePhotoAndPoints(const SfmResult& result, const SfmOptions& o, const fs::path& dir) {
  {
    const fs::path photo = o.data_dir / "images" / result.reference;
    cv::Mat image = ReadPhoto(photo).image;
    const PinholeCamera& camera = *result.cameras.Find(result.reference);
    if (image.cols != camera.width || image.rows != camera.height)
      throw InputError(photo.string() + ": " + std::to_string(image.cols) + "x" +
                       std::to_string(image.rows) + " now, " + std::to_string(camera.width) + "x" +
                       std::to_string(camera.height) + " when it was read first");
    image = UndistortPhoto(image, camera.K, result.distortion.at(result.reference));
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
                  "COLMAP's mean over the track, pixels of the copies it saw (long side at most "
                  "--max-image-size)",
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
  CheckOutputDir(o.out_dir);
  AtomicDirectory staging(o.out_dir);
  // COLMAP's workspace, colmap/ in the staging directory, with the copies of
  // the photos it works on.
  Colmap colmap;
  colmap.options = &o;
  colmap.dir = staging.path() / "colmap";
  colmap.image_dir = colmap.dir / "images";
  EnsureDirectory(colmap.image_dir);
  std::vector<cv::Mat> thumbnails;
  result.photos = PreparePhotos(o.data_dir, o.max_image_size, colmap.image_dir, &thumbnails);
  const PhotoSet& photos = result.photos;
  result.seconds_reading = timer.Mark("reading photos");
  if (photos.groups.size() > 1)
    Log(std::to_string(photos.groups.size()) +
        " cameras (photos of different sizes or from different phones)");
  if (!o.reference.empty() && !photos.Find(o.reference))
    throw InputError("--ref " + o.reference + ": no such photo in " + photos.dir.string() +
                     " (there are " + JoinNames(photos.Names()) + ")");

  colmap.exe = FindExecutable(o.colmap);
  if (colmap.exe.empty()) throw std::runtime_error(Colmap::NotFoundMessage(o.colmap));
  colmap.database = colmap.dir / "database.db";
  colmap.threads = std::to_string(o.threads);
  timer.Mark("workspace");

  ExtractFeatures(colmap, photos);
  result.seconds_extracting = timer.Mark("extracting");
  MatchFeatures(colmap, photos);
  ChooseLinkedViews(&result.photos, &thumbnails, &colmap);
  if (!o.reference.empty() && !photos.Find(o.reference))  // an edited copy, left out
    for (const LeftOut& l : photos.left_out)
      if (l.name == o.reference)
        throw InputError("--ref " + o.reference + ": left out as " + l.reason +
                         " (give --ref that photo)");
  const int n = int(photos.photos.size());
  if (!colmap.mapped.empty()) {
    const std::set<std::string> mapped(colmap.mapped.begin(), colmap.mapped.end());
    for (const PhotoCopy& p : photos.photos)
      if (!mapped.count(p.colmap_name)) result.not_mapped.push_back(p.name);
    result.other_pages = colmap.other_pages;
  }
  result.seconds_matching = timer.Mark("matching");
  Mapping mapping = MapWithRetries(colmap, photos);
  result.attempts = mapping.attempts;
  result.seconds_mapping = timer.Mark("mapping");
  if (!mapping.found)
    throw InputError("COLMAP could not reconstruct " + photos.dir.string() + ": no two of the " +
                     std::to_string(n) +
                     " photos share enough matching features (fewer than 2 views "
                     "registered)");
  KeepModel(colmap, mapping.model_dir);
  NameByPhotos(photos, &mapping.model);
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
  WritePhotoAndPoints(result, o, staging.path());
  result.seconds_total = timer.Total();
  WriteJsonAtomic(staging.path() / "cameras.json", CamerasJson(result, options_record));
  staging.Commit();
  result.seconds_total = timer.Total();
  return result;
}

}  // namespace docunfold::sfm
