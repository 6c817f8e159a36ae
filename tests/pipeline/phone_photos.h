// A data set made from another's photos the way phones and people change
// them: EXIF-tagged portrait photos, photos turned in their pixels, other
// sizes, HEIC, names with spaces and accents, a truncated photo, a sidecar
// file. The ground truth comes along: flat.png and the surface as they are,
// cameras.json rewritten for each photo as it now stands upright.
#pragma once

#include <filesystem>
#include <map>
#include <set>
#include <string>

namespace docunfold::testing {

namespace fs = std::filesystem;

// Views are indices into the source's photos sorted by name.
struct PhoneChanges {
  std::set<int> exif_portrait;  // pixels as stored, EXIF Orientation 6 (turn 90° clockwise),
                                // with the EXIF make, model and 35 mm focal length of a phone
  std::set<int> turned;         // pixels turned 90° clockwise, no tag
  std::map<int, double> scale;  // resized by this factor
  std::set<int> heic;           // stored as HEIC (heif-enc)
  std::set<int> truncated;      // cut to 60 % of its bytes (an interrupted copy)
  bool spaced_names = false;    // names with spaces, accents and brackets
  bool sidecar = false;         // an iPhone's IMG_0001.AAE beside the photos
};

// Makes <to>/images, <to>/ground_truth and <to>/VARIANT (naming `from`) from
// the data set at `from`.
// Throws std::runtime_error when a tool (heif-enc, exiftool) fails.
void MakePhoneSet(const fs::path& from, const fs::path& to, const PhoneChanges& changes);

}  // namespace docunfold::testing
