// catgraph import LAYOUT SOURCE -o DIR: a recording in one of the layouts of
// simulation/dataset_import.h as a catgraph dataset (docs/import.md).
#include <memory>
#include <string>

#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "backend/io/output_directory.h"
#include "simulation/dataset_import.h"

namespace catgraph {

void AddImportCommand(CLI::App& app, std::ostream& out) {
  struct Options {
    std::string layout, source, output;
    std::string times, odometry, poses;
    ImportOptions import;
    bool quiet = false, overwrite = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "import",
      "Turn your own recording into a catgraph dataset: an image folder with an odometry or pose CSV, the "
      "KITTI odometry layout, or the TUM RGB-D layout. Odometry made from poses where the recording has none, "
      "said so in meta.json. docs/import.md.");
  cmd->add_option("layout", o->layout, "folder, kitti or tum")
      ->required()
      ->check(CLI::IsMember(ImportLayoutNames(), CLI::ignore_case));
  cmd->add_option("source", o->source,
                  "The image folder (folder), the sequence folder with image_0/ and times.txt (kitti), or the "
                  "folder with rgb.txt and groundtruth.txt (tum)")
      ->required();
  cmd->add_option("-o,--output", o->output, "Dataset directory to write")->required();
  cmd->add_option("--times", o->times,
                  "folder: one timestamp (s) per image in file-name order (default: the file names are the "
                  "timestamps, in s or ns)");
  cmd->add_option("--odometry", o->odometry, "folder: odometry CSV (timestamp,x,y,theta)");
  cmd->add_option("--poses", o->poses,
                  "folder: ground-truth pose CSV (timestamp,x,y,theta); kitti: the poses file (poses/NN.txt)");
  cmd->add_option("--traversal-gap", o->import.traversal_gap_s,
                  "A gap between frames longer than this (s) starts a new traversal")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--seed", o->import.seed, "Noise seed of odometry made from poses")->capture_default_str();
  cmd->add_flag("--quiet", o->quiet, "No progress bar");
  AddOverwriteFlag(*cmd, o->overwrite);
  cmd->callback([o, &out] {
    std::string layout = o->layout;
    for (char& c : layout) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const ImportLayout kind = *ImportLayoutFromString(layout);
    o->import.times = o->times;
    o->import.odometry = o->odometry;
    o->import.poses = o->poses;
    auto bar = std::make_shared<ProgressBar>("images");
    if (!o->quiet) o->import.on_progress = [bar](std::size_t done, std::size_t total) { bar->Update(done, total); };
    std::vector<std::filesystem::path> inputs = {o->source};
    for (const std::string* f : {&o->times, &o->odometry, &o->poses}) {
      if (!f->empty()) inputs.emplace_back(*f);
    }
    OutputDirectory output(o->output, "import", o->overwrite, inputs);
    const ImportSummary s = ImportDataset(kind, o->source, output.path(), o->import);
    output.Commit();
    out << "wrote " << o->output << ": " << s.frames << " frames in " << s.traversals
        << (s.traversals == 1 ? " traversal" : " traversals");
    if (s.left_out > 0) out << " (" << s.left_out << " outside the odometry's or the poses' time range left out)";
    out << "; odometry " << (s.synthetic_odometry ? "made from the poses (meta.json)" : "from the recording")
        << ", " << (s.ground_truth ? "ground truth from the poses" : "no ground truth") << "\n";
  });
}

}  // namespace catgraph
