#pragma once
#include <string>

#include "binloop/types/stereo_camera.h"

namespace binloop {

/// Reads a KITTI odometry calib.txt: P0 gives fx, fy, cx, cy; P1's first-row translation is -fx·b, which
/// gives the baseline. Image size is not in the file: width/height stay 0 for the caller to fill.
/// Throws DataError for a missing file, a missing P0/P1, a line with other than 12 numbers, a non-numeric
/// value, or a non-positive focal length or baseline.
StereoCamera readKittiCalib(const std::string& path);

/// Writes P0..P3 (P2 = P0, P3 = P1, as our sequences have no colour cameras) in KITTI's layout.
void writeKittiCalib(const std::string& path, const StereoCamera& cam);

}  // namespace binloop
