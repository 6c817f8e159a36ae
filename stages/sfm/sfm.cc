#include "stages/sfm/sfm.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <regex>
#include <set>
#include <sstream>

#include "common/atomic_file.h"
#include "common/cli.h"
#include "common/dataset.h"
#include "common/errors.h"
#include "common/ply.h"
#include "stages/sfm/matching.h"
#include "stages/sfm/subprocess.h"

// Camera model and filter: measured on the data sets with ground truth
// (realistic r01-r04, 1600x1200, 4-5 views; COLMAP 3.8, SIFT at full
// resolution). Figures: camera-centre RMS / median distance of the points to
// the true surface, both in % of the page diagonal after a similarity
// alignment of the camera centres; "fail" = wrong focal length (>5x), the
// reconstruction is garbage.
//
//   mapper filter 4 px (COLMAP's default), distortion refined:
//                      r01          r02          r03           r04
//   SIMPLE_PINHOLE   0.11/0.16    0.12/0.69    fail          0.32/0.25
//   PINHOLE          0.11/0.28    0.17/0.08    fail          0.33/0.25
//   SIMPLE_RADIAL    0.11/0.15    0.12/0.75    1.45/2.63     0.39/0.41
//   RADIAL           0.11/0.15    0.14/0.91    (no model)    0.42/0.56
//   (with distortion not refined every *_RADIAL row equals SIMPLE_PINHOLE)
//
//   mapper filter 1 px, distortion refined:
//   SIMPLE_PINHOLE   0.05/0.22    0.11/0.60    fail          0.06/0.02
//   PINHOLE          0.05/0.22    0.12/0.12    fail          0.07/0.03
//   SIMPLE_RADIAL    0.05/0.22    0.12/0.56    0.03/0.22     0.06/0.02
//   RADIAL           0.05/0.22    0.14/0.63    0.02/0.21     0.08/0.13
//
// With the default 4 px filter, wrong matches between the repeated
// characters of a receipt (r03) survive and bend the solution (k = 0.09,
// cameras 1.5 % off); COLMAP then "explains" them with lens distortion.
// The 1 px filter removes them: every focal length comes out within 0.2 %
// of the truth and k stays below 0.004 (r03 with the pinhole models fails
// for another reason: the planar initial pair gives a focal length of
// 15000 px, which the retry catches). RADIAL's second coefficient bends the
// page (r04: 0.13 %), so the default is SIMPLE_RADIAL, distortion refined,
// filter 1 px. The remaining point offset (r02, 0.56 %) is the same in
// every model: with 4 views a tiny common tilt of all cameras (0.06 deg)
// moves the page 2 mm along its normal relative to the camera centres; the
// shape itself is right (0.03 % after fitting the points to the surface).

namespace docunfold::sfm {
namespace {

std::string Fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

std::string JoinNames(const std::vector<std::string>& names, size_t max = 8) {
  std::string s;
  for (size_t i = 0; i < names.size() && i < max; ++i) s += (i ? ", " : "") + names[i];
  if (names.size() > max) s += ", ...";
  return s;
}

// A directory beside the output that becomes the output when Commit() is
// called, and disappears otherwise.
class StagingDir {
 public:
  explicit StagingDir(const fs::path& target) : target_(target) {
    const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
    EnsureDirectory(parent);
    std::random_device rd;
    path_ = parent / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid()) +
                      "-" + std::to_string(rd() % 100000));
    std::error_code ec;
    fs::remove_all(path_, ec);
    fs::create_directories(path_, ec);
    if (ec) throw OutputError(path_.string() + ": cannot create: " + ec.message());
  }
  ~StagingDir() {
    if (committed_) return;
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

  // Replaces the target (an earlier sfm output) with the staging directory.
  void Commit() {
    std::error_code ec;
    fs::path old;
    if (fs::exists(target_, ec)) {
      old = path_;
      old += ".old";
      fs::remove_all(old, ec);
      fs::rename(target_, old, ec);
      if (ec)
        throw OutputError(target_.string() + ": cannot move the old output aside: " + ec.message());
    }
    fs::rename(path_, target_, ec);
    if (ec) {
      std::error_code ignored;
      if (!old.empty()) fs::rename(old, target_, ignored);
      throw OutputError(target_.string() + ": cannot rename into place: " + ec.message());
    }
    committed_ = true;
    if (!old.empty()) fs::remove_all(old, ec);
  }

 private:
  fs::path target_;
  fs::path path_;
  bool committed_ = false;
};

// An existing --out must be a folder sfm wrote (or an empty one): we replace
// it as a whole and must not wipe anything else.
void CheckOutputDir(const fs::path& out) {
  std::error_code ec;
  if (!fs::exists(out, ec)) return;
  if (!fs::is_directory(out, ec))
    throw OutputError(out.string() + ": exists and is not a directory");
  if (fs::is_empty(out, ec)) return;
  for (const char* marker : {"cameras.json", "colmap", "points.ply", "reference.png"})
    if (fs::exists(out / marker, ec)) return;
  throw OutputError(out.string() +
                    ": exists and is not an sfm output folder (no cameras.json or "
                    "colmap/); remove it or choose another --out");
}

struct Colmap {
  fs::path exe;
  const SfmOptions* options;
  fs::path dir;  // colmap/ workspace

  // Runs one COLMAP command, its output into <dir>/<log>; throws when it
  // fails (except for the mapper, whose failure the caller judges).
  SubprocessResult Run(const std::string& command, std::vector<std::string> args,
                       const std::string& log,
                       const std::function<void(const std::string&)>& on_line,
                       bool throw_on_failure = true) const {
    args.insert(args.begin(), {exe.string(), command});
    std::string last;
    SubprocessOptions sub;
    sub.log_file = dir / log;
    sub.timeout_seconds = options->timeout_seconds;
    sub.on_line = [&](const std::string& line) {
      if (options->verbose && !line.empty()) Log("colmap: " + line);
      if (line.find_first_not_of(" =\t") != std::string::npos) last = line;
      if (on_line) on_line(line);
    };
    SubprocessResult r = RunSubprocess(args, sub);
    if (r.not_found) throw std::runtime_error(NotFoundMessage(exe.string()));
    if (throw_on_failure && (r.timed_out || r.exit_code != 0)) {
      std::string why =
          r.timed_out ? "stopped after " + Fixed(options->timeout_seconds, 0) + " s (--timeout)"
          : r.signal  ? "killed by signal " + std::to_string(r.signal)
                      : "exit code " + std::to_string(r.exit_code);
      throw std::runtime_error("COLMAP " + command + " failed (" + why + ")" +
                               (last.empty() ? "" : ": " + last) +
                               "; run with --verbose to see its output");
    }
    return r;
  }

  static std::string NotFoundMessage(const std::string& program) {
    return "COLMAP not found (" + program +
           "): install it with `apt-get install colmap` (Debian/Ubuntu) or "
           "scripts/install-deps.sh, or give its path with --colmap";
  }
};

// Largest model (most registered images, then most points) among
// <dir>/0, <dir>/1, ...
bool ReadBestModel(const fs::path& dir, ColmapModel* best, fs::path* best_dir) {
  bool found = false;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return false;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_directory() || !fs::exists(entry.path() / "points3D.bin")) continue;
    ColmapModel m = ReadColmapModel(entry.path());
    if (!found || m.images.size() > best->images.size() ||
        (m.images.size() == best->images.size() && m.points.size() > best->points.size())) {
      *best = std::move(m);
      *best_dir = entry.path();
      found = true;
    }
  }
  return found;
}

// Ranks attempts: plausible ones first (in the order they were tried, i.e.
// by preference), then by views registered and points.
bool Better(const MapperAttempt& a, const MapperAttempt& b) {
  if (a.produced_model != b.produced_model) return a.produced_model;
  if (a.plausible != b.plausible) return a.plausible;
  if (a.plausible) return false;  // keep the earlier (preferred) one
  if (a.registered != b.registered) return a.registered > b.registered;
  return a.points > b.points;
}

cv::Mat ReadPhoto(const fs::path& path) {
  // COLMAP ignores EXIF orientation; so must we, or reference.png and its K
  // would disagree.
  return cv::imread(path.string(), cv::IMREAD_COLOR | cv::IMREAD_IGNORE_ORIENTATION);
}

}  // namespace

Json SfmOptions::ToJson() const {
  return {{"reference", reference.empty() ? Json(nullptr) : Json(reference)},
          {"max_image_size", max_image_size},
          {"max_num_features", max_num_features},
          {"camera_model", camera_model},
          {"refine_distortion", refine_distortion},
          {"max_reprojection_error", max_reprojection_error},
          {"two_view_tracks", two_view_tracks},
          {"matcher", matcher},
          {"retry", retry},
          {"min_points", min_points},
          {"threads", threads}};
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
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  const double divisor = depths[depths.size() / 2];
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

Json CamerasJson(const SfmResult& r, const SfmOptions& options) {
  Json doc = MakeHeader("docunfold.cameras", 1, "sfm", options.ToJson());
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

SfmResult RunSfm(const SfmOptions& o) {
  const auto start = std::chrono::steady_clock::now();
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
  result.seconds_reading = SecondsSince(start);
  if (!o.reference.empty() &&
      std::find(result.images.begin(), result.images.end(), o.reference) == result.images.end())
    throw InputError("--ref " + o.reference + ": no such photo in " +
                     (o.data_dir / "images").string() + " (there are " + JoinNames(result.images) +
                     ")");
  CheckOutputDir(o.out_dir);

  Colmap colmap;
  colmap.options = &o;
  colmap.exe = FindExecutable(o.colmap);
  if (colmap.exe.empty()) throw std::runtime_error(Colmap::NotFoundMessage(o.colmap));

  StagingDir staging(o.out_dir);
  colmap.dir = staging.path() / "colmap";
  EnsureDirectory(colmap.dir);
  const fs::path database = colmap.dir / "database.db";
  const fs::path image_dir = fs::absolute(o.data_dir / "images");
  {
    std::ofstream list(colmap.dir / "image_list.txt");
    for (const std::string& name : result.images) list << name << "\n";
    if (!list) throw OutputError((colmap.dir / "image_list.txt").string() + ": write failed");
  }
  const std::string threads = std::to_string(o.threads);
  const int long_side = std::max(width, height);
  // Keypoints come back at full resolution: a pixel at matching resolution
  // is this many photo pixels.
  const double matching_scale = double(long_side) / std::min(long_side, o.max_image_size);
  const int n = int(result.images.size());

  // 1. Features.
  {
    const auto t0 = std::chrono::steady_clock::now();
    Progress progress("extracting features", n);
    const std::regex processed(R"(Processed file \[(\d+)/(\d+)\])");
    colmap.Run("feature_extractor",
               {"--database_path", database.string(), "--image_path", image_dir.string(),
                "--image_list_path", (colmap.dir / "image_list.txt").string(),
                "--ImageReader.single_camera", "1", "--ImageReader.camera_model", o.camera_model,
                "--SiftExtraction.use_gpu", "0", "--SiftExtraction.max_image_size",
                std::to_string(o.max_image_size), "--SiftExtraction.max_num_features",
                std::to_string(o.max_num_features), "--SiftExtraction.num_threads", threads},
               "feature_extractor.log", [&](const std::string& line) {
                 std::smatch m;
                 if (std::regex_search(line, m, processed)) progress.Update(std::stol(m[1]));
               });
    progress.Done();
    result.seconds_extracting = SecondsSince(t0);
  }
  // 2. Matches between every pair: exact nearest neighbours (matching.h)
  // verified by COLMAP, or COLMAP's own exhaustive matcher.
  {
    const auto t0 = std::chrono::steady_clock::now();
    const int pairs = n * (n - 1) / 2;
    // matches_importer's list names a pair by its two names split at a space.
    const bool spaced_names = std::any_of(
        result.images.begin(), result.images.end(),
        [](const std::string& name) { return name.find_first_of(" \t") != std::string::npos; });
    const bool exact = o.matcher == "exact" && !spaced_names;
    if (o.matcher == "exact" && spaced_names)
      Log("an image name has a space, which COLMAP's match list cannot carry: COLMAP's "
          "exhaustive matcher is used instead (its matches differ a little between runs)");
    Log("matching features: " + std::to_string(pairs) + " pairs of views (" +
        (exact ? std::string("exact, ") + AutoDotKernelName() : std::string("colmap")) + ")");
    if (exact) {
      NumberImagesByName(database);
      const std::vector<ImageDescriptors> images = ReadDatabaseDescriptors(database);
      const fs::path list_file = colmap.dir / "matches_raw.txt";
      std::ofstream list(list_file);
      Progress progress("matching features", pairs);
      const auto matches = MatchAllPairs(images, MatchCriteria{}, o.threads,
                                         [&](int done) { progress.Update(done); });
      long total = 0, k = 0;
      for (size_t a = 0; a < images.size(); ++a)
        for (size_t b = a + 1; b < images.size(); ++b, ++k) {
          list << images[a].name << ' ' << images[b].name << '\n';
          for (const auto& [i, j] : matches[k]) list << i << ' ' << j << '\n';
          list << '\n';
          total += long(matches[k].size());
        }
      list.close();
      if (!list) throw OutputError(list_file.string() + ": write failed");
      progress.Done();
      Log("matching features: " + std::to_string(total) + " matches before geometric verification");
      colmap.Run("matches_importer",
                 {"--database_path", database.string(), "--match_list_path", list_file.string(),
                  "--match_type", "raw", "--SiftMatching.use_gpu", "0",
                  "--SiftMatching.num_threads", threads},
                 "matches_importer.log", nullptr);
    } else {
      colmap.Run("exhaustive_matcher",
                 {"--database_path", database.string(), "--SiftMatching.use_gpu", "0",
                  "--SiftMatching.num_threads", threads},
                 "exhaustive_matcher.log", nullptr);
    }
    result.seconds_matching = SecondsSince(t0);
  }
  // 3. Incremental mapping; retried with other settings when the result is
  // implausible.
  struct Setting {
    bool refine;
    double filter;  // px at matching resolution
  };
  std::vector<Setting> settings = {{o.refine_distortion, o.max_reprojection_error}};
  if (o.retry) {
    if (model_id >= 2) settings.push_back({!o.refine_distortion, o.max_reprojection_error});
    if (o.max_reprojection_error < 4) settings.push_back({o.refine_distortion, 4.0});
  }
  ColmapModel model;
  int best = -1;
  fs::path best_dir;
  const fs::path attempts_dir = colmap.dir / "attempts";
  const auto t_map = std::chrono::steady_clock::now();
  for (size_t a = 0; a < settings.size(); ++a) {
    const Setting& s = settings[a];
    MapperAttempt attempt;
    attempt.description =
        o.camera_model +
        (model_id >= 2 ? (s.refine ? ", distortion refined" : ", distortion fixed at 0")
                       : std::string()) +
        ", filter " + Fixed(s.filter, 1) + " px";
    const fs::path dir = attempts_dir / std::to_string(a);
    EnsureDirectory(dir);
    Log("mapping (" + attempt.description + ")");
    const std::regex registering(R"(Registering image #\d+ \((\d+)\))");
    long registered_so_far = 2;
    auto last_log = std::chrono::steady_clock::now();
    const SubprocessResult run = colmap.Run(
        "mapper",
        {"--database_path", database.string(), "--image_path", image_dir.string(), "--output_path",
         dir.string(), "--Mapper.num_threads", threads, "--Mapper.ba_refine_extra_params",
         s.refine ? "1" : "0", "--Mapper.filter_max_reproj_error",
         Fixed(s.filter * matching_scale, 3), "--Mapper.tri_ignore_two_view_tracks",
         o.two_view_tracks ? "0" : "1"},
        "mapper.log",
        [&](const std::string& line) {
          std::smatch m;
          if (!std::regex_search(line, m, registering)) return;
          registered_so_far = std::stol(m[1]);
          const auto now = std::chrono::steady_clock::now();
          if (now - last_log < std::chrono::seconds(1)) return;
          last_log = now;
          Log("mapping: " + std::to_string(registered_so_far) + "/" + std::to_string(n) +
              " views registered");
        },
        /*throw_on_failure=*/false);
    attempt.seconds = run.seconds;
    ColmapModel m;
    fs::path m_dir;
    if (ReadBestModel(dir, &m, &m_dir)) {
      attempt.produced_model = true;
      attempt.registered = int(m.images.size());
      attempt.points = int(m.points.size());
      attempt.mean_reprojection_error = m.MeanReprojectionError();
      const ColmapCamera& cam = m.cameras.begin()->second;
      attempt.focal = cam.MeanFocal();
      attempt.params = cam.params;
      const double factor = attempt.focal / long_side;
      std::vector<std::string> problems;
      if (attempt.registered < n)
        problems.push_back(std::to_string(n - attempt.registered) + " of " + std::to_string(n) +
                           " views not registered");
      if (factor < o.min_focal_factor || factor > o.max_focal_factor)
        problems.push_back("implausible focal length " + Fixed(attempt.focal, 0) + " px");
      if (attempt.points < o.min_points)
        problems.push_back("only " + std::to_string(attempt.points) + " points");
      attempt.plausible = problems.empty();
      for (size_t i = 0; i < problems.size(); ++i) attempt.problem += (i ? "; " : "") + problems[i];
    } else {
      attempt.problem = run.timed_out ? "stopped after the time limit"
                                      : "no model (no initial pair of views found)";
    }
    Log("mapping (" + attempt.description + "): " +
        (attempt.produced_model
             ? std::to_string(attempt.registered) + "/" + std::to_string(n) + " views, " +
                   std::to_string(attempt.points) + " points, focal " + Fixed(attempt.focal, 1) +
                   " px, reprojection error " + Fixed(attempt.mean_reprojection_error, 2) + " px"
             : std::string("failed")) +
        (attempt.plausible ? "" : " (" + attempt.problem + ")") + ", " + Fixed(run.seconds, 1) +
        " s");
    result.attempts.push_back(attempt);
    if (attempt.produced_model && (best < 0 || Better(attempt, result.attempts[best]))) {
      best = int(a);
      model = std::move(m);
      best_dir = m_dir;
    }
    if (attempt.plausible) break;
  }
  result.seconds_mapping = SecondsSince(t_map);
  if (best < 0)
    throw InputError("COLMAP could not reconstruct " + (o.data_dir / "images").string() +
                     ": no two of the " + std::to_string(n) +
                     " photos share enough matching features (fewer than 2 views "
                     "registered)");
  // Keep the chosen model as sparse/0 (what `colmap model_analyzer` and the
  // GUI expect), drop the others.
  {
    std::error_code ec;
    fs::create_directories(colmap.dir / "sparse", ec);
    fs::rename(best_dir, colmap.dir / "sparse" / "0", ec);
    if (ec) throw OutputError((colmap.dir / "sparse/0").string() + ": " + ec.message());
    fs::remove_all(attempts_dir, ec);
  }
  if (model.images.size() < 2)
    throw InputError("only " + std::to_string(model.images.size()) + " of " + std::to_string(n) +
                     " views registered; sfm needs at least 2");

  std::set<std::string> registered;
  for (const auto& [id, im] : model.images) registered.insert(im.name);
  for (const std::string& name : result.images)
    if (!registered.count(name)) result.unregistered.push_back(name);
  if (!result.unregistered.empty())
    Log("warning: " + std::to_string(result.unregistered.size()) + " views not registered (" +
        JoinNames(result.unregistered) + "); going on with " + std::to_string(model.images.size()));

  // 4. Reference view.
  std::map<std::string, cv::Mat1b> masks;
  for (size_t i = 0; i < result.images.size(); ++i)
    if (registered.count(result.images[i])) masks[result.images[i]] = RoughPageMask(thumbnails[i]);
  result.view_scores = ScoreReferenceViews(model, masks, o.reference_options);
  {
    const std::vector<bool> page = PagePoints(model, masks);
    result.page_points = int(std::count(page.begin(), page.end(), true));
  }
  if (!o.reference.empty()) {
    if (!registered.count(o.reference))
      throw InputError("--ref " + o.reference +
                       ": COLMAP could not register this view (registered: " +
                       JoinNames({registered.begin(), registered.end()}) + ")");
    result.reference = o.reference;
    result.reference_choice = "--ref";
  } else {
    result.reference = result.view_scores.front().image;
    result.reference_choice = "auto";
  }
  if (int(model.points.size()) < o.min_points)
    throw InputError("only " + std::to_string(model.points.size()) +
                     " 3D points (fewer than --min-points " + std::to_string(o.min_points) +
                     "): the photos share too little texture");

  // 5. The reference frame.
  result.scale_divisor = ToReferenceFrame(model, result.reference, &result.cameras, &result.points);
  const ColmapCamera& camera = model.cameras.begin()->second;
  result.camera_model = CameraModelName(camera.model_id);
  result.colmap_params = camera.params;
  result.distortion = camera.OpenCvDistortion();
  result.mean_reprojection_error = model.MeanReprojectionError();
  for (const ColmapPoint& p : model.points) {
    result.colors.push_back(p.rgb);
    result.track_lengths.push_back(int(p.image_ids.size()));
    result.reprojection_errors.push_back(p.error);
  }

  // 6. Outputs, into the staging directory.
  {
    const fs::path photo = o.data_dir / "images" / result.reference;
    cv::Mat image = ReadPhoto(photo);
    if (image.empty()) throw InputError(photo.string() + ": cannot be decoded as an image");
    if (image.cols != camera.width || image.rows != camera.height)
      throw std::runtime_error(photo.string() + ": " + std::to_string(image.cols) + "x" +
                               std::to_string(image.rows) + " but COLMAP's camera is " +
                               std::to_string(camera.width) + "x" + std::to_string(camera.height));
    image = UndistortPhoto(image, camera);
    WriteImageAtomic(staging.path() / "reference.png", image, {cv::IMWRITE_PNG_COMPRESSION, 1});
  }
  {
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
    WritePly(staging.path() / "points.ply", ply);
  }
  result.seconds_total = SecondsSince(start);
  WriteJsonAtomic(staging.path() / "cameras.json", CamerasJson(result, o));
  staging.Commit();
  result.seconds_total = SecondsSince(start);
  return result;
}

}  // namespace docunfold::sfm
