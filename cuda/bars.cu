// Bar counts and the warp inside an active rect on the device
// (cuda/bars_gpu.h).
#include <cstring>

#include "bars_gpu.h"
#include "pack_gpu.h"

namespace p3d {

namespace {

constexpr int kCountColumns = 128;  // threads a block: one column each
constexpr int kCountRows = 64;      // rows a block walks

// A block counts kCountRows rows of kCountColumns columns: each warp adds
// the bright pixels of its 32 columns of a row to the row's count (one
// atomic a warp and row), each thread its column's to the column's count.
// A plain launch: a memset comes before it.
__global__ void bar_counts_kernel(const FrameView f, int luma_threshold, uint32_t *rows, uint32_t *cols) {
  const int x = blockIdx.x * kCountColumns + threadIdx.x;
  const int y0 = blockIdx.y * kCountRows;
  const int y1 = min(y0 + kCountRows, f.height);
  uint32_t column = 0;
  for (int y = y0; y < y1; ++y) {
    const bool bright = x < f.width && bar_pixel_bright(f, x, y, luma_threshold);
    column += bright;
    const unsigned in_warp = __popc(__ballot_sync(0xffffffffu, bright));
    if ((threadIdx.x & 31) == 0 && in_warp) atomicAdd(rows + y, in_warp);
  }
  if (x < f.width && column) atomicAdd(cols + x, column);
}

// Both views of a pixel outside the rect: the source converted.
// A plain launch (after the warp's kernels and copies).
__global__ void views_outside_kernel(const FrameView src, const YuvToRgb m, const PixelRect active,
                                     const FrameView pair, StageGate gate) {
  if (gate.closed()) return;
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= src.width || y >= src.height) return;
  if (x >= active.x0 && x < active.x1 && y >= active.y0 && y < active.y1) return;
  const Rgba c = load_rgba(src, x, y, m);
  store_rgba(pair, x, y, c);
  store_rgba(pair, src.width + x, y, c);
}

}  // namespace

CudaStatus BarCountsGpu::count(const FrameView &frame, int luma_threshold, cudaStream_t stream) {
  if (!kernels_take(frame.format))
    return CudaStatus{cudaErrorInvalidValue, "BarCountsGpu::count: the kernels take 8-bit frames", __FILE__, __LINE__};
  const size_t values = static_cast<size_t>(frame.width) + frame.height;
  P3D_CUDA_TRY_STATUS(counts_.ensure(values * sizeof(uint32_t)));
  if (host_values_ < values) {
    if (host_) cudaFreeHost(host_);
    host_ = nullptr;
    host_values_ = 0;
    P3D_CUDA_TRY_ALLOC(cudaMallocHost(&host_, values * sizeof(uint32_t)), values * sizeof(uint32_t));
    host_values_ = values;
  }
  if (!done_) P3D_CUDA_TRY(cudaEventCreateWithFlags(&done_, cudaEventDisableTiming));
  uint32_t *rows = counts_.as<uint32_t>(), *cols = rows + frame.height;
  P3D_CUDA_TRY(cudaMemsetAsync(rows, 0, values * sizeof(uint32_t), stream));
  const dim3 grid((frame.width + kCountColumns - 1) / kCountColumns, (frame.height + kCountRows - 1) / kCountRows);
  bar_counts_kernel<<<grid, kCountColumns, 0, stream>>>(frame, luma_threshold, rows, cols);
  P3D_CUDA_TRY_LAUNCH(bar_counts_kernel);
  P3D_CUDA_TRY(cudaMemcpyAsync(host_, rows, values * sizeof(uint32_t), cudaMemcpyDeviceToHost, stream));
  P3D_CUDA_TRY(cudaEventRecord(done_, stream));
  pending_ = true;
  width_ = frame.width;
  height_ = frame.height;
  return {};
}

bool BarCountsGpu::take(BarCounts *counts, CudaStatus *status) {
  *status = {};
  if (!pending_) return false;
  pending_ = false;
  const cudaError_t e = cudaEventSynchronize(done_);
  if (e != cudaSuccess) {
    *status = CudaStatus{e, "cudaEventSynchronize(bar counts)", __FILE__, __LINE__};
    return false;
  }
  counts->rows.assign(host_, host_ + height_);
  counts->cols.assign(host_ + height_, host_ + height_ + width_);
  return true;
}

void BarCountsGpu::reset() {
  if (done_) {
    cudaEventSynchronize(done_);  // the copy into host_ must be over before it is freed
    cudaEventDestroy(done_);
    done_ = nullptr;
  }
  if (host_) cudaFreeHost(host_);
  host_ = nullptr;
  host_values_ = 0;
  counts_.release();
  pending_ = false;
}

CudaStatus views_outside_gpu(const FrameView &src, const YuvToRgb &m, PixelRect active, const FrameView &pair,
                             cudaStream_t stream, StageGate gate) {
  const dim3 block(32, 8), grid((src.width + 31) / 32, (src.height + 7) / 8);
  views_outside_kernel<<<grid, block, 0, stream>>>(src, m, active, pair, gate);
  P3D_CUDA_TRY_LAUNCH(views_outside_kernel);
  return {};
}

namespace {

// A packed RGB frame in a device buffer grown to hold it.
CudaStatus buffer_frame(DeviceBuffer &buf, PixelFormat format, int width, int height, FrameView *f) {
  f->format = format;
  f->width = width;
  f->height = height;
  f->stride[0] = 4 * width;
  P3D_CUDA_TRY_STATUS(buf.ensure(static_cast<size_t>(f->stride[0]) * height));
  f->plane[0] = buf.as<uint8_t>();
  return {};
}

}  // namespace

CudaStatus ActiveWarpGpu::render(WarpRendererGpu &warp, const WarpParams &params, const PackParams &pack,
                                 const FrameView &src, const YuvToRgb &m, DepthGrid<const float> depth,
                                 PixelRect rect, const FrameView &dst, cudaStream_t stream, StageGate gate) {
  if (rect.empty() || rect.x0 < 0 || rect.y0 < 0 || rect.x1 > src.width || rect.y1 > src.height ||
      depth.width != src.width || depth.height != src.height || !sub_grid_fits(depth, rect))
    return CudaStatus{cudaErrorInvalidValue, "active rect within the frame and on the depth cells", __FILE__,
                      __LINE__};
  // The pair as the CPU path keeps it (StereoPacking::pair_target): dst
  // itself where the layout is the pair, else a packed RGB pair.
  FrameView pair = dst;
  const bool pair_is_dst = pack_is_identity(pack) && is_packed_rgb(dst.format);
  if (!pair_is_dst)
    P3D_CUDA_TRY_STATUS(buffer_frame(pair_, is_packed_rgb(dst.format) ? dst.format : PixelFormat::RGBA,
                                     2 * src.width, src.height, &pair));
  const WarpParams active_params = active_warp_params(params, src.width, rect.width());
  const FrameView sub_src = sub_frame(src, rect);
  const DepthGrid<const float> sub_depth = sub_grid(depth, rect);
  if (rect.x0 == 0 && rect.x1 == src.width) {
    P3D_CUDA_TRY_STATUS(warp.render(active_params, sub_src, m, sub_depth,
                                    sub_frame(pair, PixelRect{0, rect.y0, pair.width, rect.y1}), stream, nullptr,
                                    gate));
  } else {
    FrameView active_pair;
    P3D_CUDA_TRY_STATUS(buffer_frame(active_pair_, pair.format, 2 * rect.width(), rect.height(), &active_pair));
    P3D_CUDA_TRY_STATUS(warp.render(active_params, sub_src, m, sub_depth, active_pair, stream, nullptr, gate));
    const size_t view_bytes = 4 * static_cast<size_t>(rect.width());
    uint8_t *to = pair.plane[0] + static_cast<size_t>(rect.y0) * pair.stride[0];
    P3D_CUDA_TRY_STATUS(copy_rows_gated(to + 4 * static_cast<size_t>(rect.x0), pair.stride[0], active_pair.plane[0],
                                        active_pair.stride[0], view_bytes, rect.height(), gate, stream));
    P3D_CUDA_TRY_STATUS(copy_rows_gated(to + 4 * static_cast<size_t>(src.width + rect.x0), pair.stride[0],
                                        active_pair.plane[0] + view_bytes, active_pair.stride[0], view_bytes,
                                        rect.height(), gate, stream));
  }
  P3D_CUDA_TRY_STATUS(views_outside_gpu(src, m, rect, pair, stream, gate));
  if (!pair_is_dst) P3D_CUDA_TRY_STATUS(pack_gpu(pack, pair, dst, stream, gate));
  return {};
}

}  // namespace p3d
