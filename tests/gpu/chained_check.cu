#include "chained_check.h"

#include "chained_launch.cuh"
#include "device_buffer.h"

namespace p3d::test {
namespace {

__global__ void spin_then_write(int32_t *data, int n, int round, long long spin_cycles) {
  chained_kernel_start();
  const long long t0 = clock64();
  while (clock64() - t0 < spin_cycles) {
  }
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) data[i] = round;
}

__global__ void copy_row(const int32_t *data, int n, int32_t *row) {
  chained_kernel_start();
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) row[i] = data[i];
}

}  // namespace

CudaStatus chained_writer_reader(int n, int rounds, int spin_us, std::vector<int32_t> *out, bool *chained,
                                 bool *expected) {
  int device = 0, clock_khz = 0, major = 0;
  P3D_CUDA_TRY(cudaGetDevice(&device));
  P3D_CUDA_TRY(cudaDeviceGetAttribute(&clock_khz, cudaDevAttrClockRate, device));
  P3D_CUDA_TRY(cudaDeviceGetAttribute(&major, cudaDevAttrComputeCapabilityMajor, device));
  if (clock_khz <= 0)  // no spin: the writer would not be slow enough to show a missing wait
    return CudaStatus{cudaErrorInvalidValue, "cudaDevAttrClockRate > 0", __FILE__, __LINE__};
  cudaFuncAttributes a{};
  P3D_CUDA_TRY(cudaFuncGetAttributes(&a, reinterpret_cast<const void *>(copy_row)));
  *expected = major >= 9 && a.ptxVersion >= 90;
  const long long spin_cycles = static_cast<long long>(clock_khz) * spin_us / 1000;
  *chained = chained_launch_allowed(reinterpret_cast<const void *>(copy_row)) &&
             chained_launch_allowed(reinterpret_cast<const void *>(spin_then_write));
  DeviceBuffer data, rows;
  P3D_CUDA_TRY_STATUS(data.ensure(sizeof(int32_t) * n));
  P3D_CUDA_TRY_STATUS(rows.ensure(sizeof(int32_t) * n * static_cast<size_t>(rounds)));
  cudaStream_t stream = nullptr;
  P3D_CUDA_TRY(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking));
  const int threads = 256, blocks = (n + threads - 1) / threads;
  cudaError_t err = cudaMemsetAsync(data.get(), 0xff, sizeof(int32_t) * n, stream);  // -1: no round yet
  for (int r = 0; r < rounds && err == cudaSuccess; ++r) {
    err = launch_chained(spin_then_write, blocks, threads, 0, stream, data.as<int32_t>(), n, r, spin_cycles);
    if (err == cudaSuccess)
      err = launch_chained(copy_row, blocks, threads, 0, stream, data.as<const int32_t>(), n,
                           rows.as<int32_t>() + static_cast<size_t>(r) * n);
  }
  if (err == cudaSuccess) err = cudaStreamSynchronize(stream);
  cudaStreamDestroy(stream);
  P3D_CUDA_TRY(err);
  out->resize(static_cast<size_t>(n) * rounds);
  P3D_CUDA_TRY(cudaMemcpy(out->data(), rows.get(), sizeof(int32_t) * out->size(), cudaMemcpyDeviceToHost));
  return {};
}

CudaStatus zero_chained_into(size_t size, size_t offset, size_t count, std::vector<uint8_t> *out) {
  DeviceBuffer buf;
  P3D_CUDA_TRY_STATUS(buf.ensure(size));
  P3D_CUDA_TRY(cudaMemset(buf.get(), 0xab, size));
  P3D_CUDA_TRY(zero_chained(buf.as<uint8_t>() + offset, count, nullptr));
  P3D_CUDA_TRY(cudaDeviceSynchronize());
  out->resize(size);
  P3D_CUDA_TRY(cudaMemcpy(out->data(), buf.get(), size, cudaMemcpyDeviceToHost));
  return {};
}

}  // namespace p3d::test
