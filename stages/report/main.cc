// report: one self-contained HTML page showing every stage's output.
#include "common/atomic_file.h"
#include "common/cli.h"
#include "stages/report/report.h"

int main(int argc, char** argv) {
  using namespace docunfold;
  CommandLine command{
      "report: one HTML page with every stage's output for a data set (photos, reference "
      "view, boundary, feature segments, point cloud and meshes, convergence, the rectified "
      "page, metrics, stage times and flags). Self-contained: opens from disk, offline."};
  report::ReportOptions o;
  command.RequiredPath("data", &o.data, "data-set folder (images/, optional ground_truth/)");
  command.RequiredPath("work", &o.work, "its work directory");
  command.Path("out", &o.out, "HTML file to write (default <work>/report.html)");
  report::DeclareOptions(command.table(), &o);
  return RunStage("report", command, argc, argv, [&] {
    if (o.out.empty()) o.out = o.work / "report.html";
    report::ReportResult r = report::Run(o);
    WriteTextAtomic(o.out, r.html);
    Log("wrote " + o.out.string() + " (" + std::to_string(r.html.size() / 1024) + " KB)");
  });
}
