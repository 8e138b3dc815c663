// Which shadow models a user's list names, against a vocabulary folder that holds only some model files (a
// clone does not ship the hbow vocabulary).
#include "binloop/pipeline/model_files.h"

#include <gtest/gtest.h>

#include <fstream>

#include "binloop/place/place_recognizer.h"
#include "support/test_support.h"

namespace binloop {
namespace {

TEST(ShadowModelNames, AllIsEveryModelWithAFileButTheActiveOne) {
  test::TempDir dir;
  for (const char* n : {"vlad", "hmvlad", "fabmap"}) std::ofstream(dir / (std::string(n) + ".bin")) << "x";
  std::vector<std::string> skipped;
  EXPECT_EQ(shadowModelNames("all", "hmvlad", dir.path(), &skipped),
            (std::vector<std::string>{"fabmap", "vlad"}));
  EXPECT_EQ(skipped, (std::vector<std::string>{"hbow", "vladpq"}));
}

TEST(ShadowModelNames, AListIsTakenAsWrittenAndAnUnknownNameRefused) {
  EXPECT_EQ(shadowModelNames("vlad,,hbow", "hmvlad", "/nowhere"), (std::vector<std::string>{"vlad", "hbow"}));
  EXPECT_TRUE(shadowModelNames("", "hmvlad", "/nowhere").empty());
  try {
    shadowModelNames("vlad,netvlad", "hmvlad", "/nowhere");
    FAIL() << "an unknown model was taken";
  } catch (const PlaceError& e) {
    EXPECT_NE(std::string(e.what()).find("'netvlad'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace binloop
