#include "binloop/eval/pr_plot.h"

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binloop/io/data_error.h"

namespace binloop {

void writePrPlot(const std::string& path, const std::string& title, const std::vector<PrSeries>& series) {
  const int w = 720, h = 560, l = 70, r = 170, t = 40, b = 60;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  auto px = [&](double recall, double precision) {
    return cv::Point(l + static_cast<int>(recall * (w - l - r)),
                     h - b - static_cast<int>(precision * (h - t - b)));
  };
  for (int i = 0; i <= 10; ++i) {
    const double v = i / 10.0;
    cv::line(img, px(v, 0), px(v, 1), cv::Scalar(230, 230, 230));
    cv::line(img, px(0, v), px(1, v), cv::Scalar(230, 230, 230));
    cv::putText(img, cv::format("%.1f", v), px(v, 0) + cv::Point(-10, 20), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                {0, 0, 0});
    cv::putText(img, cv::format("%.1f", v), px(0, v) + cv::Point(-35, 4), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                {0, 0, 0});
  }
  cv::rectangle(img, px(0, 1), px(1, 0), cv::Scalar(0, 0, 0));
  cv::putText(img, "recall", px(0.45, 0) + cv::Point(0, 45), cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0});
  cv::putText(img, "precision", cv::Point(5, t - 10), cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0});
  cv::putText(img, title, cv::Point(l + 80, t - 15), cv::FONT_HERSHEY_SIMPLEX, 0.55, {0, 0, 0});
  const cv::Scalar colours[] = {{180, 119, 31},  {14, 127, 255}, {44, 160, 44},   {40, 39, 214},
                                {189, 103, 148}, {75, 86, 140},  {194, 119, 227}, {127, 127, 127},
                                {34, 189, 188},  {207, 190, 23}};
  // "model+variant" (e.g. hbow+c3) shares its model's colour and is drawn thick; the plain model is thin.
  std::vector<std::string> bases;
  for (size_t s = 0; s < series.size(); ++s) {
    const std::string& label = series[s].label;
    const std::string base = label.substr(0, label.find('+'));
    const bool variant = base.size() < label.size();
    size_t ci = std::find(bases.begin(), bases.end(), base) - bases.begin();
    if (ci == bases.size()) bases.push_back(base);
    const cv::Scalar c = colours[ci % 10];
    const int thick = variant ? 3 : 1;
    cv::Point prev = px(0, 1);
    for (const auto& p : series[s].curve) {
      const cv::Point q = px(p.recall, p.precision);
      cv::line(img, prev, q, c, thick, cv::LINE_AA);
      prev = q;
    }
    const cv::Point key(w - r + 15, t + 20 + 25 * static_cast<int>(s));
    cv::line(img, key, key + cv::Point(25, 0), c, thick + 1);
    cv::putText(img, label, key + cv::Point(32, 5), cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0});
  }
  if (!cv::imwrite(path, img)) throw dataError(path, 0, "cannot write the plot");
}

}  // namespace binloop
