// Exact SIFT matching between every pair of views, for COLMAP's
// matches_importer. COLMAP's CPU exhaustive matcher finds nearest
// neighbours with FLANN's randomised k-d trees, so the same photos give a
// few different matches on every run and the whole pipeline after it
// drifts by a few hundredths; brute force over the same criteria gives the
// same matches every time, and COLMAP's geometric verification of them is
// repeatable (its RANSAC is seeded).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace docunfold::sfm {

namespace fs = std::filesystem;

// One image's SIFT descriptors as COLMAP stores them: rows of 128 unsigned
// bytes, each row L2-normalised to 512.
struct ImageDescriptors {
  int image_id = 0;
  std::string name;
  Eigen::Matrix<float, Eigen::Dynamic, 128, Eigen::RowMajor> rows;
};

// Gives a COLMAP database's images the ids 1, 2, ... in the order of their
// names (images, keypoints and descriptors tables; before matching). The
// feature extractor numbers them in the order its threads finish, and the
// mapper's choices follow the ids. Throws std::runtime_error naming the
// database when it cannot be changed.
void NumberImagesByName(const fs::path& database);

// Gives every camera of a COLMAP database that has no focal length prior the
// focal length of a lens of `focal_35mm` (35 mm equivalent) at its size, and
// no distortion, as its prior (before mapping). Throws std::runtime_error
// naming the database when it cannot be changed.
void SetMissingFocalPriors(const fs::path& database, double focal_35mm);

// The images of a COLMAP database (their names) in groups: two are in one
// group when a chain of pairs links them, each pair with at least
// `min_inliers` matches COLMAP verified. Photos of two pages, or a photo of
// something else, fall into groups the mapper cannot join. Each group sorted
// by name; the groups by size, largest first, then by their first name.
// Throws std::runtime_error naming the database when it cannot be read.
std::vector<std::vector<std::string>> ViewsLinkedByMatches(const fs::path& database,
                                                           int min_inliers);

// Two images of a COLMAP database that are one shot: one is the other
// cropped, turned, scaled or retouched (a phone's edited copy beside the
// original), or the page cut out of it and straightened (a scanner app's
// copy). Two photos taken from two places never come that close: the map
// between them is a perspective one, bent further by the page's creases,
// and neither one's frame lies inside the other's (the page with the table
// around it in each).
struct SameShot {
  std::string first, second;  // image names, first before second by id
  int matches = 0;            // verified matches
  double share = 0;           // of them, the inliers of the map found
  // Empty when a similarity joins them (either may be the copy); else the
  // image whose whole frame a homography takes into the other's (a
  // perspective-corrected copy).
  std::string copy;
};

struct SameShotOptions {
  int min_matches = 50;  // verified matches of a pair looked at
  // Of them, at least this share within max_error_px of one similarity.
  double min_similarity_share = 0.9;
  // ... or of one homography that maps one frame's corners inside the
  // other's frame (to within frame_margin of its size). A copy's matches
  // all fit it; a closer photo's fit it on a textured table's plane, not
  // on the page's creases.
  double min_perspective_share = 0.95;
  double max_error_px = 2.0;  // pixels of the copies COLMAP read
  double frame_margin = 0.02;
};

// Every pair of images that is one shot, by pair id. Throws
// std::runtime_error naming the database when it cannot be read.
std::vector<SameShot> SameShots(const fs::path& database, const SameShotOptions& options);

// Every image of a COLMAP database with its descriptors, by image id.
// Throws std::runtime_error naming the database when it cannot be read.
std::vector<ImageDescriptors> ReadDatabaseDescriptors(const fs::path& database);

// COLMAP's SIFT matching criteria (SiftMatchingOptions), computed exactly.
struct MatchCriteria {
  double max_ratio = 0.8;     // best angle < max_ratio * second best
  double max_distance = 0.7;  // best angle (radians) at most this
  bool cross_check = true;    // keep only mutual best matches
};

// How the dot products are computed; both give the same exact values.
enum class DotKernel {
  // AVX2 integer products where the CPU has them (faster: see
  // docs/decisions/sfm.md, "Exact matching"), else kPortable.
  kAuto,
  kPortable,  // Eigen's float matrix product (exact: integer sums below 2^24)
};

// Index pairs (row of a, row of b) that pass `criteria`, in order of a's
// rows. Distances are the angles between descriptors, as COLMAP's.
std::vector<std::pair<int, int>> MatchDescriptors(const ImageDescriptors& a,
                                                  const ImageDescriptors& b,
                                                  const MatchCriteria& criteria,
                                                  DotKernel kernel = DotKernel::kAuto);

// The kernel kAuto takes on this machine: "avx2" or "portable".
const char* AutoDotKernelName();

// MatchDescriptors for every pair (a, b) with a < b, in that order: pair
// (0,1), (0,2), ..., (1,2), ... Pairs run on `threads` threads (< 1: every
// core); `on_pair` is called, one call at a time, after each.
std::vector<std::vector<std::pair<int, int>>> MatchAllPairs(
    const std::vector<ImageDescriptors>& images, const MatchCriteria& criteria, int threads,
    const std::function<void(int done)>& on_pair = nullptr);

}  // namespace docunfold::sfm
