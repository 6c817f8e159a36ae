// densify's inputs and outputs: reading and checking 10_sfm, 20_boundary and
// the photos; writing points.ply, points.json and overlay.png.
#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/atomic_file.h"
#include "common/errors.h"
#include "stages/densify/densify.h"

namespace docunfold::densify {

DensifyInputs ReadInputs(const DensifyOptions& o) {
  DensifyInputs in;
  const fs::path cameras_path = o.sfm_dir / "cameras.json";
  in.cameras = ReadCameras(cameras_path);
  const PinholeCamera* ref = in.cameras.Find(in.cameras.reference);
  if (!ref) throw InputError(cameras_path.string() + ": no reference view (not written by sfm?)");
  {
    const Json doc = ReadJsonFile(cameras_path);
    const JsonReader r(doc, cameras_path);
    for (size_t i = 0; i < in.cameras.views.size(); ++i)
      in.distortion.push_back(ReadDistortion(r, "/views/" + std::to_string(i)));
  }
  in.reference = ReadImage(o.sfm_dir / "reference.png", cv::IMREAD_COLOR);
  if (in.reference.cols != ref->width || in.reference.rows != ref->height)
    throw InputError((o.sfm_dir / "reference.png").string() + ": " +
                     std::to_string(in.reference.cols) + "x" + std::to_string(in.reference.rows) +
                     " differs from the reference camera's " + std::to_string(ref->width) + "x" +
                     std::to_string(ref->height));
  const fs::path images = o.data_dir / "images";
  for (const PinholeCamera& view : in.cameras.views) {
    if (view.image == in.cameras.reference) {
      in.photos.emplace_back();
      continue;
    }
    in.photos.push_back(ReadViewPhoto(images / view.image, view, cameras_path, PhotoColor::kGray));
  }
  const fs::path boundary_file =
      fs::is_directory(o.boundary) ? o.boundary / "boundary.json" : o.boundary;
  in.boundary = ReadBoundary(boundary_file);
  in.region = ReadDocumentMask(boundary_file.parent_path() / "mask.png", ref->width, ref->height);
  in.points = ReadPly(o.sfm_dir / "points.ply");
  if (in.points.vertices.empty())
    throw InputError((o.sfm_dir / "points.ply").string() + ": no points");
  return in;
}

namespace {

// The reference image dimmed, the points by source, the hidden ones as red
// crosses, and a legend (without the passes `options` turns off).
cv::Mat DrawOverlay(const DensifyInputs& in, const DensifyResult& r,
                    const DensifyOptions& options) {
  cv::Mat overlay = in.reference * 0.55;
  const PinholeCamera& ref = *in.cameras.Find(in.cameras.reference);
  const double radius_scale = std::max(1.0, std::max(ref.width, ref.height) / 1600.0);
  // By PointSource: sfm, texture, outline, step, swept.
  const cv::Scalar colours[kPointSourceCount] = {cv::Scalar(255, 200, 0), cv::Scalar(80, 220, 80),
                                                 cv::Scalar(255, 0, 255), cv::Scalar(0, 230, 255),
                                                 cv::Scalar(0, 140, 255)};
  const std::vector<double>& source = r.points.properties[2].values;
  for (int pass = 0; pass < kPointSourceCount; ++pass)
    for (size_t i = 0; i < r.points.vertices.size(); ++i) {
      if (int(source[i]) != pass) continue;
      const Eigen::Vector3d xc = ref.CamFromWorld(r.points.vertices[i]);
      if (!(xc.z() > 0)) continue;
      const Eigen::Vector2d p = ref.ProjectCam(xc);
      if (p.x() < 0 || p.y() < 0 || p.x() >= ref.width || p.y() >= ref.height) continue;
      cv::circle(overlay, cv::Point(int(std::lround(p.x())), int(std::lround(p.y()))),
                 int(std::lround(radius_scale * (pass == int(PointSource::kOutline) ? 3 : 2))),
                 colours[pass], -1, cv::LINE_AA);
    }
  // Left out as hidden behind the page: red crosses.
  const cv::Scalar hidden_colour(0, 0, 255);
  const int arm = int(std::lround(4 * radius_scale));
  for (const Eigen::Vector3d& X : r.hidden) {
    const Eigen::Vector3d xc = ref.CamFromWorld(X);
    if (!(xc.z() > 0)) continue;
    const Eigen::Vector2d p = ref.ProjectCam(xc);
    const cv::Point c(int(std::lround(p.x())), int(std::lround(p.y())));
    cv::line(overlay, c - cv::Point(arm, arm), c + cv::Point(arm, arm), hidden_colour,
             int(std::lround(radius_scale)), cv::LINE_AA);
    cv::line(overlay, c - cv::Point(arm, -arm), c + cv::Point(arm, -arm), hidden_colour,
             int(std::lround(radius_scale)), cv::LINE_AA);
  }
  const double font = 0.8 * radius_scale;
  const int thick = int(std::lround(2 * radius_scale));
  const int sfm_kept = r.sfm_points_in_region - int(r.hidden.size());
  const std::string legend[6] = {"sfm " + std::to_string(sfm_kept),
                                 "texture " + std::to_string(r.texture_points),
                                 "outline " + std::to_string(r.outline.points),
                                 "shading steps " + std::to_string(r.steps.points),
                                 "swept " + std::to_string(r.sweep.points),
                                 "hidden (left out) " + std::to_string(r.hidden.size())};
  const cv::Scalar legend_colours[6] = {colours[0], colours[1], colours[2],
                                        colours[3], colours[4], hidden_colour};
  for (int i = 0, row = 0; i < 6; ++i) {
    if (i == int(PointSource::kStep) && !options.steps.enabled) continue;
    if (i == int(PointSource::kSwept) && !options.sweep.enabled) continue;
    cv::putText(overlay, legend[i],
                cv::Point(int(20 * radius_scale), int((40 + 34 * row++) * radius_scale)),
                cv::FONT_HERSHEY_SIMPLEX, font, legend_colours[i], thick, cv::LINE_AA);
  }
  return overlay;
}

Json CountsJson(const EdgeCounts& c) {
  return {{"samples", c.samples},
          {"unmatched", c.unmatched},
          {"ambiguous", c.ambiguous},
          {"off_surface", c.off_surface}};
}

// The points.json document.
Json PointsJson(const DensifyInputs& in, const DensifyResult& r, const Json& options_record) {
  Json doc = MakeHeader("docunfold.points", 1, "densify", options_record);
  doc["reference"] = in.cameras.reference;
  doc["working_scale"] = r.working_scale;
  doc["points"] = {{"sfm", r.sfm_points},
                   {"sfm_in_region", r.sfm_points_in_region},
                   {"sfm_hidden", r.hidden.size()},
                   {"texture", r.texture_points},
                   {"texture_surface_prewarp", r.texture_points_surface},
                   {"outline", r.outline.points},
                   {"steps", r.steps.points},
                   {"swept", r.sweep.points},
                   {"total", r.points.vertices.size()}};
  doc["texture"] = {{"samples", r.texture_samples}};
  doc["outline"] = CountsJson(r.outline);
  doc["outline"]["side_line_points"] = r.outline.side_line_points;
  doc["outline"]["side_line_weak"] = r.outline.side_line_weak;
  doc["steps"] = CountsJson(r.steps);
  doc["sweep"] = {{"candidates", r.sweep.candidates}};
  doc["views"] = Json::array();
  for (const ViewStats& v : r.views)
    doc["views"].push_back({{"image", v.image},
                            {"page_points", v.page_points},
                            {"flow_matches", v.flow_matches},
                            {"surface_flow_matches", v.surface_flow_matches},
                            {"outline_candidates", v.outline_candidates},
                            {"outline_votes", v.outline_votes}});
  doc["warnings"] = r.warnings;
  doc["seconds"] = {{"reading", r.seconds_reading}, {"texture", r.seconds_texture},
                    {"outline", r.seconds_outline}, {"texture_surface_prewarp", r.seconds_surface},
                    {"steps", r.seconds_steps},     {"sweep", r.seconds_sweep},
                    {"total", r.seconds_total}};
  return doc;
}

}  // namespace

void WriteOutputs(const DensifyInputs& in, const DensifyResult& r, const DensifyOptions& o,
                  const Json& options_record) {
  EnsureDirectory(o.out_dir);
  WritePly(o.out_dir / "points.ply", r.points);
  WriteImageAtomic(o.out_dir / "overlay.png", DrawOverlay(in, r, o),
                   {cv::IMWRITE_PNG_COMPRESSION, 1});
  WriteJsonAtomic(o.out_dir / "points.json", PointsJson(in, r, options_record));
}

}  // namespace docunfold::densify
