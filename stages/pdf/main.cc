// pdf --render 60_render --out 80_pdf [--name set01]
// The rectified page as a searchable PDF at its paper size, with ALTO XML,
// hOCR and pdf.json beside it (pdf.h).
#include "common/cli.h"
#include "stages/pdf/pdf.h"

using namespace docunfold;

int main(int argc, char** argv) {
  LimitOpenMpThreads(argv);
  CommandLine command{
      "pdf: the rectified page as a searchable PDF at its paper size (ISO A3-A6, Letter, "
      "Legal or a receipt roll when the page's shape matches one, else the image at --dpi), "
      "with an invisible text layer on the words Tesseract reads, and ALTO XML, hOCR and "
      "pdf.json beside it"};
  fs::path render, out;
  std::string name;
  pdf::PdfOptions o;
  command.RequiredPath("render", &render, "render output folder (rectified.png, render.json)");
  command.RequiredPath("out", &out,
                       "output folder: <name>.pdf, <name>.alto.xml, <name>.hocr, the page image "
                       "<name>.jpg (.tif for black-white) and pdf.json");
  command.Text("name", &name,
               "file name of the outputs (default: the work directory's, the folder above "
               "--render)");
  pdf::DeclareOptions(command.table(), &o);

  return RunStage("pdf", command, argc, argv, [&] {
    StepTimer timer;
    const pdf::PdfInputs in = pdf::ReadPdfInputs(render);
    if (name.empty())
      name = fs::absolute(render).lexically_normal().parent_path().filename().string();
    if (name.empty() || name == "." || name == "..") name = "page";
    if (name.find('/') != std::string::npos)
      throw UsageError("--name " + name + ": a file name, without '/'");
    const pdf::PdfResult r = pdf::Run(o, in, out, name, command.Record());
    Log("wrote " + r.pdf_file.string() + " (" + std::to_string(r.pdf_bytes / 1024) + " KB, " +
        (r.size.format == "none" ? std::string("no standard format") : r.size.format) + " " +
        Fixed(r.size.width_mm, 1) + " x " + Fixed(r.size.height_mm, 1) + " mm at " +
        Fixed((r.size.dpi_x + r.size.dpi_y) / 2, 0) + " dpi, " + std::to_string(r.words.size()) +
        " words, mean confidence " + Fixed(r.mean_confidence, 2) + ") in " +
        Fixed(timer.Total(), 2) + " s");
  });
}
