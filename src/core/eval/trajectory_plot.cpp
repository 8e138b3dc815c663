#include "binloop/eval/trajectory_plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binloop/io/data_error.h"

namespace binloop {

namespace {

// 1, 2 or 5 times a power of ten, the smallest at or above v.
double niceStep(double v) {
  const double p = std::pow(10.0, std::floor(std::log10(v)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= v * (1 - 1e-9)) return m * p;
  return 10 * p;
}

std::string metres(double v) {
  if (std::abs(v) < 1e-9) v = 0;  // a grid line at -1e-14 is "0", not "-0"
  return std::abs(v - std::round(v)) < 1e-9 ? cv::format("%.0f", v) : cv::format("%g", v);
}

// Matplotlib's tab10 (BGR) without its green, which marks the start: blue is the ground truth, the rest
// the estimates.
const cv::Scalar kGroundTruth(180, 119, 31);
const cv::Scalar kPalette[] = {{14, 127, 255},  {40, 39, 214},  {189, 103, 148}, {75, 86, 140},
                               {194, 119, 227}, {34, 189, 188}, {207, 190, 23},  {127, 127, 127}};

// One path of a top view: drawn as a line, with a ring at its end.
struct PlotPath {
  std::string label;
  const std::vector<Pose3>* poses;
  cv::Scalar colour;
  int thickness;
};

// A legend entry: its key is a line (a path), a filled disc (start) or a ring (end).
struct LegendEntry {
  enum class Key { line, start, end };
  std::string label;
  Key kind;
  cv::Scalar colour;
  int thickness;
  cv::Point at;  // left end of the symbol, on the text's baseline
};

void drawLegendEntry(cv::Mat& img, const LegendEntry& e) {
  using Key = LegendEntry::Key;
  const cv::Scalar black(0, 0, 0);
  const cv::Point c = e.at + cv::Point(8, -5);
  if (e.kind == Key::line) {
    cv::line(img, e.at + cv::Point(0, -5), e.at + cv::Point(30, -5), e.colour, e.thickness, cv::LINE_AA);
  } else if (e.kind == Key::start) {
    cv::circle(img, c, 8, e.colour, cv::FILLED, cv::LINE_AA);
    cv::circle(img, c, 8, black, 1, cv::LINE_AA);
  } else {
    cv::circle(img, c, 6, e.colour, e.thickness, cv::LINE_AA);
  }
  cv::putText(img, e.label, e.at + cv::Point(e.kind == Key::line ? 38 : 22, 0), cv::FONT_HERSHEY_SIMPLEX, 0.5,
              black, 1, cv::LINE_AA);
}

// A bar of `bar_px` pixels ending at `right`, labelled with the `step_m` it stands for.
void drawScaleBar(cv::Mat& img, const cv::Point& right, double step_m, int bar_px) {
  const cv::Scalar black(0, 0, 0);
  const cv::Point b1 = right, b0 = b1 - cv::Point(bar_px, 0);
  cv::line(img, b0, b1, black, 3);
  cv::line(img, b0 + cv::Point(0, -6), b0 + cv::Point(0, 6), black, 2);
  cv::line(img, b1 + cv::Point(0, -6), b1 + cv::Point(0, 6), black, 2);
  cv::putText(img, metres(step_m) + " m", b1 + cv::Point(8, 5), cv::FONT_HERSHEY_SIMPLEX, 0.5, black, 1,
              cv::LINE_AA);
}

// Grid lines every `step` metres over the world box `box` (x0, x1, z0, z1) and their labels: x's centred
// on the row `bottom_y`, z's right-aligned at `left_x`. `px` maps (x, z) to pixels.
template <class ToPixel>
void drawGrid(cv::Mat& img, ToPixel px, const std::array<double, 4>& box, double step, int left_x,
              int bottom_y) {
  const cv::Scalar grey(120, 120, 120), grid(232, 232, 232);
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  auto textWidth = [&](const std::string& s) { return cv::getTextSize(s, font, 0.4, 1, nullptr).width; };
  const auto [gx0, gx1, gz0, gz1] = box;
  for (double x = std::ceil(gx0 / step) * step; x <= gx1; x += step) {
    cv::line(img, px(x, gz0), px(x, gz1), grid);
    const std::string s_x = metres(x);
    cv::putText(img, s_x, cv::Point(px(x, gz0).x - textWidth(s_x) / 2, bottom_y), font, 0.4, grey, 1,
                cv::LINE_AA);
  }
  for (double z = std::ceil(gz0 / step) * step; z <= gz1; z += step) {
    cv::line(img, px(gx0, z), px(gx1, z), grid);
    const std::string s_z = metres(z);
    cv::putText(img, s_z, cv::Point(left_x - textWidth(s_z), px(gx0, z).y + 4), font, 0.4, grey, 1,
                cv::LINE_AA);
  }
}

// The box around every path's poses on the ground (x0, x1, z0, z1); -1..1 when there are none.
std::array<double, 4> pathBounds(const std::vector<PlotPath>& paths) {
  double x0 = 1e300, x1 = -1e300, z0 = 1e300, z1 = -1e300;
  for (const auto& p : paths) {
    for (const auto& T : *p.poses) {
      x0 = std::min(x0, T.translation().x()), x1 = std::max(x1, T.translation().x());
      z0 = std::min(z0, T.translation().z()), z1 = std::max(z1, T.translation().z());
    }
  }
  if (x0 > x1) return {-1, 1, -1, 1};  // nothing to draw
  return {x0, x1, z0, z1};
}

// The top view both plots share: `paths` (the first is the ground truth: drawn under the rest, its first
// pose marked as the start) with equal axis scales, a grid, a scale bar, and a header of the title, the
// `notes` lines and a legend that wraps onto more rows when the labels do not fit one.
void writeTopView(const std::string& path, const std::string& title, const std::vector<std::string>& notes,
                  const std::vector<PlotPath>& paths) {
  const int w = 900, l = 75, r = 25, b = 75, ph_px = 800;  // margins round an 800-px-high plot area
  const cv::Scalar black(0, 0, 0), grey(120, 120, 120), c_start(44, 160, 44);  // green
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  auto textWidth = [&](const std::string& s, double size) {
    return cv::getTextSize(s, font, size, 1, nullptr).width;
  };

  // Header layout first: its height sets where the plot area starts.
  std::vector<LegendEntry> legend;
  using Key = LegendEntry::Key;
  legend.reserve(paths.size() + 2);
  for (const auto& p : paths) legend.push_back({p.label, Key::line, p.colour, p.thickness, {}});
  legend.push_back({"start", Key::start, c_start, 0, {}});
  legend.push_back({"end", Key::end, grey, 2, {}});
  int lx = l - 60, ly = 28 + 30 * static_cast<int>(notes.size()) + 34;
  for (auto& e : legend) {
    const int symbol = e.kind == Key::line ? 38 : 22, width = symbol + textWidth(e.label, 0.5);
    if (lx > l - 60 && lx + width > w - r) lx = l - 60, ly += 26;
    e.at = cv::Point(lx, ly);
    lx += width + 30;
  }
  const int t = ly + 33, h = t + ph_px + b;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));

  // Equal scales: the box around all paths (x right, z up), padded, fitted into the plot area.
  const auto [x0, x1, z0, z1] = pathBounds(paths);
  const double span = std::max({x1 - x0, z1 - z0, 1.0});
  const double pad = 0.04 * span, pw = w - l - r, ph = h - t - b;
  const double s = std::min(pw / (x1 - x0 + 2 * pad), ph / (z1 - z0 + 2 * pad));  // pixels per metre
  const double cx = 0.5 * (x0 + x1), cz = 0.5 * (z0 + z1);
  auto px = [&](double x, double z) {
    return cv::Point(static_cast<int>(std::lround(l + pw / 2 + (x - cx) * s)),
                     static_cast<int>(std::lround(t + ph / 2 - (z - cz) * s)));
  };
  // World extent of the plot area, for the grid.
  const double gx0 = cx - pw / 2 / s, gx1 = cx + pw / 2 / s, gz0 = cz - ph / 2 / s, gz1 = cz + ph / 2 / s;

  // Grid every `step` metres with labels on the left and bottom edges.
  const double step = niceStep(std::max(gx1 - gx0, gz1 - gz0) / 8);
  drawGrid(img, px, {gx0, gx1, gz0, gz1}, step, l - 6, h - b + 16);
  cv::rectangle(img, cv::Point(l, t), cv::Point(w - r, h - b), grey);
  cv::putText(img, "x [m] (right)", cv::Point(l + static_cast<int>(pw) / 2 - 45, h - b + 36), font, 0.45,
              black, 1, cv::LINE_AA);
  cv::putText(img, "z [m] (forward)", cv::Point(l - 60, t - 8), font, 0.45, black, 1, cv::LINE_AA);

  // Paths in order (the ground truth under the estimates), then end and start markers.
  auto at = [&](const Pose3& T) { return px(T.translation().x(), T.translation().z()); };
  for (const auto& p : paths) {
    std::vector<cv::Point> pts;
    for (const auto& T : *p.poses)
      if (pts.empty() || at(T) != pts.back()) pts.push_back(at(T));
    if (pts.size() == 1) cv::circle(img, pts[0], p.thickness, p.colour, cv::FILLED, cv::LINE_AA);
    if (pts.size() > 1) cv::polylines(img, pts, false, p.colour, p.thickness, cv::LINE_AA);
  }
  for (const auto& p : paths)
    if (!p.poses->empty()) cv::circle(img, at(p.poses->back()), 6, p.colour, 2, cv::LINE_AA);
  if (!paths.empty() && !paths[0].poses->empty()) {
    cv::circle(img, at(paths[0].poses->front()), 8, c_start, cv::FILLED, cv::LINE_AA);
    cv::circle(img, at(paths[0].poses->front()), 8, black, 1, cv::LINE_AA);
  }

  // Header: title, notes, legend.
  cv::putText(img, title, cv::Point(l - 60, 28), font, 0.6, black, 1, cv::LINE_AA);
  for (size_t i = 0; i < notes.size(); ++i) {
    cv::putText(img, notes[i], cv::Point(l - 60, 58 + 30 * static_cast<int>(i)), font, 0.6, black, 1,
                cv::LINE_AA);
  }
  for (const auto& e : legend) drawLegendEntry(img, e);
  // Scale bar, bottom right below the plot: one grid step.
  drawScaleBar(img, cv::Point(w - r - 70, h - 22), step, static_cast<int>(std::lround(step * s)));

  if (!cv::imwrite(path, img)) throw dataError(path, 0, "cannot write the plot");
}

}  // namespace

void writeTrajectoryPlot(const std::string& path, const std::string& title, const std::vector<Pose3>& gt,
                         const std::vector<Pose3>& est_aligned, const TrajectoryMetrics& metrics) {
  const RelativeErrors& rel = metrics.relative;
  std::string text = cv::format("ATE RMSE %.3f m", metrics.ate_rmse_m);
  if (rel.valid) {
    text += cv::format("    t_rel %.3f %%    r_rel %.4f deg/100 m", rel.t_rel_pct, rel.r_rel_deg_per_100m);
  } else {
    text += cv::format("    t_rel, r_rel: n/a (path of %.0f m is too short)", rel.path_length_m);
  }
  writeTopView(
      path, title, {text},
      {{"ground truth", &gt, kGroundTruth, 3}, {"estimate (aligned, SE(3))", &est_aligned, kPalette[0], 2}});
}

void writeTrajectoriesPlot(const std::string& path, const std::string& title, const std::vector<Pose3>& gt,
                           const std::vector<std::pair<std::string, std::vector<Pose3>>>& aligned) {
  std::vector<PlotPath> paths{{"ground truth", &gt, kGroundTruth, 3}};
  const size_t colours = sizeof kPalette / sizeof kPalette[0];
  for (size_t i = 0; i < aligned.size(); ++i)
    paths.push_back({aligned[i].first, &aligned[i].second, kPalette[i % colours], 2});
  writeTopView(path, title, {"each estimate aligned to the ground truth by its own SE(3)"}, paths);
}

}  // namespace binloop
