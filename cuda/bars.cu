// Bar counts and the warp inside an active rect on the device
// (cuda/bars_gpu.h).
#include <cstring>

#include "bars_gpu.h"
#include "bars_kernels.cuh"
#include "pack_gpu.h"

namespace p3d {

CudaStatus BarCountsGpu::count(const FrameView &frame, int luma_threshold, cudaStream_t stream) {
  // A count left untaken (a reset of the caller's order) may still be
  // copying into host_, perhaps from another stream: it ends first.
  if (pending_) {
    pending_ = false;
    P3D_CUDA_TRY(cudaEventSynchronize(done_));
  }
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
  if (!ready_) P3D_CUDA_TRY(cudaEventCreateWithFlags(&ready_, cudaEventDisableTiming));
  if (!side_) P3D_CUDA_TRY(cudaStreamCreateWithFlags(&side_, cudaStreamNonBlocking));
  // The side stream starts where the caller's is (the frame written).
  P3D_CUDA_TRY(cudaEventRecord(ready_, stream));
  P3D_CUDA_TRY(cudaStreamWaitEvent(side_, ready_, 0));
  unjoined_ = true;
  uint32_t *rows = counts_.as<uint32_t>(), *cols = rows + frame.height;
  P3D_CUDA_TRY(cudaMemsetAsync(rows, 0, values * sizeof(uint32_t), side_));
  P3D_CUDA_TRY_STATUS(is_deep(frame.format)
                          ? bars_detail::launch_bar_counts_deep(frame, luma_threshold, rows, cols, side_)
                          : bars_detail::launch_bar_counts_of(frame, luma_threshold, rows, cols, side_));
  P3D_CUDA_TRY(cudaMemcpyAsync(host_, rows, values * sizeof(uint32_t), cudaMemcpyDeviceToHost, side_));
  P3D_CUDA_TRY(cudaEventRecord(done_, side_));
  pending_ = true;
  width_ = frame.width;
  height_ = frame.height;
  return {};
}

CudaStatus BarCountsGpu::join(cudaStream_t stream) {
  if (!unjoined_) return {};
  unjoined_ = false;
  P3D_CUDA_TRY(cudaStreamWaitEvent(stream, done_, 0));
  return {};
}

void BarCountsGpu::settle() {
  if (!unjoined_) return;
  unjoined_ = false;
  cudaEventSynchronize(done_);  // a failure shows again at take()
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
  counts->band_cols.clear();  // not bar_counts_cpu's: its next call counts every band
  return true;
}

void BarCountsGpu::reset() {
  if (done_) {
    cudaEventSynchronize(done_);  // the copy into host_ must be over before it is freed
    cudaEventDestroy(done_);
    done_ = nullptr;
  }
  if (ready_) cudaEventDestroy(ready_);
  ready_ = nullptr;
  if (side_) cudaStreamDestroy(side_);
  side_ = nullptr;
  unjoined_ = false;
  if (host_) cudaFreeHost(host_);
  host_ = nullptr;
  host_values_ = 0;
  counts_.release();
  pending_ = false;
}

CudaStatus views_outside_gpu(const FrameView &src, const YuvToRgb &m, PixelRect active, const FrameView &pair,
                             cudaStream_t stream, StageGate gate) {
  if (is_deep(src.format)) return bars_detail::launch_views_outside_deep(src, m, active, pair, stream, gate);
  return bars_detail::launch_views_outside_of<Rgba>(src, m, active, pair, stream, gate);
}

namespace {

// A packed RGB frame in a device buffer grown to hold it.
CudaStatus buffer_frame(DeviceBuffer &buf, PixelFormat format, int width, int height, FrameView *f) {
  f->format = format;
  f->width = width;
  f->height = height;
  f->stride[0] = packed_pixel_bytes(format) * width;
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
  // The gate's rows are rendered into the pairs kept here: dst keeps none.
  FrameView pair = dst;
  const bool pair_is_dst = pack_is_identity(pack) && is_packed_rgb(dst.format);
  const size_t had_pair = pair_.size(), had_active = active_pair_.size();
  if (pair_is_dst) gate = gate.every_row();
  if (!pair_is_dst)
    P3D_CUDA_TRY_STATUS(buffer_frame(pair_, is_packed_rgb(dst.format) ? dst.format
                                            : is_deep(dst.format)     ? PixelFormat::RGBA64
                                                                      : PixelFormat::RGBA,
                                     2 * src.width, src.height, &pair));
  const WarpParams active_params = active_warp_params(params, src.width, rect.width());
  const FrameView sub_src = sub_frame(src, rect);
  const DepthGrid<const float> sub_depth = sub_grid(depth, rect);
  if (pair_.size() != had_pair) gate = gate.every_row();  // a new pair holds no rows
  if (rect.x0 == 0 && rect.x1 == src.width) {
    P3D_CUDA_TRY_STATUS(warp.render(active_params, sub_src, m, sub_depth,
                                    sub_frame(pair, PixelRect{0, rect.y0, pair.width, rect.y1}), stream, nullptr,
                                    gate.from_row(rect.y0)));
  } else {
    FrameView active_pair;
    P3D_CUDA_TRY_STATUS(buffer_frame(active_pair_, pair.format, 2 * rect.width(), rect.height(), &active_pair));
    if (active_pair_.size() != had_active) gate = gate.every_row();
    P3D_CUDA_TRY_STATUS(
        warp.render(active_params, sub_src, m, sub_depth, active_pair, stream, nullptr, gate.from_row(rect.y0)));
    const size_t px = static_cast<size_t>(packed_pixel_bytes(pair.format)), view_bytes = px * rect.width();
    uint8_t *to = pair.plane[0] + static_cast<size_t>(rect.y0) * pair.stride[0];
    P3D_CUDA_TRY_STATUS(copy_rows_gated(to + px * rect.x0, pair.stride[0], active_pair.plane[0],
                                        active_pair.stride[0], view_bytes, rect.height(), gate, stream));
    P3D_CUDA_TRY_STATUS(copy_rows_gated(to + px * (src.width + rect.x0), pair.stride[0],
                                        active_pair.plane[0] + view_bytes, active_pair.stride[0], view_bytes,
                                        rect.height(), gate, stream));
  }
  P3D_CUDA_TRY_STATUS(views_outside_gpu(src, m, rect, pair, stream, gate));
  if (!pair_is_dst) P3D_CUDA_TRY_STATUS(pack_gpu(pack, pair, dst, stream, gate));
  return {};
}

}  // namespace p3d
