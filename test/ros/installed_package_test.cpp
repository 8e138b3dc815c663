// The package as a ROS user gets it: installed (what `catkin_make install` does after the build), then used
// with only the install space's setup.bash sourced and nothing of the checkout on any path: its tools find
// the shipped files, another package in a new workspace builds and links against it, and
// kitti_stereo.launch with every default closes the loop of a rendered drive played as a bag at 2x.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "binloop/io/trajectory_io.h"
#include "binloop/sim/builtin_route.h"
#include "support/test_support.h"

namespace {

const std::string kPrefix = BINLOOP_INSTALL_PREFIX;

/// `command` in bash with a clean environment but for the install space's setup (no devel space, no
/// checkout on ROS_PACKAGE_PATH or LD_LIBRARY_PATH). `command` must not contain single quotes.
binloop::test::CommandResult inInstallSpace(const std::string& command) {
  return binloop::test::runCommand("env -i HOME=\"$HOME\" PATH=/usr/bin:/bin LANG=C.UTF-8 bash -c 'source " +
                                   kPrefix + "/setup.bash && " + command + "'");
}

/// Installs the built workspace into its install prefix once per test program (no rebuild: the build is
/// what the other tests use).
const std::string& installProblem() {
  static const std::string problem = [] {
    const auto r = binloop::test::runCommand(std::string("cmake --install ") + BINLOOP_WS_BUILD_DIR);
    return r.code == 0 ? std::string() : "cmake --install failed:\n" + r.out;
  }();
  return problem;
}

}  // namespace

TEST(InstalledPackage, ToolsFindTheShippedFilesFromTheInstallSpace) {
  ASSERT_EQ(installProblem(), "");
  const std::string seq = binloop::test::sharedData("kitti/sample_00");
  BINLOOP_REQUIRE_DATA(seq);
  binloop::test::TempDir tmp;
  const auto where = inInstallSpace("rospack find binloop");
  EXPECT_EQ(where.out, kPrefix + "/share/binloop\n");
  const auto r =
      inInstallSpace("cd " + tmp.path() + " && rosrun binloop run " + seq + " --out out --lockstep");
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string summary = binloop::test::readText(tmp / "out/summary.json");
  EXPECT_NE(summary.find("\"detector\": \"hmvlad\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"reloc_vocab\": \"" + kPrefix + "/share/binloop/vocab/kitti08/hbow_k8l5.bin\""),
            std::string::npos)
      << summary;
}

TEST(InstalledPackage, ADownstreamPackageBuildsAndLinksAgainstIt) {
  ASSERT_EQ(installProblem(), "");
  binloop::test::TempDir ws;
  binloop::test::writeText(ws / "src/consumer/package.xml", R"(<?xml version="1.0"?>
<package format="2">
  <name>consumer</name>
  <version>0.0.1</version>
  <description>Builds against binloop as a robot's package would.</description>
  <maintainer email="test@example.org">test</maintainer>
  <license>BSD-3-Clause</license>
  <buildtool_depend>catkin</buildtool_depend>
  <depend>binloop</depend>
</package>
)");
  binloop::test::writeText(ws / "src/consumer/CMakeLists.txt", R"(cmake_minimum_required(VERSION 3.16)
project(consumer)
set(CMAKE_CXX_STANDARD 17)
find_package(catkin REQUIRED COMPONENTS binloop)
catkin_package()
include_directories(${catkin_INCLUDE_DIRS})
add_executable(consumer src/consumer.cpp)
target_link_libraries(consumer ${catkin_LIBRARIES})
)");
  // Headers that pull in Eigen, OpenCV and Ceres: the exported include folders and libraries must carry them.
  binloop::test::writeText(ws / "src/consumer/src/consumer.cpp", R"(#include <iostream>
#include <opencv2/core.hpp>
#include "binloop/features/orb_slam_extractor.h"
#include "binloop/optim/local_bundle_adjustment.h"
#include "binloop/place/model_file.h"
#include "binloop/util/package_paths.h"
int main() {
  const std::string f = binloop::packagePath(binloop::kShippedModelDir) + "/hmvlad.bin";
  std::cout << f << ": " << binloop::readModelHeader(f).describe() << "\n";
  const binloop::OrbSlamExtractor e{binloop::OrbSlamParams{}};
  std::cout << "features on a black image: " << e.extract(cv::Mat(376, 1241, CV_8UC1, cv::Scalar(0))).keypoints.size() << "\n";
}
)");
  const auto build =
      inInstallSpace("cd " + ws.path() + " && catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 2>&1");
  ASSERT_EQ(build.code, 0) << build.out;
  const auto run = inInstallSpace("source " + (ws / "devel/setup.bash") + " && rosrun consumer consumer");
  ASSERT_EQ(run.code, 0) << run.out;
  EXPECT_NE(run.out.find(kPrefix + "/share/binloop/vocab/kitti08/hmvlad.bin: hmvlad model"),
            std::string::npos)
      << run.out;
  EXPECT_NE(run.out.find("features on a black image: 0"), std::string::npos) << run.out;
}

// No vocabulary made, every launch default: the shipped detector closes the drive's one revisit.
TEST(InstalledPackage, TheLaunchFileWithItsDefaultsClosesTheLoopOfABag) {
  ASSERT_EQ(installProblem(), "");
  binloop::test::TempDir tmp;
  binloop::writeKittiPoses(tmp / "route.txt", binloop::sim::loopRoute(50, 80, 12, 8, 10, 1.25));
  const std::string tools = BINLOOP_TOOL_DIR;
  const auto render = binloop::test::runCommand(tools + "/render --route " + (tmp / "route.txt") +
                                                " --calib kitti04 --out " + (tmp / "seq"));
  ASSERT_EQ(render.code, 0) << render.out;
  const auto bag =
      binloop::test::runCommand(tools + "/kitti2bag " + (tmp / "seq") + " " + (tmp / "drive.bag"));
  ASSERT_EQ(bag.code, 0) << bag.out;
  // Its own master port, so that no other master on the machine is used.
  const auto r =
      inInstallSpace("export ROS_MASTER_URI=http://localhost:11391 && cd " + tmp.path() + " && " +
                     BINLOOP_ROOT_DIR + "/scripts/run_bag.sh " + (tmp / "drive.bag") + " --out out --rate 2");
  ASSERT_EQ(r.code, 0) << r.out;
  // Only the install space is sourced, so roslaunch's $(find binloop) and the nodelets are the installed
  // ones.
  const std::string summary = binloop::test::readText(tmp / "out/summary.json");
  const auto at = summary.find("\"accepted\": ");
  ASSERT_NE(at, std::string::npos) << "no loop accepted:\n" << summary << "\n" << r.out;
  EXPECT_GE(std::stoi(summary.substr(at + 12)), 1) << summary;
  EXPECT_NE(binloop::test::readText(tmp / "out/loops.csv").find(",hmvlad,0,"), std::string::npos)
      << "the active model was not hmvlad";
}
