// Reading render's inputs and writing its outputs (all or nothing).
#include <cmath>
#include <memory>
#include <opencv2/imgcodecs.hpp>

#include "common/atomic_file.h"
#include "common/errors.h"
#include "common/json_io.h"
#include "stages/render/render.h"

namespace docunfold::render {

RenderInputs ReadRenderInputs(const fs::path& sfm_dir, const fs::path& boundary_dir,
                              const fs::path& meshes_dir, const fs::path& images_dir,
                              const fs::path& features_file) {
  RenderInputs in;
  in.cameras_file = sfm_dir / "cameras.json";
  in.reference_file = sfm_dir / "reference.png";
  in.meshes_dir = meshes_dir;
  const CameraSet cameras = ReadCameras(in.cameras_file);
  if (cameras.reference.empty())
    throw InputError(in.cameras_file.string() +
                     ":/reference: missing; render needs sfm's cameras.json, "
                     "which names the "
                     "reference view");
  in.camera = *cameras.Find(cameras.reference);
  in.reference = ReadImage(in.reference_file, cv::IMREAD_COLOR);
  in.boundary = ReadBoundary(boundary_dir / "boundary.json");
  // The other views' page masks, where segment-boundary found them, with
  // the distortion of their (original, not undistorted) photos.
  const Json cameras_doc = ReadJsonFile(in.cameras_file);
  const JsonReader cameras_reader(cameras_doc, in.cameras_file);
  for (size_t i = 0; i < cameras.views.size(); ++i) {
    const PinholeCamera& view = cameras.views[i];
    if (view.image == cameras.reference) continue;
    const fs::path mask_file = boundary_dir / "views" / fs::path(view.image).stem() / "mask.png";
    std::error_code exists_ec;
    if (!fs::is_regular_file(mask_file, exists_ec)) continue;
    fs::path photo;
    if (!images_dir.empty()) {
      photo = images_dir / view.image;
      if (!fs::is_regular_file(photo, exists_ec))
        throw InputError(photo.string() + ": no such file (a view in " + in.cameras_file.string() +
                         ")");
    }
    in.views.push_back({view, ReadDocumentMask(mask_file, view.width, view.height), mask_file,
                        photo, ReadDistortion(cameras_reader, "/views/" + std::to_string(i))});
  }
  std::error_code ec;
  if (!fs::is_directory(meshes_dir, ec))
    throw InputError(meshes_dir.string() + ": no such directory (expected mesh3d.ply, mesh2d.ply)");
  in.meshes = ReadMeshPair(meshes_dir);
  // optimize's lines, for the deskew: each line's direction (its normal
  // turned, the same modulo 90 degrees) and its extent in M'.
  const fs::path lines_file = meshes_dir / "lines.json";
  if (fs::is_regular_file(lines_file, ec)) {
    const Json doc = ReadJsonFile(lines_file);
    const JsonReader r(doc, lines_file);
    if (!r.At("/lines").is_array()) r.Fail("/lines", "expected an array");
    if (r.Has("/text_down_flat")) in.text_down = r.Vector2("/text_down_flat");
    for (size_t i = 0; i < doc["lines"].size(); ++i) {
      const std::string where = "/lines/" + std::to_string(i);
      const Eigen::Vector2d n = r.Vector2(where + "/normal");
      const Eigen::Vector2d along(-n.y(), n.x());
      const Json& flat = r.At(where + "/flat");
      if (!flat.is_array()) r.Fail(where + "/flat", "expected [[x, y], ...]");
      double lo = 1e300, hi = -1e300;
      for (size_t k = 0; k < flat.size(); ++k) {
        const double t = along.dot(r.Vector2(where + "/flat/" + std::to_string(k)));
        lo = std::min(lo, t);
        hi = std::max(hi, t);
      }
      if (hi > lo && std::isfinite(hi - lo)) {
        in.lines.push_back({std::atan2(n.y(), n.x()) * 180 / M_PI, hi - lo});
        if (doc["lines"][i].value("kind", "") == "text")
          in.text_lines.push_back({std::atan2(along.y(), along.x()) * 180 / M_PI, hi - lo});
      }
    }
  }
  if (!features_file.empty() && !in.text_down) {
    const FeatureFile features = ReadFeatures(features_file);
    if (features.text_down) {
      in.text_down_image = features.text_down;
      for (const FeatureSegment& segment : features.segments)
        if (segment.kind == "text")
          in.text_points.insert(in.text_points.end(), segment.points.begin(), segment.points.end());
    }
  }
  return in;
}

void WriteRenderOutputs(const fs::path& out_dir, const RenderResult& result) {
  if (result.rectified.empty() || result.rectified_grid.empty())
    throw OutputError(out_dir.string() + ": nothing to write");
  EnsureDirectory(out_dir);
  // A target that exists as something other than a file (a directory in the
  // way) would fail its rename after the others were renamed: refuse first.
  for (const char* name : {"rectified.png", "rectified_grid.png", "render.json"}) {
    std::error_code ec;
    const fs::path target = out_dir / name;
    if (fs::exists(fs::symlink_status(target, ec)) && !fs::is_regular_file(target, ec))
      throw OutputError(target.string() + ": exists and is not a regular file");
  }
  // Everything goes to temporary files first; only when all three are
  // complete are they renamed into place.
  AtomicOutput rectified(out_dir / "rectified.png");
  AtomicOutput grid(out_dir / "rectified_grid.png");
  AtomicOutput report(out_dir / "render.json");
  // Light PNG compression: the files are large and written on every run.
  const std::vector<int> png = {cv::IMWRITE_PNG_COMPRESSION, 3};
  auto write_image = [&](const AtomicOutput& out, const cv::Mat& image) {
    bool ok = false;
    try {
      ok = cv::imwrite(out.temp_path().string(), image, png);
    } catch (const cv::Exception& e) {
      throw OutputError(out.target().string() + ": " + e.what());
    }
    if (!ok) throw OutputError(out.target().string() + ": cannot write image");
  };
  write_image(rectified, result.rectified);
  write_image(grid, result.rectified_grid);
  {
    // WriteJsonAtomic would commit on its own; write the text by hand.
    FILE* f = std::fopen(report.temp_path().c_str(), "wb");
    if (!f) throw OutputError(report.target().string() + ": cannot open for writing");
    const std::string text = result.report.dump(1) + "\n";
    const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    if (std::fclose(f) != 0 || !ok) throw OutputError(report.target().string() + ": write failed");
  }
  rectified.Commit();
  grid.Commit();
  report.Commit();
}

}  // namespace docunfold::render
