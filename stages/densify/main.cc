// densify --data DATA --sfm 10_sfm/ --boundary 20_boundary/ --out 25_points/
// Writes points.ply, points.json and overlay.png (see densify.h).
#include "common/cli.h"
#include "stages/densify/densify.h"

using namespace docunfold;

int main(int argc, char** argv) {
  CLI::App app{
      "Adds 3D points of the page to sfm's sparse cloud, cameras held fixed: "
      "text and print followed from the reference view into the other photos by "
      "optical flow, and the page's outline and the shading steps of its blank paper "
      "(a fold's crease) matched along epipolar lines. Writes "
      "points.ply (sfm's points first), points.json and overlay.png."};
  densify::DensifyOptions o;
  bool no_texture = false, no_outline = false, keep_hidden = false;
  app.add_option("--data", o.data_dir, "data set folder (its images/ are read)")->required();
  app.add_option("--sfm", o.sfm_dir, "sfm output: cameras.json, points.ply, reference.png")
      ->required();
  app.add_option("--boundary", o.boundary, "segment-boundary output: boundary.json, mask.png")
      ->required();
  app.add_option("--out", o.out_dir, "output directory (e.g. 25_points)")->required();
  app.add_option("--max-image-size", o.max_image_size,
                 "long side of the working copies of the photos (pixels)")
      ->capture_default_str()
      ->check(CLI::Range(64, 100000));
  app.add_option("--region-margin-px", o.region_margin_px,
                 "document region (mask.png) grown by this many pixels")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  app.add_flag("--no-texture", no_texture, "no texture points");
  app.add_option("--texture-step", o.texture.step_px,
                 "texture: grid spacing in working-copy pixels")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1000.0));
  app.add_option("--min-texture", o.texture.min_texture,
                 "texture: skip pixels whose structure-tensor minimum eigenvalue is below "
                 "this fraction of the region's 95th percentile")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--texture-min-views", o.texture.min_views,
                 "texture: photos a point needs, the reference included")
      ->capture_default_str()
      ->check(CLI::Range(2, 1000));
  app.add_flag("--surface-prewarp,!--no-surface-prewarp", o.texture.surface_prewarp,
               "texture: a second pass for the samples the first left without a point, the "
               "photos brought onto the reference through the surface of the points found "
               "first instead of the page's homography (the far side of a fold); on by "
               "default, --no-surface-prewarp turns it off");
  app.add_option("--surface-hole-px", o.texture.surface_hole_px,
                 "texture, second pass: only samples at least this far from every point the "
                 "first pass made (working-copy pixels; 0 = every sample it left)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10000.0));
  app.add_option("--surface-grid", o.texture.surface_grid_px,
                 "texture, second pass: the surface's depth is fitted every this many "
                 "working-copy pixels and interpolated in between")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 100.0));
  app.add_flag("--no-outline", no_outline, "no outline points");
  app.add_option("--outline-step", o.outline.step_px,
                 "outline: spacing of the samples along the real sides (working-copy pixels)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1000.0));
  app.add_option("--outline-min-views", o.outline.min_views,
                 "outline: photos that must agree on a point, the reference included")
      ->capture_default_str()
      ->check(CLI::Range(2, 1000));
  app.add_option("--outline-agree-px", o.outline.agree_px,
                 "outline: other photos agree when their edge is within this distance")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 100.0));

  bool no_steps = false, supported_only = false;
  app.add_flag("--no-steps", no_steps,
               "no shading-step points (steps of blank paper such as a fold's crease, matched "
               "on copies blurred so that print is gone)");
  app.add_option("--step-blur", o.steps.blur_px,
                 "steps: Gaussian sigma of the blurred copies (working-copy pixels)")
      ->capture_default_str()
      ->check(CLI::Range(0.5, 50.0));
  app.add_option("--step-min-contrast", o.steps.min_contrast,
                 "steps: grey levels per pixel across a step on the blurred copy")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 255.0));
  app.add_option("--step-min-views", o.steps.min_views,
                 "steps: photos that must agree on a point, the reference included")
      ->capture_default_str()
      ->check(CLI::Range(2, 1000));
  app.add_option("--step-point-gap", o.steps.min_point_gap_px,
                 "steps: only where no point is this close already, blank paper (working-copy "
                 "pixels; 0 = in print too)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10000.0));
  app.add_option("--step-max-depth-jump", o.steps.max_depth_jump,
                 "steps: a point's depth may differ this much (fraction) from the surface of "
                 "the points on either side of its step")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--step-min-side-cos", o.steps.min_side_cos,
                 "steps: refused where the surface on either side is seen this edge-on from the "
                 "reference (|cos| between ray and normal)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_flag("--step-supported-only", supported_only,
               "steps: drop points with no known points on either side to check them against");
  app.add_option("--step-unsupported-radius", o.steps.unsupported_radius_factor,
                 "steps: points without known points next to them are checked against those "
                 "within this many times the side radius")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 100.0));
  app.add_option("--step-side-radius", o.steps.side_radius_px,
                 "steps: a point must lie on the surface of the known points within this "
                 "radius on each side of its step (working-copy pixels)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 10000.0));

  app.add_flag("--keep-hidden", keep_hidden,
               "keep sfm points of the document region that the reference view shows in "
               "another colour (by default they are left out as behind the page)");
  app.add_option("--hidden-colour-distance", o.hidden.max_colour_distance,
                 "hidden: colour difference (CIE76, OpenCV 8-bit Lab) beyond which an sfm point "
                 "is not what the reference view shows")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 500.0));

  return RunStage("densify", app, argc, argv, [&] {
    o.texture.enabled = !no_texture;
    o.outline.enabled = !no_outline;
    o.steps.enabled = !no_steps;
    if (supported_only) o.steps.unsupported = false;
    o.hidden.enabled = !keep_hidden;
    const densify::DensifyInputs in = densify::ReadInputs(o);
    const densify::DensifyResult r = densify::Run(in, o);
    densify::WriteOutputs(in, r, o);
    for (const std::string& w : r.warnings) Log("warning: " + w);
    Log("wrote " + (o.out_dir / "points.ply").string() + ": " +
        std::to_string(r.sfm_points - int(r.hidden.size())) + " sfm (" +
        std::to_string(r.hidden.size()) + " hidden behind the page left out) + " +
        std::to_string(r.texture_points) + " texture + " + std::to_string(r.outline.points) +
        " outline" + (o.steps.enabled ? " + " + std::to_string(r.steps.points) + " step" : "") +
        " points, " + std::to_string(r.seconds_total).substr(0, 4) + " s");
  });
}
