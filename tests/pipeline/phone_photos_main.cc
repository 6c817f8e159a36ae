// phone-photos FROM TO [changes]: a data set made from another's photos the
// way phones and people change them (phone_photos.h). The tests and the
// benchmark make their phone-like sets with it.
#include <CLI/CLI.hpp>
#include <iostream>

#include "tests/pipeline/phone_photos.h"

int main(int argc, char** argv) {
  using docunfold::testing::PhoneChanges;
  CLI::App app{"Makes a data set from another's photos the way phones and people change them"};
  std::string from, to;
  PhoneChanges c;
  std::vector<int> exif, turned, heic, truncated;
  std::vector<std::string> scales;
  app.add_option("from", from, "data set to start from (images/, ground_truth/)")->required();
  app.add_option("to", to, "data set to make (must not exist)")->required();
  app.add_option("--exif-portrait", exif,
                 "views stored as they are with EXIF Orientation 6 and a phone's EXIF");
  app.add_option("--turn", turned, "views turned 90 degrees clockwise in their pixels");
  app.add_option("--scale", scales, "VIEW:FACTOR, a view resized (0.5, 5)");
  app.add_option("--heic", heic, "views stored as HEIC");
  app.add_option("--truncate", truncated, "views cut to 60 % of their bytes");
  app.add_flag("--spaced-names", c.spaced_names, "names with spaces, accents and brackets");
  app.add_flag("--sidecar", c.sidecar, "an iPhone's IMG_0001.AAE beside the photos");
  CLI11_PARSE(app, argc, argv);
  c.exif_portrait = {exif.begin(), exif.end()};
  c.turned = {turned.begin(), turned.end()};
  c.heic = {heic.begin(), heic.end()};
  c.truncated = {truncated.begin(), truncated.end()};
  try {
    for (const std::string& s : scales) {
      const size_t colon = s.find(':');
      if (colon == std::string::npos) throw std::invalid_argument("--scale " + s + ": VIEW:FACTOR");
      c.scale[std::stoi(s.substr(0, colon))] = std::stod(s.substr(colon + 1));
    }
    if (std::filesystem::exists(to)) throw std::invalid_argument(to + ": exists");
    docunfold::testing::MakePhoneSet(from, to, c);
  } catch (const std::exception& e) {
    std::cerr << "phone-photos: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
