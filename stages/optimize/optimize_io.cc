#include "stages/optimize/optimize_io.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/atomic_file.h"
#include "common/errors.h"
#include "common/gltf.h"
#include "common/option_table.h"
#include "common/ply.h"

namespace docunfold::optimize {
namespace {

Json Points(const std::vector<Eigen::Vector2d>& points) {
  Json a = Json::array();
  for (const auto& p : points) a.push_back({p.x(), p.y()});
  return a;
}

// "<before>WxH<after>, but the reference view is WxH": a file made for
// another image than the reference photo.
InputError SizeMismatch(const std::string& before, int width, int height, const std::string& after,
                        const PinholeCamera& reference) {
  return InputError(before + std::to_string(width) + "x" + std::to_string(height) + after +
                    ", but the reference view is " + std::to_string(reference.width) + "x" +
                    std::to_string(reference.height));
}

Json WeightsJson(const isometry::Weights& w) {
  return {{"iso", w.iso},       {"dist", w.dist}, {"fair3d", w.fair3d},
          {"fair2d", w.fair2d}, {"line", w.line}, {"ray", w.ray}};
}

}  // namespace

void DeclareOutputOptions(OptionTable& table, OutputOptions* o) {
  table.Switch("scene", &o->scene, "write scene.glb");
}

OptimizeInputs ReadInputs(const InputPaths& paths, bool view_masks) {
  OptimizeInputs in;
  const CameraSet cameras = ReadCameras(paths.sfm / "cameras.json");
  const PinholeCamera* ref = cameras.Find(cameras.reference);
  if (!ref)
    throw InputError((paths.sfm / "cameras.json").string() +
                     ": no reference view (not written by sfm?)");
  in.reference = *ref;
  const PlyData points = ReadPly(paths.PointsFile());
  if (points.vertices.empty()) throw InputError(paths.PointsFile().string() + ": no points");
  in.points = points.vertices;
  in.point_colors = points.colors;
  const fs::path boundary_file =
      fs::is_directory(paths.boundary) ? paths.boundary / "boundary.json" : paths.boundary;
  in.boundary = ReadBoundary(boundary_file);
  if (in.boundary.width != ref->width || in.boundary.height != ref->height)
    throw SizeMismatch(boundary_file.string() + ": found in a ", in.boundary.width,
                       in.boundary.height, " image", *ref);
  in.features = ReadFeatures(paths.features);
  if (in.features.width > 0 &&
      (in.features.width != ref->width || in.features.height != ref->height))
    throw SizeMismatch(paths.features.string() + ": segments of a ", in.features.width,
                       in.features.height, " image", *ref);
  in.init = ReadMeshPair(paths.init);
  // Without it optimize spares no crease; scene.glb still needs it.
  const fs::path reference_image = paths.sfm / "reference.png";
  std::error_code ec;
  if (fs::exists(reference_image, ec)) in.reference_image = ReadImage(reference_image);
  if (!in.reference_image.empty() &&
      (in.reference_image.cols != ref->width || in.reference_image.rows != ref->height))
    throw SizeMismatch(reference_image.string() + ": ", in.reference_image.cols,
                       in.reference_image.rows, " pixels", *ref);
  if (view_masks && fs::is_directory(paths.boundary))
    in.other_views = ReadOtherViewPages(cameras, paths.sfm / "cameras.json", paths.boundary);
  return in;
}

Json LinesJson(const std::vector<LineRecord>& lines, const Json& options_record,
               const std::optional<Eigen::Vector2d>& text_down_flat) {
  Json doc = MakeHeader("docunfold.lines", 1, "optimize", options_record);
  doc["description"] =
      "Feature lines straightened in M': n.p' = offset with n = normal; markers in "
      "reference-image pixels and in M' (same length unit as M).";
  doc["lines"] = Json::array();
  for (const LineRecord& l : lines) {
    Json j = {{"kind", l.kind},
              {"segments", l.segments},
              {"normal", {std::cos(l.line.theta), std::sin(l.line.theta)}},
              {"offset", l.line.offset},
              {"markers", l.pixels.size()},
              {"pixels", Points(l.pixels)},
              {"flat", Points(l.flat)}};
    if (l.side >= 0) j["side"] = kSideNames[l.side];
    doc["lines"].push_back(j);
  }
  if (text_down_flat) doc["text_down_flat"] = {text_down_flat->x(), text_down_flat->y()};
  return doc;
}

Json LogJson(const OptimizeResult& result, const Json& options_record) {
  Json doc = MakeHeader("docunfold.optimize-log", 1, "optimize", options_record);
  doc["segments"] = result.segments;
  doc["segments_off_page"] = result.segments_off_page;
  doc["line_direction"] = {{"angle_deg", result.line_direction.angle_deg},
                           {"share", result.line_direction.share},
                           {"segments", result.line_direction.lines},
                           {"turned_deg", result.upright_turn_deg}};
  doc["boundary_lines"] = result.boundary_lines;
  doc["mask_hull"] = Json::array();
  for (const HullViewCheck& c : result.hull_views)
    doc["mask_hull"].push_back({{"image", c.image},
                                {"points_seen", c.points_seen},
                                {"points_outside", c.points_outside},
                                {"used", c.used}});
  doc["points_in_region"] = result.region_points.size();
  doc["seconds"] = result.seconds;
  doc["rounds"] = Json::array();
  for (const RoundResult& r : result.rounds) {
    Json solver = isometry::ToJson(r.report);
    Json iterations = solver["iterations"];
    solver.erase("iterations");
    // Wall time since optimize started, so rounds line up on one time axis.
    for (Json& it : iterations) it["seconds"] = it["seconds"].get<double>() + r.start_seconds;
    doc["rounds"].push_back({{"round", r.round},
                             {"grid", {r.meshes.grid.nx, r.meshes.grid.ny}},
                             {"weights", WeightsJson(r.weights)},
                             {"stop_reason", r.report.stop_reason},
                             {"solver", solver},
                             {"lines", r.lines.size()},
                             {"side_markers_dropped", r.side_markers_dropped},
                             {"hull_markers", r.hull_markers},
                             {"crease_triplets", r.crease_triplets},
                             {"iterations", iterations}});
  }
  return doc;
}

void WriteOutputs(const fs::path& out, const InputPaths& paths, const OptimizeInputs& in,
                  const OptimizeResult& result, const Json& options_record,
                  const OutputOptions& output_options) {
  EnsureDirectory(out);
  const fs::path reference_image = paths.sfm / "reference.png";
  MeshPairWriteOptions mesh_options;
  mesh_options.reference_camera = in.reference;
  mesh_options.reference_image = reference_image;
  for (const RoundResult& r : result.rounds) {
    const fs::path dir = out / ("round" + std::to_string(r.round));
    MeshPairWriteOptions o = mesh_options;
    o.comments = {"docunfold optimize round " + std::to_string(r.round)};
    WriteMeshPair(dir, r.meshes, o);
    WriteJsonAtomic(dir / "lines.json", LinesJson(r.lines, options_record));
  }
  // Rounds of an earlier run with more rounds would mislead.
  std::error_code ec;
  for (int r = int(result.rounds.size());; ++r) {
    const fs::path stale = out / ("round" + std::to_string(r));
    if (!fs::exists(stale, ec)) break;
    fs::remove_all(stale, ec);
  }
  mesh_options.comments = {"docunfold optimize: final meshes"};
  WriteMeshPair(out, result.meshes, mesh_options);
  WriteJsonAtomic(out / "lines.json",
                  LinesJson(result.rounds.back().lines, options_record, result.text_down_flat));
  WriteJsonAtomic(out / "log.json", LogJson(result, options_record));
  if (!output_options.scene) return;

  // scene.glb: M textured from the reference image, M' beside it with the
  // same texture (the rectified page), and the SfM points M was fitted to.
  cv::Mat texture = in.reference_image.empty() ? ReadImage(reference_image) : in.reference_image;
  const double shrink = std::min(1.0, double(output_options.texture_width) / texture.cols);
  if (shrink < 1) cv::resize(texture, texture, cv::Size(), shrink, shrink, cv::INTER_AREA);
  GltfMesh m3, m2;
  m3.name = "M (page in 3D)";
  m2.name = "M' (flat page)";
  m3.texture = m2.texture = texture;
  m3.triangles = m2.triangles = result.meshes.grid.Triangles();
  Eigen::Vector3d lo3 = result.meshes.mesh3d[0], hi3 = lo3;
  for (const auto& v : result.meshes.mesh3d) {
    lo3 = lo3.cwiseMin(v);
    hi3 = hi3.cwiseMax(v);
  }
  Eigen::Vector2d lo2 = result.meshes.mesh2d[0];
  for (const auto& v : result.meshes.mesh2d) lo2 = lo2.cwiseMin(v);
  const double gap = 0.1 * (hi3 - lo3).norm();
  for (size_t i = 0; i < result.meshes.mesh3d.size(); ++i) {
    const Eigen::Vector2d px = in.reference.Project(result.meshes.mesh3d[i]);
    const Eigen::Vector2d uv((px.x() + 0.5) / in.reference.width,
                             (px.y() + 0.5) / in.reference.height);
    m3.positions.push_back(result.meshes.mesh3d[i]);
    m3.texcoords.push_back(uv);
    const Eigen::Vector2d f = result.meshes.mesh2d[i] - lo2;
    m2.positions.emplace_back(hi3.x() + gap + f.x(), lo3.y() + f.y(), (lo3.z() + hi3.z()) / 2);
    m2.texcoords.push_back(uv);
  }
  GltfPoints cloud;
  cloud.name = "SfM points (inliers)";
  for (size_t k = 0; k < result.region_points.size(); ++k) {
    if (k < result.inliers.size() && !result.inliers[k]) continue;
    const size_t i = size_t(result.region_points[k]);  // into in.points
    cloud.positions.push_back(in.points[i]);
    if (!in.point_colors.empty())
      cloud.colors.emplace_back(in.point_colors[i][0] / 255.f, in.point_colors[i][1] / 255.f,
                                in.point_colors[i][2] / 255.f);
  }
  WriteGlb(out / "scene.glb", {m3, m2}, {cloud});
}

}  // namespace docunfold::optimize
