// Argument checks: a programmer's or caller's error throws
// std::invalid_argument naming what is wrong (Python sees ValueError).
#pragma once

#include <string>

namespace sunlapse {

// Throws std::invalid_argument(message) unless `ok`.
void Require(bool ok, const std::string& message);

}  // namespace sunlapse
