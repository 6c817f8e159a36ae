#include "common/dataset.h"

#include <algorithm>

#include "common/errors.h"
#include "common/json_io.h"

namespace docunfold {

DataSet OpenDataSet(const fs::path& root) {
  std::error_code ec;
  if (!fs::is_directory(root, ec)) throw InputError(root.string() + ": no such data set folder");
  if (!fs::is_directory(root / "images", ec))
    throw InputError((root / "images").string() +
                     ": missing (a data set keeps its photos in images/)");
  DataSet set;
  set.root = root;
  set.photos_dir = fs::canonical(root / "images", ec);
  if (ec) set.photos_dir = fs::absolute(root / "images").lexically_normal();
  for (const auto& entry : fs::directory_iterator(root / "images", ec)) {
    if (entry.path().filename().string().rfind('.', 0) == 0) continue;
    if (entry.is_regular_file())
      set.images.push_back(entry.path());
    else if (entry.is_directory())
      set.folders.push_back(entry.path());
  }
  std::sort(set.images.begin(), set.images.end());
  std::sort(set.folders.begin(), set.folders.end());
  set.has_ground_truth = fs::is_directory(root / "ground_truth", ec);
  return set;
}

std::pair<double, double> ReadTruePageSize(const fs::path& page_json) {
  const Json page = ReadJsonFile(page_json);
  CheckFormat(page, page_json, "docunfold.gt-page", 1);
  JsonReader r(page, page_json);
  const double w = r.Number("/width_m"), h = r.Number("/height_m");
  if (!(w > 0) || !(h > 0)) r.Fail("/width_m", "page size must be positive");
  return {w, h};
}

}  // namespace docunfold
