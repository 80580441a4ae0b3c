// Chained launches (cuda/chained_launch.cuh): a kernel launched chained to
// the one before it still sees all of that kernel's writes, and
// zero_chained() clears exactly its bytes. The pipeline's own kernels are
// launched this way, and the other suites compare their results with the
// CPU references; these tests pin the mechanism down on its own, with a
// writer slow enough that a reader that did not wait would copy stale data.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "chained_check.h"

namespace {

TEST(GpuChainedLaunch, ReaderSeesItsWritersData) {
  constexpr int kN = 64 * 256, kRounds = 8, kSpinUs = 50;
  std::vector<int32_t> rows;
  bool chained = false, expected = false;
  const p3d::CudaStatus st = p3d::test::chained_writer_reader(kN, kRounds, kSpinUs, &rows, &chained, &expected);
  ASSERT_TRUE(st.ok()) << st.message();
  // On sm_90 and later code the launches overlap; elsewhere they are plain
  // and the test shows the fallback still orders them.
  RecordProperty("chained", chained ? "yes" : "no");
  EXPECT_EQ(chained, expected) << "chained_launch_allowed() against the device and the kernels' PTX version";
  long long stale = 0;
  for (int r = 0; r < kRounds; ++r)
    for (int i = 0; i < kN; ++i) stale += rows[static_cast<size_t>(r) * kN + i] != r;
  EXPECT_EQ(stale, 0) << "values a reader copied before its writer had written them (chained: " << chained << ")";
}

TEST(GpuChainedLaunch, ZeroChainedClearsExactlyItsBytes) {
  struct Case {
    size_t size, offset, count;
  };
  // Odd offsets and sizes; one larger than the kernel's 1024 x 256 threads
  // (its grid-stride loop); an empty one.
  for (const Case c : {Case{4096, 3, 1001}, Case{(1u << 20) + 64, 7, (1u << 20) + 17}, Case{64, 5, 0}}) {
    std::vector<uint8_t> out;
    const p3d::CudaStatus st = p3d::test::zero_chained_into(c.size, c.offset, c.count, &out);
    ASSERT_TRUE(st.ok()) << st.message();
    size_t wrong = 0;
    for (size_t i = 0; i < c.size; ++i) {
      const bool inside = i >= c.offset && i < c.offset + c.count;
      wrong += out[i] != (inside ? 0 : 0xab);
    }
    EXPECT_EQ(wrong, 0u) << "size " << c.size << " offset " << c.offset << " count " << c.count;
  }
}

}  // namespace
