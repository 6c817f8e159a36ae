// The steps of sfm that run COLMAP.
#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <regex>
#include <set>

#include "common/atomic_file.h"
#include "common/errors.h"
#include "common/photo.h"
#include "common/program.h"
#include "stages/sfm/matching.h"
#include "stages/sfm/sfm_internal.h"

namespace docunfold::sfm::detail {

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

SubprocessResult Colmap::Run(const std::string& command, std::vector<std::string> args,
                             const std::string& log,
                             const std::function<void(const std::string&)>& on_line,
                             bool throw_on_failure) const {
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
    std::string why = r.timed_out
                          ? "stopped after " + Fixed(options->timeout_seconds, 0) + " s (--timeout)"
                      : r.signal ? "killed by signal " + std::to_string(r.signal)
                                 : "exit code " + std::to_string(r.exit_code);
    throw std::runtime_error("COLMAP " + command + " failed (" + why + ")" +
                             (last.empty() ? "" : ": " + last) +
                             "; run with --verbose to see its output");
  }
  return r;
}

std::string Colmap::NotFoundMessage(const std::string& program) {
  return "COLMAP not found (" + program +
         "): install it with `apt-get install colmap` (Debian/Ubuntu) or "
         "scripts/install-deps.sh, or give its path with --colmap";
}

namespace {

// COLMAP's --ImageReader.camera_params for a focal length prior `f` on a
// `width` x `height` copy (principal point at the centre, no distortion).
std::string PriorParams(const std::string& model, double f, int width, int height) {
  const std::string fs = Fixed(f, 3), cx = Fixed(width / 2.0, 1), cy = Fixed(height / 2.0, 1);
  if (model == "PINHOLE") return fs + "," + fs + "," + cx + "," + cy;
  if (model == "SIMPLE_RADIAL") return fs + "," + cx + "," + cy + ",0";
  if (model == "RADIAL") return fs + "," + cx + "," + cy + ",0,0";
  return fs + "," + cx + "," + cy;
}

}  // namespace

void ExtractFeatures(const Colmap& colmap, const PhotoSet& photos) {
  const SfmOptions& o = *colmap.options;
  Progress progress("extracting features", long(photos.photos.size()));
  const std::regex processed(R"(Processed file \[(\d+)/(\d+)\])");
  long done_before = 0;
  // One run per camera group: each run with single_camera makes one camera.
  for (size_t g = 0; g < photos.groups.size(); ++g) {
    const CameraGroup& group = photos.groups[g];
    const fs::path list_file = colmap.dir / ("image_list_" + std::to_string(g) + ".txt");
    long in_group = 0;
    {
      std::ofstream list(list_file);
      for (const PhotoCopy& p : photos.photos) {
        if (p.group != int(g)) continue;
        list << p.colmap_name << "\n";
        ++in_group;
      }
      if (!list) throw OutputError(list_file.string() + ": write failed");
    }
    std::vector<std::string> args = {"--database_path",
                                     colmap.database.string(),
                                     "--image_path",
                                     colmap.image_dir.string(),
                                     "--image_list_path",
                                     list_file.string(),
                                     "--ImageReader.single_camera",
                                     "1",
                                     "--ImageReader.camera_model",
                                     o.camera_model,
                                     "--SiftExtraction.use_gpu",
                                     "0",
                                     "--SiftExtraction.max_image_size",
                                     std::to_string(o.max_image_size),
                                     "--SiftExtraction.max_num_features",
                                     std::to_string(o.max_num_features),
                                     "--SiftExtraction.num_threads",
                                     colmap.threads};
    if (group.focal_prior > 0) {
      args.push_back("--ImageReader.camera_params");
      args.push_back(
          PriorParams(o.camera_model, group.focal_prior, group.copy_width, group.copy_height));
    }
    colmap.Run("feature_extractor", args,
               "feature_extractor" + (g ? "_" + std::to_string(g) : std::string()) + ".log",
               [&](const std::string& line) {
                 std::smatch m;
                 if (std::regex_search(line, m, processed))
                   progress.Update(done_before + std::stol(m[1]));
               });
    done_before += in_group;
  }
  progress.Done();
}

namespace {

// Every pair's exact matches (matching.h) into a raw match list, imported by
// COLMAP's matches_importer, which verifies them.
void MatchExactly(const Colmap& colmap, int pairs) {
  NumberImagesByName(colmap.database);
  const std::vector<ImageDescriptors> images = ReadDatabaseDescriptors(colmap.database);
  const fs::path list_file = colmap.dir / "matches_raw.txt";
  std::ofstream list(list_file);
  Progress progress("matching features", pairs);
  const auto matches = MatchAllPairs(images, MatchCriteria{}, colmap.options->threads,
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
             {"--database_path", colmap.database.string(), "--match_list_path", list_file.string(),
              "--match_type", "raw", "--SiftMatching.use_gpu", "0", "--SiftMatching.num_threads",
              colmap.threads},
             "matches_importer.log", nullptr);
}

}  // namespace

void MatchFeatures(const Colmap& colmap, const PhotoSet& photos) {
  const SfmOptions& o = *colmap.options;
  const int n = int(photos.photos.size());
  const int pairs = n * (n - 1) / 2;
  // The copies' names have no spaces, which matches_importer's list could
  // not carry (photo_set.h).
  const bool exact = o.matcher == "exact";
  Log("matching features: " + std::to_string(pairs) + " pairs of views (" +
      (exact ? std::string("exact, ") + AutoDotKernelName() : std::string("colmap")) + ")");
  if (exact) {
    MatchExactly(colmap, pairs);
  } else {
    colmap.Run("exhaustive_matcher",
               {"--database_path", colmap.database.string(), "--SiftMatching.use_gpu", "0",
                "--SiftMatching.num_threads", colmap.threads},
               "exhaustive_matcher.log", nullptr);
  }
}

namespace {

// Of two files of one shot, whether `a` is the one kept: the one with more
// pixels (the crop is the copy), then the shorter name ("IMG_0001 (1)" and
// "..._edited" are copies), then the first by name (iOS's IMG_E0001 after
// IMG_0001).
bool KeptOver(const PhotoCopy& a, const PhotoCopy& b) {
  const long pixels_a = long(a.width) * a.height, pixels_b = long(b.width) * b.height;
  if (pixels_a != pixels_b) return pixels_a > pixels_b;
  if (a.name.size() != b.name.size()) return a.name.size() < b.name.size();
  return a.name < b.name;
}

// Leaves out every photo that is an edited copy of another (a crop, a turn,
// a filter, a scanner app's straightened page) and returns their COLMAP
// names: a copy adds no baseline, and as the reference it would frame the
// page by a crop (a straightened page has no table around it at all).
std::set<std::string> LeaveOutEditedCopies(const Colmap& colmap, PhotoSet* photos,
                                           std::vector<cv::Mat>* thumbnails) {
  // A similarity that takes 90 % of 50 or more verified matches to within
  // 2 px: of the 116 pairs of views of the bench's sets at most 54 % come
  // that close, of a cropped, turned and brightened copy 99 %. A homography
  // that takes 95 % and puts one's whole frame inside the other's: none of
  // the 126 pairs of the bench's sets (21 reach 95 %, up to 98.7 %, but each
  // photo's frame runs past the other's), a page straightened out of one of
  // set01's photos with four of the five (97-99.5 %). A closer photo of a
  // creased page on a granite table came 87 % close, its frame inside: the
  // table's plane fits one homography, the page's parallax does not.
  const SameShotOptions options;
  std::map<std::string, size_t> index;  // COLMAP name -> photo
  for (size_t i = 0; i < photos->photos.size(); ++i) index[photos->photos[i].colmap_name] = i;
  std::set<std::string> copies;
  for (const SameShot& shot : SameShots(colmap.database, options)) {
    if (copies.count(shot.first) || copies.count(shot.second) || !index.count(shot.first) ||
        !index.count(shot.second))
      continue;
    const PhotoCopy& a = photos->photos[index[shot.first]];
    const PhotoCopy& b = photos->photos[index[shot.second]];
    const bool perspective = !shot.copy.empty();
    const bool keep_a = perspective ? shot.copy == b.colmap_name : KeptOver(a, b);
    const PhotoCopy& kept = keep_a ? a : b;
    const PhotoCopy& copy = keep_a ? b : a;
    copies.insert(copy.colmap_name);
    photos->left_out.push_back(
        {copy.name,
         perspective ? "all of it lies within " + kept.name +
                           " (a scanner app's copy of its page, or a close-up from the same spot)"
                     : "the same shot as " + kept.name + ", edited or taken from the same spot"});
    Log("left out: " + copy.name + " (" + photos->left_out.back().reason + ": " +
        std::to_string(int(std::lround(100 * shot.share))) + " % of " +
        std::to_string(shot.matches) + " matches one " +
        (perspective ? "homography" : "similarity") + " apart)");
  }
  for (size_t i = photos->photos.size(); i-- > 0;) {
    if (!copies.count(photos->photos[i].colmap_name)) continue;
    photos->photos.erase(photos->photos.begin() + long(i));
    if (thumbnails && i < thumbnails->size()) thumbnails->erase(thumbnails->begin() + long(i));
  }
  if (photos->photos.size() < 2)
    throw InputError(photos->dir.string() + ": " + std::to_string(photos->photos.size()) +
                     " photo (" + photos->LeftOutSummary() +
                     "); sfm needs at least 2 views of the page");
  return copies;
}

}  // namespace

void ChooseLinkedViews(PhotoSet* photos, std::vector<cv::Mat>* thumbnails, Colmap* colmap) {
  const std::set<std::string> copies = LeaveOutEditedCopies(*colmap, photos, thumbnails);
  // The mapper's own floor (Mapper.min_num_matches): it ignores pairs of
  // views with fewer verified matches, so no model joins views across groups.
  constexpr int kMinVerifiedMatches = 15;
  std::vector<std::vector<std::string>> groups;
  for (std::vector<std::string> group :
       ViewsLinkedByMatches(colmap->database, kMinVerifiedMatches)) {
    group.erase(std::remove_if(group.begin(), group.end(),
                               [&](const std::string& name) { return copies.count(name) > 0; }),
                group.end());
    if (!group.empty()) groups.push_back(std::move(group));
  }
  // Largest first, then the first by name (as ViewsLinkedByMatches, copies left out).
  std::sort(groups.begin(), groups.end(), [](const auto& a, const auto& b) {
    return a.size() != b.size() ? a.size() > b.size() : a.front() < b.front();
  });
  const bool several_pages = groups.size() >= 2 && groups.front().size() >= 2;
  // (not one pair linked: the mapper fails and says so)
  if (!several_pages && (copies.empty() || groups.front().size() < 2)) return;
  std::map<std::string, std::string> photo_of;  // copy's name -> photo's name
  for (const PhotoCopy& p : photos->photos) photo_of[p.colmap_name] = p.name;
  if (several_pages) {
    std::string list;
    for (size_t i = 0; i < groups.size(); ++i)
      list += (i ? "; " : "") + photo_of[groups[i].front()] +
              (groups[i].size() > 1 ? " and " + std::to_string(groups[i].size() - 1) + " more"
                                    : std::string());
    Log("the photos fall into " + std::to_string(groups.size()) +
        " groups with no features in common (a page each, or photos of something else): " + list +
        "; mapping the first (the other groups of two or more are other pages, listed in "
        "cameras.json; pipeline.mk makes each and joins them into one PDF)");
  }
  colmap->mapped = groups.front();
  for (size_t i = 1; i < groups.size(); ++i) {
    if (groups[i].size() < 2) continue;  // a photo of something else
    std::vector<std::string> page;
    for (const std::string& name : groups[i]) page.push_back(photo_of[name]);
    std::sort(page.begin(), page.end());
    colmap->other_pages.push_back(std::move(page));
  }
  std::sort(colmap->other_pages.begin(), colmap->other_pages.end());
  const fs::path list_file = colmap->dir / "mapped_images.txt";
  std::ofstream out(list_file);
  for (const std::string& name : colmap->mapped) out << name << '\n';
  out.close();
  if (!out) throw OutputError(list_file.string() + ": write failed");
}

namespace {

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

struct MapperSetting {
  bool refine;               // distortion refined in bundle adjustment
  double filter;             // px at matching resolution
  bool refine_focal = true;  // false: the focal length stays at its prior
  // Before mapping, cameras without an EXIF prior get a phone's
  // (kPhoneFocal35mm) as theirs.
  bool phone_prior = false;
};

// Two photos of a page may not determine the focal length: the page is
// nearly a plane, and bundle adjustment trades focal length for depth (on
// three two-photo synth pages it ran to 2.0-5.8 times the truth). A phone's
// EXIF focal length is then the better value, and is kept; without EXIF, a
// focal length no phone's main camera has is taken for such a trade, and
// the photos are mapped again with a phone's.
bool KeepExifFocal(const PhotoSet& photos) {
  if (photos.photos.size() != 2) return false;
  for (const PhotoCopy& p : photos.photos)
    if (photos.groups[size_t(p.group)].focal_35mm <= 0) return false;
  return true;
}

// A phone's main camera, 35 mm equivalent (mm), and how far (a factor
// either way) a focal length two photos give may be from it and be believed.
constexpr double kPhoneFocal35mm = 26;
constexpr double kPhoneFocalFactor = 1.4;

std::vector<std::string> Joined(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// Judges the model an attempt made: every view registered, a plausible
// focal length, enough points.
void JudgeModel(const ColmapModel& m, const Colmap& colmap, const PhotoSet& photos,
                const MapperSetting& s, MapperAttempt* attempt) {
  const SfmOptions& o = *colmap.options;
  const int n = int(colmap.mapped.empty() ? photos.photos.size() : colmap.mapped.size());
  attempt->produced_model = true;
  attempt->registered = int(m.images.size());
  attempt->points = int(m.points.size());
  attempt->mean_reprojection_error = m.MeanReprojectionError();
  const ColmapCamera& first = m.cameras.begin()->second;
  attempt->focal = first.MeanFocal();
  attempt->params = first.params;
  std::vector<std::string> problems;
  if (attempt->registered < n)
    problems.push_back(std::to_string(n - attempt->registered) + " of " + std::to_string(n) +
                       " views not registered");
  for (const auto& [id, cam] : m.cameras) {
    const double factor = cam.MeanFocal() / std::max(cam.width, cam.height);
    if (factor < o.min_focal_factor || factor > o.max_focal_factor) {
      problems.push_back("implausible focal length " + Fixed(cam.MeanFocal(), 0) + " px");
      break;
    }
  }
  if (n == 2 && s.refine_focal) {
    for (const auto& [id, cam] : m.cameras) {
      const double ratio =
          cam.MeanFocal() / FocalPixelsFrom35mm(kPhoneFocal35mm, cam.width, cam.height);
      if (ratio > kPhoneFocalFactor || ratio < 1 / kPhoneFocalFactor) {
        problems.push_back("focal length " + Fixed(cam.MeanFocal(), 0) + " px, " +
                           Fixed(ratio * kPhoneFocal35mm, 0) +
                           " mm equivalent: two photos do not fix it");
        break;
      }
    }
  }
  if (attempt->points < o.min_points)
    problems.push_back("only " + std::to_string(attempt->points) + " points");
  attempt->plausible = problems.empty();
  for (size_t i = 0; i < problems.size(); ++i) attempt->problem += (i ? "; " : "") + problems[i];
}

// One run of the mapper with setting `s` into `dir`; the largest model it
// made into *m and *m_dir.
MapperAttempt RunMapper(const Colmap& colmap, const PhotoSet& photos, const MapperSetting& s,
                        const fs::path& dir, ColmapModel* m, fs::path* m_dir) {
  const SfmOptions& o = *colmap.options;
  const int n = int(photos.photos.size());
  const int model_id = CameraModelId(o.camera_model);
  MapperAttempt attempt;
  attempt.description =
      o.camera_model +
      (model_id >= 2 ? (s.refine ? ", distortion refined" : ", distortion fixed at 0")
                     : std::string()) +
      ", filter " + Fixed(s.filter, 1) + " px" +
      (s.refine_focal ? std::string()
       : s.phone_prior
           ? ", focal length fixed (EXIF's, else a phone's " + Fixed(kPhoneFocal35mm, 0) + " mm)"
           : ", focal length fixed at EXIF's");
  if (s.phone_prior) SetMissingFocalPriors(colmap.database, kPhoneFocal35mm);
  EnsureDirectory(dir);
  Log("mapping (" + attempt.description + ")");
  const std::regex registering(R"(Registering image #\d+ \((\d+)\))");
  long registered_so_far = 2;
  auto last_log = std::chrono::steady_clock::now();
  // (From photos it cannot join to its first model the mapper builds one
  // model per initial pair and drops each below 10 views: 10 minutes on two
  // pages' photos. It is given only the views that can join; further models
  // stay allowed, for set01's first is a poor one.)
  std::vector<std::string> image_list;
  if (!colmap.mapped.empty())
    image_list = {"--image_list_path", (colmap.dir / "mapped_images.txt").string()};
  // The mapper runs on one thread: on more, its bundle adjustment sums in a
  // different order on each run, the cameras differ in their last bits, and
  // some pages' results follow them. On 4-6 photos one thread is faster too.
  const SubprocessResult run = colmap.Run(
      "mapper",
      Joined({"--database_path", colmap.database.string(), "--image_path",
              colmap.image_dir.string(), "--output_path", dir.string(), "--Mapper.num_threads", "1",
              "--Mapper.ba_refine_extra_params", s.refine ? "1" : "0",
              "--Mapper.ba_refine_focal_length", s.refine_focal ? "1" : "0",
              "--Mapper.filter_max_reproj_error", Fixed(s.filter, 3),
              "--Mapper.tri_ignore_two_view_tracks", o.two_view_tracks ? "0" : "1"},
             image_list),
      "mapper.log",
      [&](const std::string& line) {
        std::smatch match;
        if (!std::regex_search(line, match, registering)) return;
        registered_so_far = std::stol(match[1]);
        const auto now = std::chrono::steady_clock::now();
        if (now - last_log < std::chrono::seconds(1)) return;
        last_log = now;
        Log("mapping: " + std::to_string(registered_so_far) + "/" + std::to_string(n) +
            " views registered");
      },
      /*throw_on_failure=*/false);
  attempt.seconds = run.seconds;
  if (ReadBestModel(dir, m, m_dir)) {
    JudgeModel(*m, colmap, photos, s, &attempt);
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
  return attempt;
}

}  // namespace

Mapping MapWithRetries(const Colmap& colmap, const PhotoSet& photos) {
  const SfmOptions& o = *colmap.options;
  const int model_id = CameraModelId(o.camera_model);
  std::vector<MapperSetting> settings = {{o.refine_distortion, o.max_reprojection_error}};
  if (KeepExifFocal(photos)) {
    // Distortion too stays at 0: phones correct it in the camera, and with
    // the focal length fixed it is the one parameter left to trade (refined,
    // it cost those pages 0.09-0.38 MS-SSIM).
    Log("two photos: the focal length is kept at EXIF's, not refined");
    settings = {{false, o.max_reprojection_error, false}};
    if (o.retry && o.max_reprojection_error < 4) settings.push_back({false, 4.0, false});
  } else if (o.retry && photos.photos.size() == 2) {
    settings.push_back({false, o.max_reprojection_error, false, true});
    if (o.max_reprojection_error < 4) settings.push_back({false, 4.0, false, true});
  } else if (o.retry) {
    if (model_id >= 2) settings.push_back({!o.refine_distortion, o.max_reprojection_error});
    if (o.max_reprojection_error < 4) settings.push_back({o.refine_distortion, 4.0});
  }
  Mapping mapping;
  int best = -1;
  for (size_t a = 0; a < settings.size(); ++a) {
    ColmapModel m;
    fs::path m_dir;
    const MapperAttempt attempt = RunMapper(
        colmap, photos, settings[a], colmap.dir / "attempts" / std::to_string(a), &m, &m_dir);
    mapping.attempts.push_back(attempt);
    if (attempt.produced_model && (best < 0 || Better(attempt, mapping.attempts[best]))) {
      best = int(a);
      mapping.model = std::move(m);
      mapping.model_dir = m_dir;
    }
    if (attempt.plausible) break;
  }
  mapping.found = best >= 0;
  return mapping;
}

void KeepModel(const Colmap& colmap, const fs::path& model_dir) {
  std::error_code ec;
  fs::create_directories(colmap.dir / "sparse", ec);
  fs::rename(model_dir, colmap.dir / "sparse" / "0", ec);
  if (ec) throw OutputError((colmap.dir / "sparse/0").string() + ": " + ec.message());
  fs::remove_all(colmap.dir / "attempts", ec);
}

}  // namespace docunfold::sfm::detail
