// render --sfm 10_sfm --boundary 20_boundary --meshes 50_optimize --out 60_render
// Texture-maps M' with the reference image through M and writes the cropped,
// rectified page: rectified.png, rectified_grid.png, render.json (render.h).
#include "common/cli.h"
#include "stages/render/render.h"

using namespace docunfold;

int main(int argc, char** argv) {
  LimitOpenMpThreads(argv);
  CommandLine command{
      "render: the flat, cropped page from the meshes M (mesh3d.ply) and M' "
      "(mesh2d.ply) and the reference image"};
  fs::path sfm, boundary, meshes, out, images, features;
  render::RenderOptions o;
  command.RequiredPath("sfm", &sfm, "sfm output folder (cameras.json, reference.png)");
  command.RequiredPath("boundary", &boundary, "segment-boundary output folder (boundary.json)");
  command.RequiredPath("meshes", &meshes,
                       "folder with mesh3d.ply and mesh2d.ply (50_optimize or 40_init)");
  command.RequiredPath("out", &out,
                       "output folder: rectified.png, rectified_grid.png, render.json");
  command.Path("features", &features,
               "features.json (30_features/): when Tesseract cannot tell which way up the page is "
               "and the meshes have no lines.json beside them (init-mesh's), the side the text's "
               "baselines lie on decides");
  command.Path("images", &images,
               "the photos (<data>/images): the page found past a cut side is textured from the "
               "other views that see it (without: the fill colour)");
  render::DeclareOptions(command.table(), &o);

  return RunStage("render", command, argc, argv, [&] {
    StepTimer timer;
    const render::RenderInputs in =
        render::ReadRenderInputs(sfm, boundary, meshes, images, features);
    const double read_s = timer.Mark("read");
    const render::RenderResult result = render::Run(o, in);
    timer.Mark("render");
    for (const std::string& warning : result.warnings) Log("warning: " + warning);
    Json report = render::RenderReport(o, in, result, command.Record());
    report["timing_s"]["read"] = read_s;
    render::WriteRenderOutputs(out, result, report);
    const double write_s = timer.Mark("write");
    Log("wrote " + (out / "rectified.png").string() + " " + std::to_string(result.rectified.cols) +
        "x" + std::to_string(result.rectified.rows) + " (crop " + result.crop_rule + ", size " +
        result.size_rule + ", rotation " + Fixed(result.rotation_deg, 3) + " deg) in " +
        Fixed(timer.Total(), 2) + " s (read " + Fixed(read_s, 2) + " s, write " +
        Fixed(write_s, 2) + " s)");
  });
}
