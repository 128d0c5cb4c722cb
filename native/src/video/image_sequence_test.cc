#include "sunlapse/video/image_sequence.h"

#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <string>

namespace sunlapse {
namespace {
namespace fs = std::filesystem;

// A folder holding empty files of these names (names are all that matter).
fs::path Folder(const std::string& name,
                std::initializer_list<const char*> files) {
  const fs::path d = fs::temp_directory_path() / ("sunlapse_seq_" + name + "_" +
                                                  std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  for (const char* f : files) std::ofstream(d / f).put('x');
  return d;
}

TEST(ImageSequence, RunsToTheHighestNumberPresentAcrossAGap) {
  const fs::path d =
      Folder("gap", {"IMG_0007.JPG", "IMG_0008.JPG", "IMG_0010.JPG",
                     "IMG_0011.png", "IMG_10000.JPG", "other_0012.JPG"});
  const auto s = FindImageSequence((d / "IMG_0007.JPG").string());
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->first_number, 7);
  EXPECT_EQ(s->last_number, 10);  // not the .png, nor the 5-digit name
  EXPECT_EQ(s->num_frames(), 4);
  EXPECT_TRUE(s->padded);
  EXPECT_EQ(s->Path(2),
            (d / "IMG_0009.JPG").string());  // the gap: a missing frame
  fs::remove_all(d);
}

TEST(ImageSequence, UnpaddedNumbersMayGrow) {
  const fs::path d = Folder("grow", {"f8.png", "f9.png", "f10.png", "f11.png"});
  const auto s = FindImageSequence((d / "f8.png").string());
  ASSERT_TRUE(s.has_value());
  EXPECT_FALSE(s->padded);
  EXPECT_EQ(s->last_number, 11);
  EXPECT_EQ(s->Path(3), (d / "f11.png").string());
  fs::remove_all(d);
}

TEST(ImageSequence, AMovieOrAnUnnumberedImageIsNone) {
  EXPECT_FALSE(FindImageSequence("/tmp/clip_0001.mp4").has_value());
  EXPECT_FALSE(FindImageSequence("/tmp/still.png").has_value());
  // At most 9 digits are the number (it fits an int): the rest is the stem.
  const auto s = FindImageSequence("/tmp/f1234567890.png");
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->first_number, 234567890);
  EXPECT_EQ(s->prefix, "/tmp/f1");
}

}  // namespace
}  // namespace sunlapse
