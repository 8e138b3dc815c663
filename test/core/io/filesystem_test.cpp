#include "binloop/io/filesystem.h"

#include <algorithm>

#include "binloop/io/data_error.h"
#include "support/test_support.h"

TEST(Filesystem, NaturalOrder) {
  std::vector<std::string> v{"10.jpg", "2.jpg", "1.png", "img10b.png", "img2b.png", "000003.png"};
  std::sort(v.begin(), v.end(), binloop::naturalLess);
  EXPECT_EQ(v,
            (std::vector<std::string>{"1.png", "2.jpg", "000003.png", "10.jpg", "img2b.png", "img10b.png"}));
}

TEST(Filesystem, ListsOnlyWantedExtensionsInNaturalOrder) {
  binloop::test::TempDir tmp;
  for (const char* n : {"10.JPG", "2.png", "1.jpg", "notes.txt"}) binloop::test::writeText(tmp / n, "x");
  const auto files = binloop::listFilesNatural(tmp.path(), {".png", ".jpg"});
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files[0], tmp / "1.jpg");
  EXPECT_EQ(files[2], tmp / "10.JPG");
  EXPECT_THROW_WITH(binloop::listFilesNatural(tmp / "nope", {".png"}), binloop::DataError, "no such folder");
}
