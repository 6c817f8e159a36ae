// synth: makes a data set of photos of a creased page with ground truth.
#include "common/cli.h"
#include "stages/synth/synth.h"

namespace {

// The command as typed, quoted where a shell would need it.
std::string TypedCommand(int argc, char** argv) {
  std::string line = "synth";
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    const bool plain = a.find_first_of(" '\"$\\") == std::string::npos && !a.empty();
    line += " " + (plain ? a : "'" + a + "'");
  }
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace docunfold;
  CommandLine command{
      "synth: photographs of a creased, folded or curled page with full ground truth.\n"
      "Writes <out>/images/view_NN.jpg and <out>/ground_truth/ (flat.png, text.txt, "
      "page.json, mesh.ply, cameras.json, features.json, synth.json) and <out>/COMMAND.\n"
      "Deterministic for a seed."};
  synth::SynthOptions o;
  command.RequiredPath("out", &o.out, "data-set folder to create");
  synth::DeclareOptions(command.table(), &o);
  return RunStage("synth", command, argc, argv, [&] {
    o.command_line = TypedCommand(argc, argv);
    const synth::SynthResult r = synth::Run(o, command.Record());
    Log("wrote " + o.out.string() + ": " + std::to_string(r.views) + " views, " +
        std::to_string(r.folds) + " folds, " + std::to_string(r.mesh_vertices) +
        " mesh vertices in " + Fixed(r.seconds, 1) + " s");
  });
}
