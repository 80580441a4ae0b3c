// Runs the warp reductions of cuda/warp_reduce.cuh on the GPU, one warp per
// 32 values: for warp w, out[4w..4w+3] = warp_reduce_sum,
// warp_reduce_sum_shuffle, warp_reduce_max and warp_reduce_max_shuffle of
// in[32w..32w+31]. in.size() is a multiple of 32.
#pragma once

#include <cstdint>
#include <vector>

#include "cuda_check.h"

namespace p3d::test {

CudaStatus warp_reductions_gpu(const std::vector<uint32_t> &in, std::vector<uint32_t> *out);

}  // namespace p3d::test
