// package.xml is what `rosdep install` and a ROS build farm read to set a machine up: every package the
// build, the tests and the launch files use must be named there. rosdep's database is not reachable here,
// so this reads the sources: each #include family, each find_package and each launched package must map to
// a dependency package.xml declares. A new library or launched package fails here until it is declared
// (and added to the table below).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "support/test_support.h"

namespace fs = std::filesystem;

namespace {

/// Every <depend>, <build_depend>, <exec_depend>, <test_depend>, <buildtool_depend> and the like.
std::set<std::string> declared() {
  const std::string xml = binloop::test::readText((fs::path(BINLOOP_ROOT_DIR) / "package.xml").string());
  std::set<std::string> names;
  const std::regex dep(R"(<(\w*depend)>\s*([^<\s]+)\s*</\1>)");
  for (std::sregex_iterator it(xml.begin(), xml.end(), dep), end; it != end; ++it) names.insert((*it)[2]);
  return names;
}

std::vector<fs::path> filesUnder(const std::vector<std::string>& dirs,
                                 const std::set<std::string>& extensions) {
  std::vector<fs::path> out;
  for (const auto& d : dirs) {
    const fs::path root = fs::path(BINLOOP_ROOT_DIR) / d;
    if (!fs::exists(root)) continue;
    for (const auto& e : fs::recursive_directory_iterator(root))
      if (e.is_regular_file() && extensions.count(e.path().extension().string())) out.push_back(e.path());
  }
  return out;
}

// Include families (the first folder of an <a/b.h> include) and the dependency that provides each.
const std::map<std::string, std::string> kIncludeFamilies = {
    {"opencv2", "libopencv-dev"},
    {"Eigen", "eigen"},
    {"ceres", "libceres-dev"},
    {"gtest", "gtest"},
    {"gmock", "gtest"},
    {"benchmark", "libbenchmark-dev"},
    {"ros", "roscpp"},
    {"sys", ""},      // POSIX
    {"binloop", ""},  // this package's generated messages and dynamic_reconfigure header
};
// find_package names and the dependency that provides each ("" = nothing to declare).
const std::map<std::string, std::string> kCmakePackages = {
    {"catkin", "catkin"},      {"OpenCV", "libopencv-dev"}, {"Eigen3", "eigen"},
    {"Ceres", "libceres-dev"}, {"GTest", "gtest"},          {"Threads", ""},
    {"rostest", "rostest"},    {"roslaunch", "roslaunch"},  {"benchmark", "libbenchmark-dev"},
};
// find_library names (a library without a CMake package) and the dependency that provides each.
const std::map<std::string, std::string> kCmakeLibraries = {
    {"cholmod", "suitesparse"},
};

}  // namespace

TEST(PackageManifest, EveryIncludedLibraryIsDeclared) {
  const auto deps = declared();
  ASSERT_TRUE(deps.count("roscpp")) << "package.xml not read";
  const std::regex inc(R"(#include\s*<([A-Za-z0-9_]+)/)");
  std::set<std::string> checked;
  for (const auto& f : filesUnder({"src", "include", "test", "bench"}, {".cpp", ".h", ".hpp"})) {
    const std::string text = binloop::test::readText(f.string());
    for (std::sregex_iterator it(text.begin(), text.end(), inc), end; it != end; ++it) {
      const std::string family = (*it)[1];
      const auto known = kIncludeFamilies.find(family);
      // A ROS message or library package includes as <pkg/...> under its own name.
      const std::string dep = known != kIncludeFamilies.end() ? known->second : family;
      if (dep.empty() || !checked.insert(dep).second) continue;
      EXPECT_TRUE(deps.count(dep)) << f.string() << " includes <" << family << "/...>, provided by '" << dep
                                   << "', which package.xml does not declare";
    }
  }
  EXPECT_GE(checked.size(), 15u) << "fewer include families than the package uses: the scan is broken";
}

TEST(PackageManifest, EveryFindPackageAndCatkinComponentIsDeclared) {
  const auto deps = declared();
  std::string cmake;
  for (const auto& f : filesUnder({"cmake"}, {".cmake"})) cmake += binloop::test::readText(f.string());
  cmake += binloop::test::readText((fs::path(BINLOOP_ROOT_DIR) / "CMakeLists.txt").string());
  const std::regex fp(R"(find_package\(\s*([A-Za-z0-9_]+))");
  int found = 0;
  for (std::sregex_iterator it(cmake.begin(), cmake.end(), fp), end; it != end; ++it, ++found) {
    const std::string name = (*it)[1];
    const auto known = kCmakePackages.find(name);
    ASSERT_NE(known, kCmakePackages.end())
        << "find_package(" << name << "): add it to this test's table and to package.xml";
    if (!known->second.empty())
      EXPECT_TRUE(deps.count(known->second))
          << "find_package(" << name << ") needs '" << known->second << "' in package.xml";
  }
  EXPECT_GE(found, 5);
  const std::regex fl(R"(find_library\(\s*[A-Za-z0-9_]+\s+([A-Za-z0-9_]+))");
  for (std::sregex_iterator it(cmake.begin(), cmake.end(), fl), end; it != end; ++it) {
    const std::string name = (*it)[1];
    const auto known = kCmakeLibraries.find(name);
    ASSERT_NE(known, kCmakeLibraries.end())
        << "find_library(... " << name << "): add it to this test's table and to package.xml";
    EXPECT_TRUE(deps.count(known->second))
        << "find_library(... " << name << ") needs '" << known->second << "' in package.xml";
  }
  // The catkin components: set(BINLOOP_CATKIN_DEPS ...) and message_generation.
  const std::smatch m = [&] {
    std::smatch r;
    std::regex_search(cmake, r, std::regex(R"(set\(BINLOOP_CATKIN_DEPS([^)]*)\))"));
    return r;
  }();
  ASSERT_FALSE(m.empty()) << "BINLOOP_CATKIN_DEPS not found in CMakeLists.txt";
  std::stringstream list(m[1].str());
  int components = 0;
  for (std::string c; list >> c; ++components)
    EXPECT_TRUE(deps.count(c)) << "catkin component " << c << " not in package.xml";
  EXPECT_GE(components, 10);
  EXPECT_TRUE(deps.count("message_generation") && deps.count("message_runtime"));
}

TEST(PackageManifest, EveryLaunchedPackageIsDeclared) {
  const auto deps = declared();
  const std::regex pkg(R"(pkg="([^"]+)\")");
  int found = 0;
  for (const auto& f : filesUnder({"launch", "test"}, {".launch", ".test"})) {
    const std::string text = binloop::test::readText(f.string());
    for (std::sregex_iterator it(text.begin(), text.end(), pkg), end; it != end; ++it, ++found) {
      const std::string p = (*it)[1];
      if (p != "binloop")
        EXPECT_TRUE(deps.count(p)) << f.string() << " launches a node of '" << p << "', not in package.xml";
    }
  }
  EXPECT_GE(found, 5);
}
