// The steps of RunSfm that run COLMAP (colmap_steps.cc): feature extraction,
// matching and mapping with retries.
#pragma once

#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/subprocess.h"
#include "stages/sfm/colmap_model.h"
#include "stages/sfm/photo_set.h"
#include "stages/sfm/sfm.h"

namespace docunfold::sfm::detail {

// An existing --out must be a folder sfm wrote (or an empty one): we replace
// it as a whole and must not wipe anything else.
void CheckOutputDir(const fs::path& out);

// COLMAP's command-line tools on one workspace.
struct Colmap {
  fs::path exe;
  const SfmOptions* options;
  fs::path dir;         // colmap/ workspace
  fs::path database;    // <dir>/database.db
  fs::path image_dir;   // <dir>/images: the photos' copies (photo_set.h)
  std::string threads;  // --threads as COLMAP takes it
  // When the photos fall into groups with no features in common, the copies
  // of the largest, which alone the mapper is given (listed in
  // <dir>/mapped_images.txt); empty: every photo.
  std::vector<std::string> mapped;
  // The other groups of two or more photos (other pages), as photo file
  // names, each sorted, the groups by their first name.
  std::vector<std::vector<std::string>> other_pages;

  // Runs one COLMAP command, its output into <dir>/<log>; throws when it
  // fails (except for the mapper, whose failure the caller judges).
  SubprocessResult Run(const std::string& command, std::vector<std::string> args,
                       const std::string& log,
                       const std::function<void(const std::string&)>& on_line,
                       bool throw_on_failure = true) const;

  static std::string NotFoundMessage(const std::string& program);
};

// SIFT features of every photo into the database (feature_extractor).
void ExtractFeatures(const Colmap& colmap, const PhotoSet& photos);

// Matches between every pair of photos: exact nearest neighbours
// (matching.h) verified by COLMAP, or COLMAP's own exhaustive matcher.
void MatchFeatures(const Colmap& colmap, const PhotoSet& photos);

// Leaves out a photo that is an edited copy of another (cropped, turned or
// retouched; logged, in PhotoSet::left_out, and its thumbnail removed), then
// groups the photos by the matches COLMAP verified between them: when they
// fall into more than one group (photos of two pages, or of something else),
// says so in one line, leaves the mapper the largest (Colmap::mapped) and
// lists the other groups of two or more (Colmap::other_pages). InputError
// when fewer than 2 photos remain.
void ChooseLinkedViews(PhotoSet* photos, std::vector<cv::Mat>* thumbnails, Colmap* colmap);

// What the mapper made, over its attempts.
struct Mapping {
  std::vector<MapperAttempt> attempts;  // in the order tried
  bool found = false;                   // some attempt made a model
  ColmapModel model;                    // the best attempt's
  fs::path model_dir;                   // where it is
};

// Incremental mapping into <dir>/attempts/<i>/, retried with other settings
// (SfmOptions::retry) while the result is implausible; the best attempt
// (plausible first, in the order tried) wins.
Mapping MapWithRetries(const Colmap& colmap, const PhotoSet& photos);

// Keeps the chosen model as <dir>/sparse/0 (what `colmap model_analyzer` and
// the GUI expect) and drops the other attempts.
void KeepModel(const Colmap& colmap, const fs::path& model_dir);

}  // namespace docunfold::sfm::detail
