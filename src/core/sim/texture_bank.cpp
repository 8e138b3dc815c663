#include "binloop/sim/texture_bank.h"

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binloop/util/hash_random.h"

namespace binloop::sim {

namespace {

constexpr int kSize = 512;

// Tileable multi-octave value noise in [0, 255].
cv::Mat valueNoise(int size, HashRng& rng, int base_cells, int octaves) {
  cv::Mat acc(size, size, CV_32F, cv::Scalar(0));
  float amp = 1, total = 0;
  for (int o = 0, cells = base_cells; o < octaves; ++o, cells *= 2, amp *= 0.55f) {
    cv::Mat grid(cells, cells, CV_32F);
    for (int i = 0; i < cells * cells; ++i) grid.at<float>(i) = static_cast<float>(rng.uniform());
    cv::Mat wrapped, up;
    cv::copyMakeBorder(grid, wrapped, 2, 2, 2, 2, cv::BORDER_WRAP);
    const float scale = static_cast<float>(size) / cells;
    cv::resize(wrapped, up, cv::Size(), scale, scale, cv::INTER_CUBIC);
    const int off = static_cast<int>(2 * scale);
    acc += amp * up(cv::Rect(off, off, size, size));
    total += amp;
  }
  acc = acc / total;
  cv::Mat out;
  cv::normalize(acc, out, 0, 255, cv::NORM_MINMAX, CV_8U);
  return out;
}

// Stretches to a given mean and spread so that every photo gives comparable contrast.
cv::Mat normalizeContrast(const cv::Mat& gray, double mean, double stddev) {
  cv::Scalar m, s;
  cv::meanStdDev(gray, m, s);
  cv::Mat out;
  gray.convertTo(out, CV_8U, stddev / std::max(1.0, s[0]), mean - m[0] * stddev / std::max(1.0, s[0]));
  return out;
}

cv::Mat randomCrop(const cv::Mat& photo, HashRng& rng, double min_frac, double max_frac) {
  const int side = std::min(photo.cols, photo.rows);
  const int c = std::max(16, static_cast<int>(side * rng.uniform(min_frac, max_frac)));
  const int x = rng.below(std::max(1, photo.cols - c + 1)), y = rng.below(std::max(1, photo.rows - c + 1));
  cv::Mat out;
  // INTER_AREA only when shrinking: enlarging with it copies pixels into blocks.
  cv::resize(photo(cv::Rect(x, y, std::min(c, photo.cols - x), std::min(c, photo.rows - y))), out,
             cv::Size(kSize, kSize), 0, 0, c >= kSize ? cv::INTER_AREA : cv::INTER_CUBIC);
  return out;
}

// Windows in a grid that tiles the texture: dark glass showing a dimmed copy of the wall, lighter frames.
void paintWindows(cv::Mat& wall, HashRng& rng) {
  const int nx = 3 + rng.below(3), ny = 3 + rng.below(3);
  const int cw = kSize / nx, ch = kSize / ny;
  const int ww = static_cast<int>(cw * rng.uniform(0.35, 0.7)),
            wh = static_cast<int>(ch * rng.uniform(0.4, 0.75));
  const int frame = 3 + rng.below(5);
  const double glass = rng.uniform(0.25, 0.55);
  const int frame_value = rng.chance(0.5) ? 210 : 50;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      if (rng.chance(0.08)) continue;  // a blank bay now and then
      const cv::Rect r(i * cw + (cw - ww) / 2, j * ch + (ch - wh) / 2, ww, wh);
      wall(r).convertTo(wall(r), CV_8U, glass, 10);
      cv::rectangle(wall, r, cv::Scalar(frame_value), frame);
      if (rng.chance(0.5)) {
        cv::line(wall, {r.x + r.width / 2, r.y}, {r.x + r.width / 2, r.y + r.height}, cv::Scalar(frame_value),
                 std::max(2, frame / 2));
      }
    }
  }
}

}  // namespace

std::vector<std::string> defaultTexturePhotos() {
  const std::string cv_dir = "/usr/share/doc/opencv-doc/examples/data/";
  const std::string sk_dir = "/usr/lib/python3/dist-packages/skimage/data/";
  const std::vector<std::string> candidates = {
      cv_dir + "building.jpg",     cv_dir + "aero1.jpg",     cv_dir + "aero3.jpg",
      cv_dir + "aloeL.jpg",        cv_dir + "baboon.jpg",    cv_dir + "board.jpg",
      cv_dir + "fruits.jpg",       cv_dir + "home.jpg",      cv_dir + "leuvenA.jpg",
      cv_dir + "leuvenB.jpg",      cv_dir + "messi5.jpg",    cv_dir + "orange.jpg",
      cv_dir + "stuff.jpg",        cv_dir + "graf1.png",     cv_dir + "basketball1.png",
      cv_dir + "box_in_scene.png", cv_dir + "HappyFish.jpg", cv_dir + "squirrel_cls.jpg",
      cv_dir + "starry_night.jpg", cv_dir + "lena.jpg",      sk_dir + "astronaut.png",
      sk_dir + "brick.png",        sk_dir + "camera.png",    sk_dir + "chelsea.png",
      sk_dir + "coffee.png",       sk_dir + "coins.png",     sk_dir + "motorcycle_left.png",
      sk_dir + "rocket.jpg",       sk_dir + "grass.png",     sk_dir + "gravel.png"};
  std::vector<std::string> found;
  for (const auto& c : candidates)
    if (std::filesystem::exists(c)) found.push_back(c);
  return found;
}

TextureBank TextureBank::build(const std::vector<std::string>& photo_paths, uint64_t seed, int n_facades) {
  std::vector<cv::Mat> photos;
  cv::Mat gravel, grass, brick;
  for (const auto& p : photo_paths) {
    cv::Mat img = cv::imread(p, cv::IMREAD_GRAYSCALE);
    if (img.empty() || img.cols < 64 || img.rows < 64) continue;
    const std::string name = std::filesystem::path(p).filename().string();
    if (name == "gravel.png") {
      gravel = img;
    } else if (name == "grass.png") {
      grass = img;
    } else if (name == "brick.png") {
      brick = img;
    }
    photos.push_back(img);  // ground photos serve as façade material too
  }
  TextureBank bank;
  bank.photos_used = photos.size();
  HashRng rng(hashCombine(seed, 0x7E47u));
  auto add = [&](const cv::Mat& m) {
    bank.textures.emplace_back(m);
    return static_cast<int>(bank.textures.size()) - 1;
  };
  auto material = [&](int i, double crop_lo, double crop_hi) {
    if (photos.empty()) return valueNoise(kSize, rng, 4 + rng.below(8), 5);
    return randomCrop(photos[(i * 7 + rng.below(static_cast<int>(photos.size()))) % photos.size()], rng,
                      crop_lo, crop_hi);
  };

  for (int i = 0; i < n_facades; ++i) {
    cv::Mat wall = normalizeContrast(material(i, 0.3, 0.9), rng.uniform(100, 160), rng.uniform(30, 50));
    paintWindows(wall, rng);
    bank.facades.push_back(add(wall));
  }
  for (int i = 0; i < n_facades / 3; ++i) {
    bank.walls.push_back(
        add(normalizeContrast(material(i, 0.2, 0.6), rng.uniform(90, 170), rng.uniform(20, 40))));
  }
  for (int i = 0; i < 12; ++i) {
    cv::Mat body = normalizeContrast(material(i, 0.1, 0.4), rng.uniform(50, 180), rng.uniform(15, 30));
    // A dark window band across the upper part, the way car sides look.
    body(cv::Rect(0, 0, kSize, kSize / 3)).convertTo(body(cv::Rect(0, 0, kSize, kSize / 3)), CV_8U, 0.3, 15);
    bank.cars.push_back(add(body));
  }
  auto ground = [&](const cv::Mat& photo, double mean, double sd) {
    cv::Mat base = normalizeContrast(valueNoise(kSize, rng, 32, 4), mean, sd * 0.6);
    if (!photo.empty()) {
      cv::Mat p;
      cv::resize(photo, p, cv::Size(kSize, kSize), 0, 0,
                 photo.cols >= kSize ? cv::INTER_AREA : cv::INTER_CUBIC);
      cv::addWeighted(base, 0.5, normalizeContrast(p, mean, sd), 0.5, 0, base);
    }
    return base;
  };
  bank.road = add(ground(gravel, 95, 18));
  bank.pavement = add(ground(brick, 150, 25));
  bank.grass = add(ground(grass, 110, 30));
  bank.pole = add(normalizeContrast(valueNoise(kSize, rng, 4, 3), 120, 25));
  bank.foliage = add(normalizeContrast(valueNoise(kSize, rng, 24, 5), 70, 35));
  return bank;
}

}  // namespace binloop::sim
