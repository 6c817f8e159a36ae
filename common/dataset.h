// A data set on disk: images/ with the photos and, optionally,
// ground_truth/ (the true flat page, surface and cameras: flat.png,
// mesh.ply, cameras.json, page.json, ...).
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace docunfold {

namespace fs = std::filesystem;

struct DataSet {
  fs::path root;
  // The photos' own folder: root/images with links resolved (pipeline.mk
  // reaches a plain folder of photos through a link), absolute; what a
  // message or a report names as where the photos are.
  fs::path photos_dir;
  // Every file in images/ but hidden ones, sorted by name: which are photos
  // the photo reader (photo.h) tells by their content.
  std::vector<fs::path> images;
  // Folders in images/ (hidden ones aside), sorted: never read, listed so
  // that a reader can say they are left out.
  std::vector<fs::path> folders;
  bool has_ground_truth = false;

  fs::path ground_truth(const std::string& file) const { return root / "ground_truth" / file; }
};

// Lists a data set; throws InputError when the folder or images/ is missing.
DataSet OpenDataSet(const fs::path& root);

// The page's size in metres (width, height) from ground_truth/page.json
// (docunfold.gt-page); InputError when missing, malformed or not positive.
std::pair<double, double> ReadTruePageSize(const fs::path& page_json);

}  // namespace docunfold
