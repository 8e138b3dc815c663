#include "binloop/features/image_features.h"

#include <atomic>
#include <exception>
#include <filesystem>
#include <mutex>
#include <thread>

#include <opencv2/imgproc.hpp>

#include "binloop/io/data_error.h"
#include "binloop/io/filesystem.h"
#include "binloop/io/kitti_sequence.h"

namespace binloop {

std::vector<std::string> listImages(const std::string& dir) {
  requireDirectory(dir);
  const std::string left = (std::filesystem::path(dir) / "image_0").string();
  const std::string from = std::filesystem::is_directory(left) ? left : dir;
  auto files = listFilesNatural(from, {".png", ".jpg", ".jpeg", ".PNG", ".JPG", ".JPEG"});
  if (files.empty()) throw dataError(from, 0, "holds no png or jpg images");
  return files;
}

ExtractorSettings extractorSettings(const ExtractOptions& o) { return extractorSettings(o.orb, o.max_side); }

std::vector<Descriptors> extractDescriptors(const std::vector<std::string>& paths, const ExtractOptions& o,
                                            const ProgressFn& progress) {
  const OrbSlamExtractor extractor(o.orb);  // checks the settings before any image is read; thread-safe
  std::vector<Descriptors> out(paths.size());
  std::atomic<size_t> next{0}, done{0};
  std::exception_ptr error;
  std::mutex m;
  auto work = [&] {
    for (size_t i; (i = next++) < paths.size();) {
      try {
        cv::Mat img = readGrayImage(paths[i]);
        const int side = std::max(img.cols, img.rows);
        if (o.max_side > 0 && side > o.max_side) {
          const double s = double(o.max_side) / side;
          cv::resize(img, img, cv::Size(), s, s, cv::INTER_AREA);
        }
        out[i] = extractor.extract(img).descriptors;
      } catch (const DataError& e) {
        std::lock_guard<std::mutex> l(m);
        if (o.skip_unreadable) {
          if (o.skipped) o.skipped->push_back(e.what());
        } else if (!error) {
          error = std::current_exception();
          next = paths.size();
        }
      } catch (...) {
        std::lock_guard<std::mutex> l(m);
        if (!error) error = std::current_exception();
        next = paths.size();
      }
      const size_t d = ++done;
      if (progress) {
        std::lock_guard<std::mutex> l(m);
        progress(d, paths.size());
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, o.threads); ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  return out;
}

}  // namespace binloop
