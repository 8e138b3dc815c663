// contact-sheet: tiles images into one PNG with a caption over each (for docs and quick looks).
#include <filesystem>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binloop/io/kitti_sequence.h"
#include "binloop/util/cli_args.h"

int main(int argc, char** argv) {
  binloop::CliArgs args("contact-sheet",
                        "contact-sheet --out sheet.png --image <path>:<caption> ... [options]");
  args.option("out", "PNG to write")
      .option("image", "an image and its caption, 'path:caption' (repeat; shown in order)")
      .option("columns", "images per row", "2")
      .option("scale", "scale of each image", "0.5");
  return binloop::runTool("contact-sheet", [&] {
    if (!args.parse(argc, argv)) return 0;
    const auto items = args.all("image");
    if (items.empty() || !args.has("out"))
      throw binloop::CliError("--out and at least one --image are needed");
    const int cols = static_cast<int>(args.integer("columns"));
    const double scale = args.number("scale");
    std::vector<cv::Mat> tiles;
    for (const auto& item : items) {
      // The caption may hold colons too: split at the first colon that ends an existing file's path.
      std::string path = item, caption;
      for (auto colon = item.find(':'); colon != std::string::npos; colon = item.find(':', colon + 1))
        if (std::filesystem::is_regular_file(item.substr(0, colon))) {
          path = item.substr(0, colon);
          caption = item.substr(colon + 1);
          break;
        }
      cv::Mat img = binloop::readGrayImage(path), small;
      cv::resize(img, small, cv::Size(), scale, scale, cv::INTER_AREA);
      cv::cvtColor(small, small, cv::COLOR_GRAY2BGR);
      cv::rectangle(small, cv::Rect(0, 0, small.cols, 22), cv::Scalar(0, 0, 0), cv::FILLED);
      cv::putText(small, caption, {6, 16}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 1,
                  cv::LINE_AA);
      tiles.push_back(small);
    }
    const cv::Size sz = tiles[0].size();
    const int rows = (static_cast<int>(tiles.size()) + cols - 1) / cols;
    cv::Mat sheet(rows * (sz.height + 4), cols * (sz.width + 4), CV_8UC3, cv::Scalar(255, 255, 255));
    for (size_t i = 0; i < tiles.size(); ++i) {
      cv::Mat t;
      cv::resize(tiles[i], t, sz);
      t.copyTo(sheet(cv::Rect(static_cast<int>(i % cols) * (sz.width + 4),
                              static_cast<int>(i / cols) * (sz.height + 4), sz.width, sz.height)));
    }
    if (!cv::imwrite(args.str("out"), sheet)) throw std::runtime_error(args.str("out") + ": cannot write");
    std::cout << "contact-sheet: " << tiles.size() << " images -> " << args.str("out") << "\n";
    return 0;
  });
}
