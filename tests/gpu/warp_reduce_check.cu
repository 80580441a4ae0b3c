#include "warp_reduce_check.h"

#include "device_buffer.h"
#include "warp_reduce.cuh"

namespace p3d::test {

namespace {

__global__ void warp_reductions_kernel(const uint32_t *in, uint32_t *out, int warps) {
  const int w = blockIdx.x * (blockDim.x / 32) + threadIdx.x / 32;
  if (w >= warps) return;  // whole warps leave together: the full mask holds
  const uint32_t v = in[32 * w + threadIdx.x % 32];
  const uint32_t r[4] = {warp_reduce_sum(v), warp_reduce_sum_shuffle(v), warp_reduce_max(v),
                         warp_reduce_max_shuffle(v)};
  if (threadIdx.x % 32 == 0)
    for (int k = 0; k < 4; ++k) out[4 * w + k] = r[k];
}

}  // namespace

CudaStatus warp_reductions_gpu(const std::vector<uint32_t> &in, std::vector<uint32_t> *out) {
  const int warps = static_cast<int>(in.size() / 32);
  out->assign(static_cast<size_t>(warps) * 4, 0);
  DeviceBuffer d_in, d_out;
  P3D_CUDA_TRY_STATUS(d_in.ensure(in.size() * sizeof(uint32_t)));
  P3D_CUDA_TRY_STATUS(d_out.ensure(out->size() * sizeof(uint32_t)));
  P3D_CUDA_TRY(cudaMemcpy(d_in.get(), in.data(), in.size() * sizeof(uint32_t), cudaMemcpyHostToDevice));
  constexpr int kWarpsPerBlock = 4;
  warp_reductions_kernel<<<(warps + kWarpsPerBlock - 1) / kWarpsPerBlock, 32 * kWarpsPerBlock>>>(
      d_in.as<const uint32_t>(), d_out.as<uint32_t>(), warps);
  P3D_CUDA_TRY_LAUNCH(warp_reductions_kernel);
  P3D_CUDA_TRY(cudaMemcpy(out->data(), d_out.get(), out->size() * sizeof(uint32_t), cudaMemcpyDeviceToHost));
  return {};
}

}  // namespace p3d::test
