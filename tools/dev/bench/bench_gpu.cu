// GPU timings for pseudo3d-bench (see bench_gpu.h).
//
// Every timed iteration is bracketed by its own cudaEvent pair and all
// iterations are queued back to back without host synchronisation, so the
// times are GPU times of the stage, not of the host's launch loop; only the
// NeighborAverage fill synchronises inside the warp, as it does in the
// element. Inputs are uploaded up front (4 frames rotate, so a frame is not
// simply still in L2 from the previous iteration) and each stage's inputs are
// the real outputs of the stages before it, computed once before timing.
#include "bench_gpu.h"

#include <utility>

#include <cuda_runtime_api.h>

#include "bilateral_gpu.h"
#include "cuda_check.h"
#include "depth_estimate_gpu.h"
#include "device_frames.h"
#include "pack_gpu.h"
#include "warp_gpu.h"

namespace p3d::bench {
namespace {

// The input frame converted to RGBA, alone: what the colour conversion the
// warp does on its source rows costs on its own.
__global__ void convert_kernel(FrameView in, YuvToRgb m, FrameView out) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= in.width || y >= in.height) return;
  store_rgba(out, x, y, load_rgba(in, x, y, m));
}

CudaStatus convert_gpu(const FrameView &in, const YuvToRgb &m, const FrameView &out, cudaStream_t stream) {
  const dim3 block(32, 8);
  const dim3 grid((in.width + block.x - 1) / block.x, (in.height + block.y - 1) / block.y);
  convert_kernel<<<grid, block, 0, stream>>>(in, m, out);
  P3D_CUDA_TRY_LAUNCH(convert_kernel);
  return {};
}

// Owned stream and events; destruction errors cannot be reported from a
// destructor and leave nothing behind that matters for a benchmark.
class Stream {
 public:
  ~Stream() {
    if (s_) cudaStreamDestroy(s_);
  }
  CudaStatus create() {
    P3D_CUDA_TRY(cudaStreamCreateWithFlags(&s_, cudaStreamNonBlocking));
    return {};
  }
  cudaStream_t get() const { return s_; }

 private:
  cudaStream_t s_ = nullptr;
};

class EventPairs {
 public:
  ~EventPairs() {
    for (cudaEvent_t e : events_) cudaEventDestroy(e);
  }
  CudaStatus create(int pairs) {
    while (static_cast<int>(events_.size()) < 2 * pairs) {
      cudaEvent_t e = nullptr;
      P3D_CUDA_TRY(cudaEventCreate(&e));
      events_.push_back(e);
    }
    return {};
  }
  cudaEvent_t start(int i) const { return events_[2 * i]; }
  cudaEvent_t stop(int i) const { return events_[2 * i + 1]; }

 private:
  std::vector<cudaEvent_t> events_;
};

// Warm-up, then plan.iterations timed runs of op(i) (i counts on from the
// warm-up, so the frame rotation continues), each between its own events.
template <typename Op>
CudaStatus time_op(const Op &op, cudaStream_t stream, const TimingPlan &plan, const EventPairs &events,
                   std::vector<double> *ms) {
  for (int i = 0; i < plan.warmup; ++i) P3D_CUDA_TRY_STATUS(op(i));
  P3D_CUDA_TRY(cudaStreamSynchronize(stream));
  for (int i = 0; i < plan.iterations; ++i) {
    P3D_CUDA_TRY(cudaEventRecord(events.start(i), stream));
    P3D_CUDA_TRY_STATUS(op(plan.warmup + i));
    P3D_CUDA_TRY(cudaEventRecord(events.stop(i), stream));
  }
  P3D_CUDA_TRY(cudaStreamSynchronize(stream));
  ms->clear();
  for (int i = 0; i < plan.iterations; ++i) {
    float t = 0.f;
    P3D_CUDA_TRY(cudaEventElapsedTime(&t, events.start(i), events.stop(i)));
    ms->push_back(t);
  }
  return {};
}

// Everything one frame size needs on the device: the rotating inputs, each
// stage's precomputed inputs per frame, and scratch outputs for the timings.
struct SizeBench {
  std::vector<DevFrame> frames, stereo;
  std::vector<DevDepth> depth, filtered;
  DevDepth out_depth, out_filtered;
  DevFrame out_stereo, out_packed, out_rgba;
  DepthEstimatorGpu estimator;
  BilateralFilterGpu filter;
  WarpRendererGpu renderer;

  CudaStatus allocate(const StageParams &p, const std::vector<HostFrame> &host) {
    const int w = host[0].width(), h = host[0].height();
    const PixelFormat sf = stereo_format(host[0].format());
    // The grids the elements hand on (gst/depth_plane.h), or full-size maps.
    const int depth_shift = p.depth_grids ? block_grid_shift(p.depth, w, h) : 0;
    const int filtered_shift = p.depth_grids ? bilateral_grid_shift(bilateral_sanitize(p.filter), w, h) : 0;
    int pw = 0, ph = 0;
    pack_size(p.pack.layout, w, h, &pw, &ph);
    frames.resize(host.size());
    stereo.resize(host.size());
    depth.resize(host.size());
    filtered.resize(host.size());
    for (size_t k = 0; k < host.size(); ++k) {
      P3D_CUDA_TRY_STATUS(frames[k].upload(host[k]));
      P3D_CUDA_TRY_STATUS(stereo[k].allocate(sf, 2 * w, h));
      P3D_CUDA_TRY_STATUS(depth[k].allocate(w, h, depth_shift));
      P3D_CUDA_TRY_STATUS(filtered[k].allocate(w, h, filtered_shift));
    }
    P3D_CUDA_TRY_STATUS(out_depth.allocate(w, h, depth_shift));
    P3D_CUDA_TRY_STATUS(out_filtered.allocate(w, h, filtered_shift));
    P3D_CUDA_TRY_STATUS(out_stereo.allocate(sf, 2 * w, h));
    P3D_CUDA_TRY_STATUS(out_packed.allocate(sf, pw, ph));
    P3D_CUDA_TRY_STATUS(out_rgba.allocate(PixelFormat::RGBA, w, h));
    return {};
  }

  // Depth, filtered depth and stereo pair of every input frame.
  CudaStatus precompute(const StageParams &p, cudaStream_t s) {
    for (size_t k = 0; k < frames.size(); ++k) {
      P3D_CUDA_TRY_STATUS(estimator.estimate(p.depth, frames[k].view, depth[k].view, s));
      P3D_CUDA_TRY_STATUS(filter.run(p.filter, frames[k].view, as_const(depth[k].view), filtered[k].view, s));
      P3D_CUDA_TRY_STATUS(renderer.render(p.warp, frames[k].view, p.yuv, as_const(filtered[k].view),
                                          stereo[k].view, s));
    }
    P3D_CUDA_TRY(cudaStreamSynchronize(s));
    return {};
  }

  CudaStatus run_stage(const std::string &stage, const StageParams &p, int i, cudaStream_t s) {
    const size_t k = static_cast<size_t>(i) % frames.size();
    const FrameView &f = frames[k].view;
    if (stage == "convert") return convert_gpu(f, p.yuv, out_rgba.view, s);
    if (stage == "depth") return estimator.estimate(p.depth, f, out_depth.view, s);
    if (stage == "filter") return filter.run(p.filter, f, as_const(depth[k].view), out_filtered.view, s);
    if (stage == "warp") return renderer.render(p.warp, f, p.yuv, as_const(filtered[k].view), out_stereo.view, s);
    if (stage == "pack") return pack_gpu(p.pack, stereo[k].view, out_packed.view, s);
    if (stage == "warp-pack")
      return renderer.render_packed(p.warp, p.pack, f, p.yuv, as_const(filtered[k].view), out_packed.view, s);
    // chain: the warp and the pack as pseudo3dwarp runs them with a layout
    // (render_packed: fused where it can be, else the pair, then pack_gpu)
    P3D_CUDA_TRY_STATUS(estimator.estimate(p.depth, f, out_depth.view, s));
    P3D_CUDA_TRY_STATUS(filter.run(p.filter, f, as_const(out_depth.view), out_filtered.view, s));
    return renderer.render_packed(p.warp, p.pack, f, p.yuv, as_const(out_filtered.view), out_packed.view, s);
  }
};

CudaStatus time_stages(const StageParams &p, const std::vector<HostFrame> &host, const TimingPlan &plan,
                       std::vector<StageTimes> *out) {
  Stream stream;
  P3D_CUDA_TRY_STATUS(stream.create());
  EventPairs events;
  P3D_CUDA_TRY_STATUS(events.create(plan.iterations));
  SizeBench b;
  P3D_CUDA_TRY_STATUS(b.allocate(p, host));
  P3D_CUDA_TRY_STATUS(b.precompute(p, stream.get()));
  out->clear();
  for (const std::string &stage : stage_names()) {
    // "convert" times the 8-bit conversion kernel above; the chain of a
    // deep frame converts into 16-bit rows, which it does not time.
    if (stage == "convert" && is_deep(host[0].format())) continue;
    StageTimes t{stage, {}};
    auto op = [&](int i) { return b.run_stage(stage, p, i, stream.get()); };
    P3D_CUDA_TRY_STATUS(time_op(op, stream.get(), plan, events, &t.ms));
    out->push_back(std::move(t));
  }
  return {};
}

CudaStatus time_copy(size_t bytes, const TimingPlan &plan, std::vector<double> *ms) {
  Stream stream;
  P3D_CUDA_TRY_STATUS(stream.create());
  EventPairs events;
  P3D_CUDA_TRY_STATUS(events.create(plan.iterations));
  DeviceBuffer src, dst;
  P3D_CUDA_TRY_STATUS(src.ensure(bytes));
  P3D_CUDA_TRY_STATUS(dst.ensure(bytes));
  // Touch both buffers so the first timed copy does not pay for mapping pages.
  P3D_CUDA_TRY(cudaMemsetAsync(src.get(), 0x5a, bytes, stream.get()));
  P3D_CUDA_TRY(cudaMemsetAsync(dst.get(), 0, bytes, stream.get()));
  auto op = [&](int) -> CudaStatus {
    P3D_CUDA_TRY(cudaMemcpyAsync(dst.get(), src.get(), bytes, cudaMemcpyDeviceToDevice, stream.get()));
    return {};
  };
  return time_op(op, stream.get(), plan, events, ms);
}

bool report(const CudaStatus &st, std::string *error) {
  if (st.ok()) return true;
  *error = st.message();
  return false;
}

}  // namespace

bool gpu_present() { return cuda_device_present(); }

std::string gpu_name() {
  int dev = 0;
  cudaDeviceProp prop{};
  if (cudaGetDevice(&dev) != cudaSuccess || cudaGetDeviceProperties(&prop, dev) != cudaSuccess) return "";
  return prop.name;
}

bool gpu_time_copy(size_t bytes, const TimingPlan &plan, std::vector<double> *ms, std::string *error) {
  return report(time_copy(bytes, plan, ms), error);
}

bool gpu_time_stages(const StageParams &params, const std::vector<HostFrame> &frames, const TimingPlan &plan,
                     std::vector<StageTimes> *out, std::string *error) {
  if (frames.empty()) {
    *error = "no input frames";
    return false;
  }
  return report(time_stages(params, frames, plan, out), error);
}

}  // namespace p3d::bench
