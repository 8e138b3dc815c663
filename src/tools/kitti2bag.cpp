// kitti2bag: a KITTI odometry sequence folder -> ROS 1 bag (see docs/tools.md).
#include <iostream>

#include "binloop/io/data_error.h"
#include "binloop/io/kitti_sequence.h"
#include "binloop/util/cli_args.h"
#include "binloop/util/progress_bar.h"
#include "binloop_ros/kitti_bag_writer.h"
#include "binloop_ros/topics.h"

int main(int argc, char** argv) {
  binloop::CliArgs args("kitti2bag", "kitti2bag <sequence_dir> <out.bag> [options]");
  args.positional("sequence_dir", "KITTI folder with image_0/, image_1/, calib.txt, times.txt")
      .positional("out.bag", "bag to write")
      .option("poses", "ground-truth poses (KITTI format); default <sequence_dir>/poses.txt if present")
      .option("start", "first frame", "0")
      .option("end", "last frame (inclusive); default the last one")
      .option("stamp-offset", "seconds added to times.txt (ROS time cannot be 0)", "1.0")
      .flag("lz4", "compress the bag with LZ4")
      .flag("png", "images as PNG CompressedImage on <topic>/compressed (play with transport:=compressed)")
      .flag("force", "overwrite an existing bag");
  return binloop::runTool("kitti2bag", [&] {
    if (!args.parse(argc, argv)) return 0;
    const auto seq = binloop::KittiSequence::open(args.str("sequence_dir"), args.str("poses"));
    binloop_ros::KittiBagOptions opt;
    opt.start = static_cast<size_t>(args.integer("start"));
    if (args.has("end")) opt.end = static_cast<size_t>(args.integer("end"));
    opt.stamp_offset_s = args.number("stamp-offset");
    opt.lz4 = args.has("lz4");
    opt.png = args.has("png");
    opt.overwrite = args.has("force");
    std::cout << "kitti2bag: " << seq.directory() << ": " << seq.size() << " frames, camera "
              << seq.camera().describe() << (seq.hasPoses() ? ", with ground truth" : ", no ground truth")
              << "\n";
    binloop::ProgressBar bar("kitti2bag");
    const auto summary = binloop_ros::writeKittiBag(
        seq, args.str("out.bag"), opt, [&](size_t done, size_t total) { bar.update(done, total); });
    bar.finish();
    namespace t = binloop_ros::topics;
    std::cout << "kitti2bag: wrote " << args.str("out.bag") << " (" << summary.bytes / 1e6 << " MB)\n"
              << "  " << summary.frames << " stereo frames, stamps " << std::fixed << summary.first_stamp
              << " .. " << summary.last_stamp << " s\n"
              << "  " << t::kLeftImage << ", " << t::kRightImage << " (mono8), " << t::kLeftInfo << ", "
              << t::kRightInfo << "\n";
    if (summary.ground_truth)
      std::cout << "  " << t::kGroundTruth << " (nav_msgs/Odometry, " << summary.ground_truth
                << " poses, frame '" << t::kGroundTruthFrame << "')\n";
    return 0;
  });
}
