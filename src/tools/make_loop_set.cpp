// make-loop-set: a real-image loop set (an image folder and its loop pairs) from a list of places; see
// include/binloop/eval/loop_set.h and docs/loop_models.md, "Real-image loop sets".
#include <filesystem>
#include <fstream>
#include <iostream>

#include "binloop/eval/loop_set.h"
#include "binloop/util/cli_args.h"

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  binloop::CliArgs args("make-loop-set",
                        "make-loop-set --list <places.txt> --out <dir> [--seed N] [--shared <dir>]");
  args.option("list", "places, one per line: '<name> <image A> [<image B> | = | -]'")
      .option("out", "folder for the frames (NNNNNN.png), loops.txt and frames.txt")
      .option("shared", "what $SHARED stands for in the list", "../shared/data")
      .option("seed", "seed of the revisit order and the synthetic second views", "1");
  return binloop::runTool("make-loop-set", [&] {
    if (!args.parse(argc, argv)) return 0;
    if (!args.has("list") || !args.has("out")) throw binloop::CliError("--list and --out are required");
    const auto places = binloop::readLoopSetList(args.str("list"), args.str("shared"));
    const fs::path out = args.str("out");
    if (fs::exists(out)) fs::remove_all(out);
    const auto set = binloop::makeLoopSet(places, out.string(), static_cast<uint64_t>(args.integer("seed")));
    std::ofstream loops(out / "loops.txt"), frames(out / "frames.txt");
    loops << "# query ref: every revisit frame with every first-visit frame of its place ("
          << args.str("list") << ")\n";
    for (const auto& [q, r] : set.loops) loops << q << " " << r << "\n";
    frames << "# frame place revisit source\n";
    for (size_t i = 0; i < set.frames.size(); ++i)
      frames << i << " " << set.frames[i].place << " " << set.frames[i].revisit << " " << set.frames[i].source
             << "\n";
    std::cout << "make-loop-set: " << places.size() << " places, " << set.frames.size() << " frames, "
              << set.loops.size() << " loop pairs -> " << out.string() << "\n";
    return 0;
  });
}
