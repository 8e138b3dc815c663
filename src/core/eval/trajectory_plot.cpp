#include "binloop/eval/trajectory_plot.h"

#include <algorithm>
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

}  // namespace

void writeTrajectoryPlot(const std::string& path, const std::string& title, const std::vector<Pose3>& gt,
                         const std::vector<Pose3>& est_aligned, const TrajectoryMetrics& metrics) {
  const int w = 900, h = 1000, l = 75, r = 25, t = 125, b = 75;  // plot area inside these margins
  const cv::Scalar black(0, 0, 0), grey(120, 120, 120), grid(232, 232, 232);
  const cv::Scalar c_gt(180, 119, 31), c_est(14, 127, 255), c_start(44, 160, 44);  // blue, orange, green
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));

  // Equal scales: the box around both paths (x right, z up), padded, fitted into the plot area.
  double x0 = 1e300, x1 = -1e300, z0 = 1e300, z1 = -1e300;
  for (const auto* poses : {&gt, &est_aligned})
    for (const auto& T : *poses) {
      x0 = std::min(x0, T.translation().x()), x1 = std::max(x1, T.translation().x());
      z0 = std::min(z0, T.translation().z()), z1 = std::max(z1, T.translation().z());
    }
  if (x0 > x1) x0 = z0 = -1, x1 = z1 = 1;  // nothing to draw
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
  for (double x = std::ceil(gx0 / step) * step; x <= gx1; x += step) {
    cv::line(img, px(x, gz0), px(x, gz1), grid);
    const std::string s_x = metres(x);
    const int tw = cv::getTextSize(s_x, font, 0.4, 1, nullptr).width;
    cv::putText(img, s_x, cv::Point(px(x, gz0).x - tw / 2, h - b + 16), font, 0.4, grey, 1, cv::LINE_AA);
  }
  for (double z = std::ceil(gz0 / step) * step; z <= gz1; z += step) {
    cv::line(img, px(gx0, z), px(gx1, z), grid);
    const std::string s_z = metres(z);
    const int tw = cv::getTextSize(s_z, font, 0.4, 1, nullptr).width;
    cv::putText(img, s_z, cv::Point(l - 6 - tw, px(gx0, z).y + 4), font, 0.4, grey, 1, cv::LINE_AA);
  }
  cv::rectangle(img, cv::Point(l, t), cv::Point(w - r, h - b), grey);
  cv::putText(img, "x [m] (right)", cv::Point(l + static_cast<int>(pw) / 2 - 45, h - b + 36), font, 0.45, black, 1,
              cv::LINE_AA);
  cv::putText(img, "z [m] (forward)", cv::Point(l - 60, t - 8), font, 0.45, black, 1, cv::LINE_AA);

  // Paths: ground truth under the estimate, then end and start markers.
  auto polyline = [&](const std::vector<Pose3>& poses, const cv::Scalar& c, int thick) {
    std::vector<cv::Point> pts;
    for (const auto& T : poses) {
      const cv::Point p = px(T.translation().x(), T.translation().z());
      if (pts.empty() || p != pts.back()) pts.push_back(p);
    }
    if (pts.size() == 1) cv::circle(img, pts[0], thick, c, cv::FILLED, cv::LINE_AA);
    if (pts.size() > 1) cv::polylines(img, pts, false, c, thick, cv::LINE_AA);
  };
  polyline(gt, c_gt, 3);
  polyline(est_aligned, c_est, 2);
  auto at = [&](const Pose3& T) { return px(T.translation().x(), T.translation().z()); };
  if (!gt.empty()) cv::circle(img, at(gt.back()), 6, c_gt, 2, cv::LINE_AA);
  if (!est_aligned.empty()) cv::circle(img, at(est_aligned.back()), 6, c_est, 2, cv::LINE_AA);
  if (!gt.empty()) {
    cv::circle(img, at(gt.front()), 8, c_start, cv::FILLED, cv::LINE_AA);
    cv::circle(img, at(gt.front()), 8, black, 1, cv::LINE_AA);
  }

  // Header: title, metrics, legend.
  cv::putText(img, title, cv::Point(l - 60, 28), font, 0.6, black, 1, cv::LINE_AA);
  const RelativeErrors& rel = metrics.relative;
  std::string text = cv::format("ATE RMSE %.3f m", metrics.ate_rmse_m);
  if (rel.valid)
    text += cv::format("    t_rel %.3f %%    r_rel %.4f deg/100 m", rel.t_rel_pct, rel.r_rel_deg_per_100m);
  else
    text += cv::format("    t_rel, r_rel: n/a (path of %.0f m is too short)", rel.path_length_m);
  cv::putText(img, text, cv::Point(l - 60, 58), font, 0.6, black, 1, cv::LINE_AA);
  int lx = l - 60;
  const int ly = 92;
  auto key = [&](const std::string& label, const cv::Scalar& c, int thick) {
    cv::line(img, cv::Point(lx, ly - 5), cv::Point(lx + 30, ly - 5), c, thick, cv::LINE_AA);
    cv::putText(img, label, cv::Point(lx + 38, ly), font, 0.5, black, 1, cv::LINE_AA);
    lx += 38 + cv::getTextSize(label, font, 0.5, 1, nullptr).width + 30;
  };
  key("ground truth", c_gt, 3);
  key("estimate (aligned, SE(3))", c_est, 2);
  cv::circle(img, cv::Point(lx + 8, ly - 5), 8, c_start, cv::FILLED, cv::LINE_AA);
  cv::circle(img, cv::Point(lx + 8, ly - 5), 8, black, 1, cv::LINE_AA);
  cv::putText(img, "start", cv::Point(lx + 22, ly), font, 0.5, black, 1, cv::LINE_AA);
  lx += 22 + cv::getTextSize("start", font, 0.5, 1, nullptr).width + 30;
  cv::circle(img, cv::Point(lx + 8, ly - 5), 6, grey, 2, cv::LINE_AA);
  cv::putText(img, "end", cv::Point(lx + 22, ly), font, 0.5, black, 1, cv::LINE_AA);

  // Scale bar, bottom right below the plot: one grid step.
  const int bar = static_cast<int>(std::lround(step * s));
  const cv::Point b1(w - r - 70, h - 22), b0 = b1 - cv::Point(bar, 0);
  cv::line(img, b0, b1, black, 3);
  cv::line(img, b0 + cv::Point(0, -6), b0 + cv::Point(0, 6), black, 2);
  cv::line(img, b1 + cv::Point(0, -6), b1 + cv::Point(0, 6), black, 2);
  cv::putText(img, metres(step) + " m", b1 + cv::Point(8, 5), font, 0.5, black, 1, cv::LINE_AA);

  if (!cv::imwrite(path, img)) throw dataError(path, 0, "cannot write the plot");
}

}  // namespace binloop
