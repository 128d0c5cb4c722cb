#include "temp_dir.h"

#include <unistd.h>

#include <system_error>
#include <vector>

namespace sunlapse::testing {
namespace {
namespace fs = std::filesystem;

struct Made {
  std::vector<fs::path> dirs;
  ~Made() {
    std::error_code ignored;
    for (const fs::path& d : dirs) fs::remove_all(d, ignored);
  }
};
Made made;

}  // namespace

fs::path TempDir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() /
                     ("sunlapse_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  made.dirs.push_back(d);
  return d;
}

}  // namespace sunlapse::testing
