// Reading render's inputs, render.json, and writing the outputs (all or
// nothing).
#include <algorithm>
#include <cmath>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <utility>

#include "common/atomic_file.h"
#include "common/errors.h"
#include "common/json_io.h"
#include "stages/render/lines_file.h"
#include "stages/render/render.h"

namespace docunfold::render {

namespace {

// The photos of cameras.json's reference_selection/views other than
// `reference`, in its order; advice only, so a missing or odd entry is skipped.
std::vector<std::string> OtherReferences(const Json& cameras, const std::string& reference) {
  std::vector<std::string> names;
  const auto selection = cameras.find("reference_selection");
  if (selection == cameras.end() || !selection->is_object()) return names;
  const auto views = selection->find("views");
  if (views == selection->end() || !views->is_array()) return names;
  for (const Json& v : *views) {
    const auto image = v.is_object() ? v.find("image") : v.end();
    if (image == v.end() || !image->is_string()) continue;
    if (image->get<std::string>() != reference) names.push_back(image->get<std::string>());
  }
  return names;
}

}  // namespace

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
  in.other_references = OtherReferences(ReadJsonFile(in.cameras_file), cameras.reference);
  in.reference = ReadImage(in.reference_file, cv::IMREAD_COLOR);
  in.boundary = ReadBoundary(boundary_dir / "boundary.json");
  // The other views' page masks, where segment-boundary found them, with
  // the distortion of their (original, not undistorted) photos.
  for (ViewPage& page : ReadOtherViewPages(cameras, in.cameras_file, boundary_dir)) {
    fs::path photo;
    std::error_code exists_ec;
    if (!images_dir.empty()) {
      photo = images_dir / page.camera.image;
      if (!fs::is_regular_file(photo, exists_ec))
        throw InputError(photo.string() + ": no such file (a view in " + in.cameras_file.string() +
                         ")");
    }
    in.views.push_back({page.camera, std::move(page.mask), page.file, photo, page.distortion});
  }
  std::error_code ec;
  if (!fs::is_directory(meshes_dir, ec))
    throw InputError(meshes_dir.string() + ": no such directory (expected mesh3d.ply, mesh2d.ply)");
  in.meshes = ReadMeshPair(meshes_dir);
  // optimize's lines, for the deskew and the page's orientation.
  const fs::path lines_file = meshes_dir / "lines.json";
  if (fs::is_regular_file(lines_file, ec)) {
    LinesFile lines = ReadLinesFile(lines_file);
    in.lines = std::move(lines.lines);
    in.text_lines = std::move(lines.text_lines);
    in.text_down = lines.text_down;
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

namespace {

Json Vec2(const Eigen::Vector2d& v) { return Json::array({v.x(), v.y()}); }

// render.json's "straightening": what each direction's pass found.
Json StraighteningJson(const RenderOptions& options, const RenderResult& r) {
  auto pass = [](const StraightenPass& p) {
    return Json{{"strips", p.strips},
                {"windows", p.windows},
                {"shifts_found", p.shifts_found},
                {"max_shift_px", p.max_shift_px}};
  };
  return {{"applied", options.straighten.enabled},
          {"rows", pass(r.straightened_rows)},
          {"columns", pass(r.straightened_columns)}};
}

// Side i of render.json's "sides": its line, how it was placed or reached,
// and the page edge past it where the reference image cuts it.
Json SideReport(const RenderOptions& options, const RenderResult& r, int i) {
  const SideFit& s = r.sides[i];
  Json j = {{"real", s.real}, {"used", s.used}, {"samples", s.samples}, {"mapped", s.mapped}};
  if (s.used) {
    j["point"] = Vec2(s.point);
    j["direction"] = Vec2(s.direction);
    j["rms"] = s.rms;
    j["warped"] = r.warped_sides[i];
    if (s.reference_cos) j["reference_cos"] = *s.reference_cos;
    if (!s.placed_by.empty()) j["placed_by"] = {{"view", s.placed_by}, {"cos", s.placed_by_cos}};
  }
  if (!s.note.empty()) j["note"] = s.note;
  if (s.scattered) j["median_bound"] = s.median_bound;
  if (const CutSideEdge& e = r.reached_sides[i]; e.measured) {
    j["reached_past_mesh"] = {
        {"bound", e.bound}, {"extension", e.extension}, {"crossings", e.crossings}};
    if (!e.placed_by.empty())
      j["reached_past_mesh"]["placed_by"] = {{"view", e.placed_by}, {"cos", e.placed_by_cos}};
  }
  if (!s.real && options.extend_cut_sides) {
    const CutSideEdge& e = r.cut_edges[i];
    Json c = {{"measured", e.measured},
              {"edge_seen", e.edge_seen},
              {"crossings", e.crossings},
              {"columns_seen", e.columns_seen},
              {"views", e.views}};
    if (e.measured) {
      c["bound"] = e.bound;
      c["extension"] = e.extension;
    }
    if (!e.note.empty()) c["note"] = e.note;
    j["page_edge_in_other_views"] = c;
  }
  return j;
}

}  // namespace

Json RenderReport(const RenderOptions& options, const RenderInputs& in, const RenderResult& r,
                  const Json& options_record) {
  Json doc = MakeHeader("docunfold.render", 1, "render", options_record);
  doc["inputs"] = {{"meshes", in.meshes_dir.string()},
                   {"reference", in.reference_file.string()},
                   {"boundary", in.boundary.file.string()},
                   {"grid", {in.meshes.grid.nx, in.meshes.grid.ny}}};
  doc["inputs"]["view_masks"] = Json::array();
  for (const ViewMask& v : in.views) doc["inputs"]["view_masks"].push_back(v.file.string());
  doc["width"] = r.rectified.cols;
  doc["height"] = r.rectified.rows;
  doc["pixels_per_unit"] = r.pixels_per_unit;
  doc["pixels_per_unit_y"] = r.pixels_per_unit_y;
  doc["reference_pixels_per_unit"] = r.reference_pixels_per_unit;
  doc["size_rule"] = r.size_rule;
  doc["capped"] = r.capped;
  doc["rotation_deg"] = r.rotation_deg;
  doc["deskew_source"] = r.deskew_source;
  doc["warnings"] = r.warnings;
  doc["crop"] = {{"x0", r.crop_x0}, {"y0", r.crop_y0},     {"x1", r.crop_x1},
                 {"y1", r.crop_y1}, {"rule", r.crop_rule}, {"warp_max_shift", r.warp_max_shift}};
  const auto& w = r.warped_sides;
  if (std::find(w.begin(), w.end(), true) != w.end())
    doc["crop"]["warp_box"] = {r.warp_box[0], r.warp_box[1], r.warp_box[2], r.warp_box[3]};
  Json sides = Json::object();
  for (int i = 0; i < 4; ++i) sides[kSideNames[i]] = SideReport(options, r, i);
  doc["sides"] = sides;
  if (const PageFormatFit& f = r.page_format;
      options.page_aspect > 0 && (f.axis >= 0 || !f.note.empty())) {
    // axis -1 with a note: sides of both axes are cut off unseen.
    Json j = {{"aspect", options.page_aspect},
              {"applied", f.applied},
              {"axis", f.axis < 0    ? "both"
                       : f.axis == 0 ? "x"
                                     : "y"}};
    if (f.axis >= 0) {
      j["seen"] = f.seen;
      j["across"] = f.across;
    }
    if (f.applied) j["length"] = f.length;
    if (!f.note.empty()) j["note"] = f.note;
    doc["page_format"] = j;
  }
  doc["fill_rgb"] = {r.fill[2], r.fill[1], r.fill[0]};
  doc["page_fraction"] = r.page_fraction;
  doc["hidden_fraction"] = r.hidden_fraction;
  doc["minified_fraction"] = r.minified_fraction;
  doc["other_view_fraction"] = r.other_view_fraction;
  doc["shading"] = {{"removed", r.shading_removed}};
  if (r.shading_removed) doc["shading"]["paper_fraction"] = r.shading_paper_fraction;
  doc["straightening"] = StraighteningJson(options, r);
  Json regs = Json::array();
  for (const ViewRegistration& g : r.registrations)
    regs.push_back({{"view", in.views[g.view].camera.image},
                    {"affine",
                     {{g.affine(0, 0), g.affine(0, 1), g.affine(0, 2)},
                      {g.affine(1, 0), g.affine(1, 1), g.affine(1, 2)}}},
                    {"inliers", g.inliers},
                    {"moved", g.moved},
                    {"agreement", g.agreement},
                    {"used", g.used}});
  doc["other_views"] = regs;
  Json texture = {{"method", options.texture == Texture::kFusion ? "fusion" : "reference"}};
  if (options.texture == Texture::kFusion) {
    Json views = Json::array();
    for (const FusionViewReport& v : r.texture_views)
      views.push_back({{"view", v.name},
                       {"seen", v.seen},
                       {"share", v.share},
                       {"gain_bgr", {v.gain[0], v.gain[1], v.gain[2]}},
                       {"flow_p95_px", v.flow_p95},
                       {"sharpness", v.sharpness}});
    texture["views"] = views;
    texture["unseen_fraction"] = r.texture_unseen;
    Json steps = Json::object();
    for (const auto& [step, seconds] : r.texture_timings) steps[step] = seconds;
    texture["timing_s"] = steps;
  }
  doc["texture"] = texture;
  doc["grid_line_step"] = r.grid_line_step;
  Json timing = Json::object();
  double total = 0;
  for (const auto& [step, seconds] : r.timings) {
    timing[step] = seconds;
    total += seconds;
  }
  timing["total"] = total;
  doc["timing_s"] = timing;
  doc["orientation"] = r.orientation;
  return doc;
}

void WriteRenderOutputs(const fs::path& out_dir, const RenderResult& result, const Json& report) {
  if (result.rectified.empty() || result.rectified_grid.empty())
    throw OutputError(out_dir.string() + ": nothing to write");
  EnsureDirectory(out_dir);
  // A target that exists as something other than a file (a directory in the
  // way) would fail its rename after the others were renamed: refuse first.
  for (const char* name :
       {"rectified.png", "rectified_grid.png", "texture_labels.png", "render.json"}) {
    std::error_code ec;
    const fs::path target = out_dir / name;
    if (fs::exists(fs::symlink_status(target, ec)) && !fs::is_regular_file(target, ec))
      throw OutputError(target.string() + ": exists and is not a regular file");
  }
  // Everything goes to temporary files first; only when all are
  // complete are they renamed into place.
  AtomicOutput rectified(out_dir / "rectified.png");
  AtomicOutput grid(out_dir / "rectified_grid.png");
  AtomicOutput report_file(out_dir / "render.json");
  std::optional<AtomicOutput> labels;
  if (!result.texture_labels.empty()) labels.emplace(out_dir / "texture_labels.png");
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
  if (labels) write_image(*labels, DrawLabels(result.texture_labels));
  {
    // WriteJsonAtomic would commit on its own; write the text by hand.
    FILE* f = std::fopen(report_file.temp_path().c_str(), "wb");
    if (!f) throw OutputError(report_file.target().string() + ": cannot open for writing");
    const std::string text = report.dump(1) + "\n";
    const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    if (std::fclose(f) != 0 || !ok)
      throw OutputError(report_file.target().string() + ": write failed");
  }
  rectified.Commit();
  grid.Commit();
  if (labels) labels->Commit();
  report_file.Commit();
  // A label map of an earlier fusion run would describe another image.
  std::error_code ec;
  if (!labels) fs::remove(out_dir / "texture_labels.png", ec);
}

}  // namespace docunfold::render
