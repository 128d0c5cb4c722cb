// Folders for tests' files, removed when the test program ends.
#pragma once

#include <filesystem>
#include <string>

namespace sunlapse::testing {

// An empty folder named after `name` and the process (tests of several
// programs may run at once), made afresh.
std::filesystem::path TempDir(const std::string& name);

}  // namespace sunlapse::testing
