#include "sunlapse/common/require.h"

#include <stdexcept>

namespace sunlapse {

void Require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

}  // namespace sunlapse
