// GPU side of the chained-launch tests (test_gpu_chained.cpp): kernels
// launched with launch_chained() (cuda/chained_launch.cuh).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "cuda_check.h"

namespace p3d::test {

// `rounds` rounds of a writer and a reader kernel, both launched chained
// one after the other on one stream, no host sync between rounds: the
// writer's blocks each wait about `spin_us` microseconds, then write the
// round number into `n` ints; the reader copies them into round r's row of
// the result. A reader that did not wait for its writer would copy the
// previous round's numbers. *out: rounds x n values; *chained: whether
// the launches really were chained (chained_launch_allowed()); *expected:
// whether they should have been, from the device's compute capability and
// the kernels' PTX version, read here on their own (sm_90 and later).
CudaStatus chained_writer_reader(int n, int rounds, int spin_us, std::vector<int32_t> *out, bool *chained,
                                 bool *expected);

// zero_chained() of `count` bytes at `offset` into a buffer of `size`
// bytes first set to 0xab; *out: the buffer afterwards.
CudaStatus zero_chained_into(size_t size, size_t offset, size_t count, std::vector<uint8_t> *out);

}  // namespace p3d::test
