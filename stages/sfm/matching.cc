#include "stages/sfm/matching.h"

#include <sqlite3.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/calib3d.hpp>
#include <stdexcept>
#include <thread>

#include "common/photo.h"
#include "stages/sfm/descriptor_dots.h"

namespace docunfold::sfm {
namespace {

// Best and second-best dot product of one descriptor with the other set.
struct Nearest {
  float best = -std::numeric_limits<float>::infinity();
  float second = -std::numeric_limits<float>::infinity();
  int index = -1;
  void Offer(float dot, int i) {
    if (dot > best) {
      second = best;
      best = dot;
      index = i;
    } else if (dot > second) {
      second = dot;
    }
  }
};

// Rows are normalised to 512, so dot / 512^2 is the cosine of the angle.
double Angle(float dot) {
  constexpr double kNorm = 1.0 / (512.0 * 512.0);
  return std::acos(std::clamp(double(dot) * kNorm, -1.0, 1.0));
}

// The one-way matches that pass the distance and ratio tests; -1 elsewhere.
std::vector<int> OneWay(const std::vector<Nearest>& nearest, const MatchCriteria& c) {
  std::vector<int> match(nearest.size(), -1);
  for (size_t i = 0; i < nearest.size(); ++i) {
    const Nearest& n = nearest[i];
    if (n.index < 0) continue;
    const double best = Angle(n.best);
    if (best > c.max_distance) continue;
    const double second =
        std::isfinite(n.second) ? Angle(n.second) : std::numeric_limits<double>::infinity();
    if (best >= c.max_ratio * second) continue;
    match[i] = n.index;
  }
  return match;
}

using Database = std::unique_ptr<sqlite3, int (*)(sqlite3*)>;

Database OpenDatabase(const fs::path& database, int flags) {
  sqlite3* raw = nullptr;
  if (sqlite3_open_v2(database.c_str(), &raw, flags, nullptr) != SQLITE_OK) {
    const std::string why = raw ? sqlite3_errmsg(raw) : "cannot open";
    sqlite3_close(raw);
    throw std::runtime_error(database.string() + ": " + why);
  }
  return Database(raw, sqlite3_close);
}

using Statement = std::unique_ptr<sqlite3_stmt, int (*)(sqlite3_stmt*)>;

// `sql` compiled for `db`; throws naming `database` when it does not compile.
Statement Prepare(const Database& db, const fs::path& database, const char* sql) {
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(db.get(), sql, -1, &raw, nullptr) != SQLITE_OK)
    throw std::runtime_error(database.string() + ": " + sqlite3_errmsg(db.get()));
  return Statement(raw, sqlite3_finalize);
}

// The two image ids of a COLMAP pair id: id1 * 2147483647 + id2 (id1 < id2).
std::pair<long, long> ImagesOfPair(long pair_id) {
  constexpr long kPairBase = 2147483647;
  return {pair_id / kPairBase, pair_id % kPairBase};
}

}  // namespace

void NumberImagesByName(const fs::path& database) {
  const Database db = OpenDatabase(database, SQLITE_OPEN_READWRITE);
  std::vector<int> old_ids;
  {
    const Statement stmt = Prepare(db, database, "SELECT image_id FROM images ORDER BY name");
    while (sqlite3_step(stmt.get()) == SQLITE_ROW)
      old_ids.push_back(sqlite3_column_int(stmt.get(), 0));
  }
  // Moved out of the way first, so that no id is ever taken twice.
  constexpr long kOffset = 1000000;
  std::string sql = "BEGIN;";
  for (const char* table : {"images", "keypoints", "descriptors"}) {
    sql += std::string("UPDATE ") + table + " SET image_id = image_id + " +
           std::to_string(kOffset) + ";";
    for (size_t k = 0; k < old_ids.size(); ++k)
      sql += std::string("UPDATE ") + table + " SET image_id = " + std::to_string(k + 1) +
             " WHERE image_id = " + std::to_string(old_ids[k] + kOffset) + ";";
  }
  sql += "COMMIT;";
  char* error = nullptr;
  if (sqlite3_exec(db.get(), sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
    const std::string why = error ? error : "failed";
    sqlite3_free(error);
    throw std::runtime_error(database.string() + ": renumbering the images: " + why);
  }
}

std::vector<std::vector<std::string>> ViewsLinkedByMatches(const fs::path& database,
                                                           int min_inliers) {
  const Database db = OpenDatabase(database, SQLITE_OPEN_READONLY);
  std::map<long, std::string> names;
  {
    const Statement stmt = Prepare(db, database, "SELECT image_id, name FROM images");
    while (sqlite3_step(stmt.get()) == SQLITE_ROW)
      names[sqlite3_column_int64(stmt.get(), 0)] =
          reinterpret_cast<const char*>(sqlite3_column_text(stmt.get(), 1));
  }
  std::map<long, long> parent;  // union-find over image ids
  for (const auto& [id, name] : names) parent[id] = id;
  auto root = [&](long id) {
    while (parent[id] != id) id = parent[id] = parent[parent[id]];
    return id;
  };
  {
    // Config 2 and up is a verified geometry (0 undefined, 1 degenerate).
    const Statement stmt = Prepare(
        db, database, "SELECT pair_id FROM two_view_geometries WHERE config >= 2 AND rows >= ?");
    sqlite3_bind_int(stmt.get(), 1, min_inliers);
    while (sqlite3_step(stmt.get()) == SQLITE_ROW) {
      const long pair = sqlite3_column_int64(stmt.get(), 0);
      const auto [a, b] = ImagesOfPair(pair);
      if (parent.count(a) && parent.count(b)) parent[root(a)] = root(b);
    }
  }
  std::map<long, std::vector<std::string>> by_root;
  for (const auto& [id, name] : names) by_root[root(id)].push_back(name);
  std::vector<std::vector<std::string>> groups;
  for (auto& [id, group] : by_root) {
    std::sort(group.begin(), group.end());
    groups.push_back(std::move(group));
  }
  std::sort(groups.begin(), groups.end(), [](const auto& a, const auto& b) {
    return a.size() != b.size() ? a.size() > b.size() : a.front() < b.front();
  });
  return groups;
}

namespace {

// Whether `map` takes all four corners of a `from` frame inside a `to` frame
// (to within `margin` of its size).
bool FrameInside(const cv::Mat& map, const cv::Size& from, const cv::Size& to, double margin) {
  if (map.empty() || from.area() <= 0 || to.area() <= 0) return false;
  const std::vector<cv::Point2f> corners = {{0, 0},
                                            {float(from.width), 0},
                                            {float(from.width), float(from.height)},
                                            {0, float(from.height)}};
  std::vector<cv::Point2f> mapped;
  cv::perspectiveTransform(corners, mapped, map);
  const double mx = margin * to.width, my = margin * to.height;
  return std::all_of(mapped.begin(), mapped.end(), [&](const cv::Point2f& p) {
    return std::isfinite(p.x) && std::isfinite(p.y) && p.x >= -mx && p.y >= -my &&
           p.x <= to.width + mx && p.y <= to.height + my;
  });
}

}  // namespace

std::vector<SameShot> SameShots(const fs::path& database, const SameShotOptions& options) {
  const Database db = OpenDatabase(database, SQLITE_OPEN_READONLY);
  std::map<long, std::string> names;
  std::map<long, std::vector<cv::Point2f>> keypoints;  // x, y of each, in the copy's pixels
  std::map<long, cv::Size> frames;                     // each copy's size (0 x 0 unknown)
  {
    const Statement stmt = Prepare(
        db, database,
        "SELECT images.image_id, images.name, keypoints.rows, keypoints.cols, keypoints.data, "
        "cameras.width, cameras.height FROM images JOIN keypoints ON images.image_id = "
        "keypoints.image_id LEFT JOIN cameras ON images.camera_id = cameras.camera_id");
    while (sqlite3_step(stmt.get()) == SQLITE_ROW) {
      const long id = sqlite3_column_int64(stmt.get(), 0);
      names[id] = reinterpret_cast<const char*>(sqlite3_column_text(stmt.get(), 1));
      frames[id] = {sqlite3_column_int(stmt.get(), 5), sqlite3_column_int(stmt.get(), 6)};
      const int rows = sqlite3_column_int(stmt.get(), 2), cols = sqlite3_column_int(stmt.get(), 3);
      const auto* data = static_cast<const float*>(sqlite3_column_blob(stmt.get(), 4));
      if (rows < 0 || cols < 2 ||
          sqlite3_column_bytes(stmt.get(), 4) != int(rows * cols * sizeof(float)) ||
          (rows > 0 && !data))
        throw std::runtime_error(database.string() + ": keypoints of " + names[id] + " are " +
                                 std::to_string(rows) + "x" + std::to_string(cols) + " in " +
                                 std::to_string(sqlite3_column_bytes(stmt.get(), 4)) + " bytes");
      std::vector<cv::Point2f>& points = keypoints[id];
      for (int r = 0; r < rows; ++r) points.emplace_back(data[r * cols], data[r * cols + 1]);
    }
  }
  const Statement stmt = Prepare(db, database,
                                 "SELECT pair_id, rows, cols, data FROM two_view_geometries "
                                 "WHERE config >= 2 AND rows >= ? ORDER BY pair_id");
  sqlite3_bind_int(stmt.get(), 1, std::max(4, options.min_matches));
  std::vector<SameShot> shots;
  while (sqlite3_step(stmt.get()) == SQLITE_ROW) {
    const long pair = sqlite3_column_int64(stmt.get(), 0);
    const auto [a, b] = ImagesOfPair(pair);
    const int rows = sqlite3_column_int(stmt.get(), 1), cols = sqlite3_column_int(stmt.get(), 2);
    const auto* data = static_cast<const uint32_t*>(sqlite3_column_blob(stmt.get(), 3));
    if (!keypoints.count(a) || !keypoints.count(b) || cols != 2 || !data ||
        sqlite3_column_bytes(stmt.get(), 3) != int(rows * 2 * sizeof(uint32_t)))
      throw std::runtime_error(database.string() + ": verified matches of pair " +
                               std::to_string(pair) + " do not fit its images' keypoints");
    const std::vector<cv::Point2f>&ka = keypoints[a], &kb = keypoints[b];
    std::vector<cv::Point2f> from, to;
    for (int r = 0; r < rows; ++r) {
      if (data[2 * r] >= ka.size() || data[2 * r + 1] >= kb.size())
        throw std::runtime_error(database.string() + ": a verified match of pair " +
                                 std::to_string(pair) + " names a keypoint its image lacks");
      from.push_back(ka[data[2 * r]]);
      to.push_back(kb[data[2 * r + 1]]);
    }
    // (OpenCV's RANSAC is seeded: the same matches give the same answer)
    cv::Mat inliers;
    const cv::Mat map =
        cv::estimateAffinePartial2D(from, to, inliers, cv::RANSAC, options.max_error_px);
    const double share = map.empty() ? 0.0 : cv::countNonZero(inliers) / double(rows);
    if (share >= options.min_similarity_share) {
      shots.push_back({names[a], names[b], rows, share, ""});
      continue;
    }
    // (RANSAC stops at the first model good enough by its odds, and the
    // refined map keeps that model's inliers: they are counted again here)
    const cv::Mat b_from_a = cv::findHomography(from, to, cv::RANSAC, options.max_error_px);
    if (b_from_a.empty()) continue;
    std::vector<cv::Point2f> mapped;
    cv::perspectiveTransform(from, mapped, b_from_a);
    int close = 0;
    for (size_t k = 0; k < mapped.size(); ++k)
      close += cv::norm(mapped[k] - to[k]) <= options.max_error_px;
    const double perspective_share = close / double(rows);
    if (perspective_share < options.min_perspective_share) continue;
    if (FrameInside(b_from_a, frames[a], frames[b], options.frame_margin))
      shots.push_back({names[a], names[b], rows, perspective_share, names[a]});
    else if (FrameInside(b_from_a.inv(), frames[b], frames[a], options.frame_margin))
      shots.push_back({names[a], names[b], rows, perspective_share, names[b]});
  }
  return shots;
}

void SetMissingFocalPriors(const fs::path& database, double focal_35mm) {
  const Database db = OpenDatabase(database, SQLITE_OPEN_READWRITE);
  const Statement select = Prepare(db, database,
                                   "SELECT camera_id, model, width, height, params FROM cameras "
                                   "WHERE prior_focal_length = 0");
  const Statement update = Prepare(
      db, database, "UPDATE cameras SET params = ?, prior_focal_length = 1 WHERE camera_id = ?");
  // Read whole before the first update: SQLite leaves undefined whether a
  // running SELECT sees rows an UPDATE changed.
  struct Camera {
    int id, model, width, height;
    std::vector<double> params;
  };
  std::vector<Camera> cameras;
  while (sqlite3_step(select.get()) == SQLITE_ROW) {
    Camera c{sqlite3_column_int(select.get(), 0),
             sqlite3_column_int(select.get(), 1),
             sqlite3_column_int(select.get(), 2),
             sqlite3_column_int(select.get(), 3),
             {}};
    const auto* data = static_cast<const double*>(sqlite3_column_blob(select.get(), 4));
    c.params.assign(data, data + sqlite3_column_bytes(select.get(), 4) / sizeof(double));
    cameras.push_back(std::move(c));
  }
  for (Camera& c : cameras) {
    // COLMAP's model ids: 0 SIMPLE_PINHOLE, 2 SIMPLE_RADIAL, 3 RADIAL have
    // one focal length, PINHOLE (1) and the OpenCV models (4 on) two; then
    // the principal point, then the distortion.
    const size_t focals = c.model == 1 || c.model >= 4 ? 2 : 1;
    if (c.params.size() < focals + 2)
      throw std::runtime_error(database.string() + ": camera " + std::to_string(c.id) + " has " +
                               std::to_string(c.params.size()) + " parameters");
    std::fill(c.params.begin(), c.params.begin() + focals,
              FocalPixelsFrom35mm(focal_35mm, c.width, c.height));
    std::fill(c.params.begin() + focals + 2, c.params.end(), 0.0);
    sqlite3_reset(update.get());
    sqlite3_bind_blob(update.get(), 1, c.params.data(), int(c.params.size() * sizeof(double)),
                      SQLITE_TRANSIENT);
    sqlite3_bind_int(update.get(), 2, c.id);
    if (sqlite3_step(update.get()) != SQLITE_DONE)
      throw std::runtime_error(database.string() + ": " + sqlite3_errmsg(db.get()));
  }
}

std::vector<ImageDescriptors> ReadDatabaseDescriptors(const fs::path& database) {
  const Database db = OpenDatabase(database, SQLITE_OPEN_READONLY);
  const Statement stmt = Prepare(db, database,
                                 "SELECT images.image_id, images.name, descriptors.rows, "
                                 "descriptors.cols, descriptors.data FROM images JOIN descriptors "
                                 "ON images.image_id = descriptors.image_id "
                                 "ORDER BY images.image_id");
  std::vector<ImageDescriptors> images;
  int step;
  while ((step = sqlite3_step(stmt.get())) == SQLITE_ROW) {
    ImageDescriptors d;
    d.image_id = sqlite3_column_int(stmt.get(), 0);
    d.name = reinterpret_cast<const char*>(sqlite3_column_text(stmt.get(), 1));
    const int rows = sqlite3_column_int(stmt.get(), 2), cols = sqlite3_column_int(stmt.get(), 3);
    const int bytes = sqlite3_column_bytes(stmt.get(), 4);
    const auto* data = static_cast<const uint8_t*>(sqlite3_column_blob(stmt.get(), 4));
    if (cols != 128 || rows < 0 || bytes != rows * cols || (rows > 0 && !data))
      throw std::runtime_error(database.string() + ": descriptors of " + d.name + " are " +
                               std::to_string(rows) + "x" + std::to_string(cols) + " in " +
                               std::to_string(bytes) + " bytes, expected 128 bytes a row");
    d.rows.resize(rows, 128);
    for (int i = 0; i < rows * 128; ++i) d.rows.data()[i] = float(data[i]);
    images.push_back(std::move(d));
  }
  if (step != SQLITE_DONE)
    throw std::runtime_error(database.string() + ": " + sqlite3_errmsg(db.get()));
  return images;
}

#ifndef DOCUNFOLD_SFM_AVX2
void DescriptorDotsAvx2(const int16_t*, int, const int16_t*, int, int32_t*, size_t) {
  throw std::logic_error("DescriptorDotsAvx2: this build has no AVX2 kernel");
}
#endif

bool HaveDescriptorDotsAvx2() {
#ifdef DOCUNFOLD_SFM_AVX2
  static const bool have = __builtin_cpu_supports("avx2");
  return have;
#else
  return false;
#endif
}

const char* AutoDotKernelName() { return HaveDescriptorDotsAvx2() ? "avx2" : "portable"; }

std::vector<std::pair<int, int>> MatchDescriptors(const ImageDescriptors& a,
                                                  const ImageDescriptors& b,
                                                  const MatchCriteria& criteria, DotKernel kernel) {
  const int na = int(a.rows.rows()), nb = int(b.rows.rows());
  std::vector<Nearest> a_to_b(na), b_to_a(nb);
  // Each dot product is a sum of 128 products of integers below 256: exact
  // in int32 and in float whatever the order of summation, so both kernels
  // (and any BLAS path of Eigen's) give the same values.
  if (kernel == DotKernel::kAuto && HaveDescriptorDotsAvx2()) {
    const int blocks = (nb + kDotBlockRows - 1) / kDotBlockRows;
    std::vector<int16_t> a16(size_t(na) * 128), b_packed(size_t(blocks) * kDotBlockValues, 0);
    for (int i = 0; i < na; ++i)
      for (int k = 0; k < 128; ++k) a16[size_t(i) * 128 + k] = int16_t(a.rows(i, k));
    for (int j = 0; j < nb; ++j)
      for (int k = 0; k < 128; ++k)
        b_packed[size_t(j / kDotBlockRows) * kDotBlockValues + (k / 2) * 2 * kDotBlockRows +
                 (j % kDotBlockRows) * 2 + k % 2] = int16_t(b.rows(j, k));
    // In blocks of a's rows small enough to stay in cache until scanned.
    constexpr int kBlock = 64;
    const size_t stride = size_t(blocks) * kDotBlockRows;
    std::vector<int32_t> dots(size_t(kBlock) * stride);
    for (int start = 0; start < na; start += kBlock) {
      const int rows = std::min(kBlock, na - start);
      DescriptorDotsAvx2(a16.data() + size_t(start) * 128, rows, b_packed.data(), blocks,
                         dots.data(), stride);
      for (int i = 0; i < rows; ++i) {
        const int32_t* row = dots.data() + size_t(i) * stride;
        for (int j = 0; j < nb; ++j) {
          const float d = float(row[j]);
          a_to_b[start + i].Offer(d, j);
          b_to_a[j].Offer(d, start + i);
        }
      }
    }
  } else {
    // In blocks of a's rows, to bound the memory of the dot products.
    constexpr int kBlock = 1024;
    Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> dots;
    for (int start = 0; start < na; start += kBlock) {
      const int rows = std::min(kBlock, na - start);
      dots.noalias() = a.rows.middleRows(start, rows) * b.rows.transpose();
      for (int i = 0; i < rows; ++i)
        for (int j = 0; j < nb; ++j) {
          const float d = dots(i, j);
          a_to_b[start + i].Offer(d, j);
          b_to_a[j].Offer(d, start + i);
        }
    }
  }
  const std::vector<int> ab = OneWay(a_to_b, criteria);
  const std::vector<int> ba = criteria.cross_check ? OneWay(b_to_a, criteria) : std::vector<int>();
  std::vector<std::pair<int, int>> matches;
  for (int i = 0; i < na; ++i) {
    if (ab[i] < 0) continue;
    if (criteria.cross_check && ba[ab[i]] != i) continue;
    matches.emplace_back(i, ab[i]);
  }
  return matches;
}

std::vector<std::vector<std::pair<int, int>>> MatchAllPairs(
    const std::vector<ImageDescriptors>& images, const MatchCriteria& criteria, int threads,
    const std::function<void(int done)>& on_pair) {
  std::vector<std::pair<size_t, size_t>> pairs;
  for (size_t a = 0; a < images.size(); ++a)
    for (size_t b = a + 1; b < images.size(); ++b) pairs.emplace_back(a, b);
  std::vector<std::vector<std::pair<int, int>>> matches(pairs.size());
  if (threads < 1) threads = int(std::max(1u, std::thread::hardware_concurrency()));
  threads = std::min<int>(threads, int(pairs.size()));
  std::atomic<size_t> next{0};
  std::mutex report;
  int done = 0;
  std::exception_ptr failure;
  auto work = [&] {
    try {
      for (size_t k; (k = next++) < pairs.size();) {
        matches[k] = MatchDescriptors(images[pairs[k].first], images[pairs[k].second], criteria);
        const std::lock_guard<std::mutex> lock(report);
        if (on_pair) on_pair(++done);
      }
    } catch (...) {
      const std::lock_guard<std::mutex> lock(report);
      if (!failure) failure = std::current_exception();
      next = pairs.size();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
  return matches;
}

}  // namespace docunfold::sfm
