// synth: makes a data set of photos of a creased page with ground truth.
#include <cstdio>

#include "common/cli.h"
#include "stages/synth/synth.h"

int main(int argc, char** argv) {
  using namespace docunfold;
  synth::SynthOptions o;
  std::string kind = "text", background = "plain";
  std::string size;
  CLI::App app{
      "synth: photographs of a creased, folded or curled page with full ground truth.\n"
      "Writes <out>/images/view_NN.jpg and <out>/ground_truth/ (flat.png, text.txt, "
      "page.json, mesh.ply, cameras.json, features.json, synth.json) and <out>/COMMAND.\n"
      "Deterministic for a seed."};
  app.add_option("--out", o.out, "data-set folder to create")->required();
  app.add_flag("--force", o.force, "replace an existing folder");
  app.add_option("--seed", o.seed, "random seed")->capture_default_str();
  app.add_option("--kind", kind, "page: text, table, receipt or poster")->capture_default_str();
  app.add_option("--page-size", size, "page size in mm, WxH (default: A4, receipt 80x200)");
  app.add_option("--creases", o.folds.creases, "number of narrow folds")->capture_default_str();
  app.add_option("--crease-width-mm", o.folds.crease_width_min,
                 "narrowest crease, mm (widest is --crease-width-max-mm)");
  app.add_option("--crease-width-max-mm", o.folds.crease_width_max, "widest crease, mm");
  app.add_option("--angle-min", o.folds.crease_angle_min, "smallest crease angle, degrees")
      ->capture_default_str();
  app.add_option("--angle-max", o.folds.crease_angle_max, "largest crease angle, degrees")
      ->capture_default_str();
  app.add_flag("--curl", o.folds.curl, "add one wide bend (a curl of several cm)");
  app.add_option("--views", o.cameras.views, "number of photos")->capture_default_str();
  app.add_option("--width", o.cameras.width, "image width, pixels")->capture_default_str();
  app.add_option("--height", o.cameras.height, "image height, pixels")->capture_default_str();
  app.add_option("--elevation-min", o.cameras.elevation_min_deg, "lowest camera elevation, deg")
      ->capture_default_str();
  app.add_option("--elevation-max", o.cameras.elevation_max_deg, "highest camera elevation, deg")
      ->capture_default_str();
  app.add_flag("--cut-off", o.cameras.cut_off,
               "frame every view so that part of the page is outside the image");
  app.add_option("--background", background, "table: plain, wood, cloth or granite")
      ->capture_default_str();
  app.add_option("--noise", o.render.noise_sigma, "sensor noise, grey levels")
      ->capture_default_str();
  app.add_option("--jpeg-quality", o.render.jpeg_quality, "JPEG quality")->capture_default_str();
  app.add_option("--flat-dpi", o.flat_dpi, "resolution of flat.png")->capture_default_str();
  app.add_option("--mesh-spacing-mm", o.mesh_spacing_m, "vertex spacing of mesh.ply, mm");
  return RunStage("synth", app, argc, argv, [&] {
    o.kind = synth::ParsePageKind(kind);
    o.render.background = synth::ParseBackground(background);
    // Options given in millimetres.
    if (app.count("--crease-width-mm")) o.folds.crease_width_min /= 1000;
    if (app.count("--crease-width-max-mm")) o.folds.crease_width_max /= 1000;
    if (app.count("--mesh-spacing-mm")) o.mesh_spacing_m /= 1000;
    if (o.folds.crease_width_max < o.folds.crease_width_min)
      o.folds.crease_width_max = o.folds.crease_width_min;
    if (!size.empty()) {
      double w = 0, h = 0;
      if (std::sscanf(size.c_str(), "%lfx%lf", &w, &h) != 2 || w <= 0 || h <= 0)
        throw UsageError("--page-size: expected WxH in millimetres, e.g. 210x297");
      o.page_width_m = w / 1000;
      o.page_height_m = h / 1000;
    }
    if (o.cameras.width < 64 || o.cameras.height < 64)
      throw UsageError("--width and --height must be at least 64 pixels");
    o.command_line = "synth";
    for (int i = 1; i < argc; ++i) {
      std::string a = argv[i];
      const bool plain = a.find_first_of(" '\"$\\") == std::string::npos && !a.empty();
      o.command_line += " " + (plain ? a : "'" + a + "'");
    }
    synth::SynthResult r = synth::Run(o);
    char buf[200];
    std::snprintf(buf, sizeof buf, "wrote %s: %d views, %d folds, %d mesh vertices in %.1f s",
                  o.out.c_str(), r.views, r.folds, r.mesh_vertices, r.seconds);
    Log(buf);
  });
}
