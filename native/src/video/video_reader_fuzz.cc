// libFuzzer target for VideoReader (not built by CMake; tools/fuzz-reader.sh
// builds and runs it). Each input is written to a file whose extension comes
// from the first byte, so FFmpeg's guessing by name is exercised too.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

#include "sunlapse/video/video_reader.h"

namespace {
namespace fs = std::filesystem;

const fs::path& FuzzDir() {
  static const fs::path dir = [] {
    fs::path d = fs::temp_directory_path() /
                 ("sunlapse_fuzz_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* const kExtensions[] = {".mp4", ".mpg", ".gif", ".png",
                                            ".jpg", ".avi", ".tif"};
  // A name without digits: one image, never a numbered sequence (whose
  // directory scan would see other inputs).
  const fs::path file =
      FuzzDir() / (std::string("input") + kExtensions[data[0] % 7]);
  {
    FILE* out = std::fopen(file.c_str(), "wb");
    if (out == nullptr) return 0;
    std::fwrite(data + 1, 1, size - 1, out);
    std::fclose(out);
  }
  try {
    sunlapse::VideoReader reader(file.string());
    // The reader must refuse frames too large to be footage.
    if (static_cast<int64_t>(reader.width()) * reader.height() >
        sunlapse::VideoReader::kMaxFramePixels) {
      std::fprintf(stderr, "accepted a %dx%d frame\n", reader.width(),
                   reader.height());
      __builtin_trap();
    }
    cv::Mat bgr;
    for (int i = 0; i < 50 && reader.Read(&bgr); ++i) {
      if (!bgr.empty() &&
          (bgr.cols != reader.width() || bgr.rows != reader.height() ||
           bgr.type() != CV_8UC3)) {
        __builtin_trap();  // Read() broke its contract
      }
    }
    reader.Seek(0);
    reader.Read(&bgr);
    if (reader.num_frames() > 2) {
      reader.Seek(reader.num_frames() - 1);
      reader.Read(&bgr);
    }
    reader.Seek(1);
    reader.Read(&bgr);
  } catch (const std::invalid_argument&) {
    // Documented: the file cannot be decoded.
  }
  fs::remove(file);
  return 0;
}
