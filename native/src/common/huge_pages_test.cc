#include "sunlapse/common/huge_pages.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace sunlapse {
namespace {

constexpr size_t kHuge = size_t{2} << 20;

TEST(AdviseHugePages, AdvisesOnlyTheWholeHugePagesInside) {
  EXPECT_EQ(AdviseHugePages(nullptr, 8 * kHuge), 0u);
  std::vector<uint8_t> small(kHuge / 2, 7);
  EXPECT_EQ(AdviseHugePages(small.data(), small.size()), 0u);

  std::vector<uint8_t> big(5 * kHuge + 12345, 3);
  const size_t advised = AdviseHugePages(big.data(), big.size());
  // Whole 2 MB pages, never past the buffer: at least 4 of them fit
  // whatever its alignment (none where the kernel has no such pages).
  EXPECT_EQ(advised % kHuge, 0u);
  EXPECT_LE(advised, big.size());
#if defined(__linux__)
  if (advised != 0) {
    EXPECT_GE(advised, 4 * kHuge);
  }
#endif
  for (size_t i = 0; i < big.size(); i += 4096) ASSERT_EQ(big[i], 3);
}

TEST(AdviseHugePages, ReserveHugeKeepsAVectorsContents) {
  std::vector<float> v = {1.f, 2.f, 3.f};
  ReserveHuge(&v, 3 * kHuge / sizeof(float));
  EXPECT_GE(v.capacity(), 3 * kHuge / sizeof(float));
  EXPECT_EQ(v, (std::vector<float>{1.f, 2.f, 3.f}));
  const float* before = v.data();
  ReserveHuge(&v, 10);  // room already: the vector is left alone
  EXPECT_EQ(v.data(), before);
}

}  // namespace
}  // namespace sunlapse
