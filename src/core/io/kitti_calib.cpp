#include "binloop/io/kitti_calib.h"

#include <cstdio>
#include <fstream>
#include <map>

#include "binloop/io/data_error.h"
#include "binloop/io/number_lines.h"

namespace binloop {

StereoCamera readKittiCalib(const std::string& path) {
  std::map<std::string, NumberLine> rows;
  for (auto& l : readNumberLines(path)) {
    if (l.label.empty()) throw dataError(path, l.line_no, "expected 'P0:', 'P1:', ... at line start");
    rows[l.label] = l;
  }
  for (const char* key : {"P0", "P1"}) {
    auto it = rows.find(key);
    if (it == rows.end()) throw dataError(path, 0, std::string("no '") + key + ":' line");
    requireCount(path, it->second, 12, std::string(key) + " (a 3x4 projection matrix)");
  }
  const auto& p0 = rows["P0"].values;
  const auto& p1 = rows["P1"].values;
  StereoCamera cam;
  cam.fx = p0[0];
  cam.cx = p0[2];
  cam.fy = p0[5];
  cam.cy = p0[6];
  if (cam.fx <= 0 || cam.fy <= 0) throw dataError(path, rows["P0"].line_no, "focal length must be positive");
  if (p1[0] != p0[0]) throw dataError(path, rows["P1"].line_no, "P1's fx differs from P0's: not rectified");
  cam.baseline_m = -p1[3] / p1[0];
  if (cam.baseline_m <= 0) {
    throw dataError(
        path, rows["P1"].line_no,
        "P1[0][3] must be -fx*baseline (negative) for a right camera; got " + std::to_string(p1[3]));
  }
  return cam;
}

void writeKittiCalib(const std::string& path, const StereoCamera& cam) {
  std::ofstream out(path);
  if (!out) throw dataError(path, 0, "cannot be opened for writing");
  const char* names[] = {"P0", "P1", "P2", "P3"};
  for (int i = 0; i < 4; ++i) {
    const auto P = cam.projectionMatrix(i % 2 == 1);
    out << names[i] << ":";
    char buf[32];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        std::snprintf(buf, sizeof buf, " %.12e", P(r, c));
        out << buf;
      }
    }
    out << "\n";
  }
  if (!out) throw dataError(path, 0, "write failed");
}

}  // namespace binloop
