// The GPU chain of pseudo3d-bench's scene mode (scene_chain_gpu.h).
#include "scene_chain_gpu.h"

#include <stdexcept>
#include <string>

#include "bars.h"
#include "bars_gpu.h"
#include "bilateral_gpu.h"
#include "change_gpu.h"
#include "depth_estimate_gpu.h"
#include "warp_gpu.h"

namespace p3d::bench {

namespace {

void check(const CudaStatus &st) {
  if (!st.ok()) throw std::runtime_error(st.message());
}
void check(cudaError_t e, const char *what) {
  if (e != cudaSuccess) throw std::runtime_error(std::string(what) + ": " + cudaGetErrorName(e));
}

// A stage's planes, recycled as the elements' DepthPlanePool recycles them:
// each frame's plane is another than the one before, which a stage holds.
constexpr int kPoolPlanes = 3;

}  // namespace

struct GpuSceneChain::Impl {
  StageParams p;
  bool adaptive;
  float tolerance;
  int width, height;
  cudaStream_t stream = nullptr;
  cudaEvent_t marks[4] = {};
  DepthEstimatorGpu estimator;
  BilateralFilterGpu filter;
  WarpRendererGpu warp;
  DevDepth depth_planes[kPoolPlanes], filter_planes[kPoolPlanes];
  DevFrame outputs[kPoolPlanes];
  int frames = 0;
  // Adaptive: each stage's inputs (the frame's copy on the device, the
  // tiles that changed), the filter's dirty tiles, the warp's kept output.
  FrameHistoryGpu depth_frame, filter_frame, warp_frame;
  ChangeMapGpu depth_changes, filter_changes, warp_changes, dirty;
  KeptOutputGpu kept;
  ChangeBackOff depth_backoff, filter_backoff, warp_backoff;
  bool filter_has_last = false;  // the filter holds its previous output
  double warp_rows = 1;          // warp_rows_share()
  HostFrame host_out;
  // crop-bars=auto (adaptive off): the bars and the picture between them.
  bool crop = false;
  BarCountsGpu bar_counts;
  BarTracker bars;
  PixelRect rect;
  ActiveWarpGpu active_warp;

  // After the frame's last event: each stage's time between the marks,
  // the output (pool slot k) read back.
  void end_frame(int k, StageMs *ms) {
    float t[3] = {0, 0, 0};
    for (int i = 0; i < 3; ++i) check(cudaEventElapsedTime(&t[i], marks[i], marks[i + 1]), "cudaEventElapsedTime");
    ms->depth = t[0];
    ms->filter = t[1];
    ms->warp = t[2];
    check(outputs[k].download(&host_out));
    ++frames;
  }

  ~Impl() {
    bar_counts.reset();
    for (cudaEvent_t e : marks)
      if (e) cudaEventDestroy(e);
    if (stream) cudaStreamDestroy(stream);
  }
};

GpuSceneChain::GpuSceneChain(const StageParams &p, int width, int height, PixelFormat input, bool adaptive,
                             float tolerance, bool crop)
    : impl_(std::make_unique<Impl>()) {
  Impl &s = *impl_;
  if (adaptive && crop) throw std::runtime_error("the GPU scene chain crops the bars with adaptive off only");
  s.crop = crop;
  s.rect = whole_picture(width, height);
  s.p = p;
  s.p.depth = frame_scaled(p.depth, width, height);  // as the elements scale them
  s.p.filter = frame_scaled(p.filter, width, height);
  s.adaptive = adaptive;
  s.tolerance = tolerance;
  s.width = width;
  s.height = height;
  check(cudaStreamCreateWithFlags(&s.stream, cudaStreamNonBlocking), "cudaStreamCreateWithFlags");
  for (cudaEvent_t &e : s.marks) check(cudaEventCreate(&e), "cudaEventCreate");
  const int depth_shift = block_grid_shift(s.p.depth, width, height);
  const int filter_shift = bilateral_grid_shift(bilateral_sanitize(s.p.filter), width, height);
  int ow = 0, oh = 0;
  pack_size(s.p.pack.layout, width, height, &ow, &oh);
  for (int k = 0; k < kPoolPlanes; ++k) {
    check(s.depth_planes[k].allocate(width, height, depth_shift));
    check(s.filter_planes[k].allocate(width, height, filter_shift));
    check(s.outputs[k].allocate(stereo_format(input), ow, oh));
  }
}

GpuSceneChain::~GpuSceneChain() = default;
GpuSceneChain::GpuSceneChain(GpuSceneChain &&) noexcept = default;

namespace {

// DepthPlane::set_active on the device: 0 in the grid's cells outside r.
void zero_outside(DepthGrid<float> g, PixelRect r, cudaStream_t stream) {
  for (const PixelRect &b : cells_outside(r, g.shift, g.cells.width, g.cells.height))
    if (!b.empty())
      check(cudaMemset2DAsync(g.cells.row(b.y0) + b.x0, g.cells.pitch, 0, b.width() * sizeof(float), b.height(),
                              stream),
            "cudaMemset2DAsync");
}

}  // namespace

// crop-bars=auto with adaptive off, as the elements run it on CUDA memory:
// pseudo3ddepth's bar counts (read back at the next frame) and
// frame_rect, pseudo3dfilter's filter_rect, pseudo3dwarp's ActiveWarpGpu
// inside the rect.
void GpuSceneChain::frame_cropped(const FrameView &src, StageMs *ms) {
  Impl &s = *impl_;
  const int k = s.frames % kPoolPlanes;
  const DepthGrid<float> depth = s.depth_planes[k].view, filtered = s.filter_planes[k].view;
  const FrameView out = s.outputs[k].view;
  const PixelRect whole = whole_picture(src.width, src.height);
  check(cudaEventRecord(s.marks[0], s.stream), "cudaEventRecord");
  // pseudo3ddepth
  auto observe_queued = [&s] {  // the counts last queued, into the tracker
    BarCounts counts;
    CudaStatus st;
    if (!s.bar_counts.take(&counts, &st)) throw std::runtime_error("no bar counts queued");
    check(st);
    s.bars.observe(counts);
  };
  if (s.bars.previous_due()) observe_queued();  // the previous frame's, queued then
  check(s.bar_counts.count(src, bar_luma_threshold(s.p.yuv), s.stream));
  if (s.bars.counted()) observe_queued();  // the first frame: its own, waited for
  PixelRect rect = s.bars.active(src.width, src.height);
  const int block_shift = block_grid_shift(s.p.depth, rect.width(), rect.height());
  rect = rect_on_cells(rect, block_shift, src.width, src.height);
  if (rect != s.rect) {
    s.estimator.reset();
    s.rect = rect;
  }
  zero_outside(depth, rect, s.stream);
  check(s.estimator.estimate(s.p.depth, sub_frame(src, rect), sub_grid(depth, rect), s.stream));
  check(s.bar_counts.join(s.stream));
  check(cudaEventRecord(s.marks[1], s.stream), "cudaEventRecord");
  // pseudo3dfilter
  const int cell_shift = bilateral_grid_shift(bilateral_sanitize(s.p.filter), rect.width(), rect.height());
  const PixelRect frect = sub_grid_fits(depth, rect) ? rect_on_cells(rect, cell_shift, src.width, src.height) : whole;
  zero_outside(filtered, frect, s.stream);
  check(s.filter.run(s.p.filter, sub_frame(src, frect), sub_grid(as_const(depth), frect), sub_grid(filtered, frect),
                     s.stream));
  check(cudaEventRecord(s.marks[2], s.stream), "cudaEventRecord");
  // pseudo3dwarp
  const PixelRect wrect = sub_grid_fits(filtered, frect) ? frect : whole;
  if (wrect != whole)
    check(s.active_warp.render(s.warp, s.p.warp, s.p.pack, src, s.p.yuv, as_const(filtered), wrect, out, s.stream));
  else
    check(s.warp.render_packed(s.p.warp, s.p.pack, src, s.p.yuv, as_const(filtered), out, s.stream));
  check(cudaEventRecord(s.marks[3], s.stream), "cudaEventRecord");
  check(cudaEventSynchronize(s.marks[3]), "cudaEventSynchronize");
  s.end_frame(k, ms);
}

void GpuSceneChain::frame(const FrameView &src, StageMs *ms) {
  if (impl_->crop) {
    frame_cropped(src, ms);
    return;
  }
  Impl &s = *impl_;
  const int k = s.frames % kPoolPlanes, prev = (s.frames + kPoolPlanes - 1) % kPoolPlanes;
  const bool first = s.frames == 0;
  const DepthGrid<float> depth = s.depth_planes[k].view, filtered = s.filter_planes[k].view;
  const FrameView out = s.outputs[k].view;
  // Which stages compare this frame (ChangeBackOff); the others compute it
  // whole with their histories reset, as the elements do.
  const bool depth_compares = s.adaptive && s.depth_backoff.compare_next();
  const bool filter_compares =
      s.adaptive && filter_compares_on_gpu(s.filter_planes[k].view.shift) && s.filter_backoff.compare_next();
  const bool warp_compares = s.adaptive && s.warp_backoff.compare_next();
  if (!depth_compares) s.depth_frame.reset();
  if (!filter_compares) {
    s.filter_frame.reset();
    s.filter_has_last = false;
  }
  if (!warp_compares) {
    s.warp_frame.reset();
    s.kept.reset();
  }
  check(cudaEventRecord(s.marks[0], s.stream), "cudaEventRecord");
  // pseudo3ddepth
  if (depth_compares) {
    check(s.depth_frame.compare(src, s.tolerance, s.depth_changes, s.stream));
    check(s.depth_changes.summarize(s.stream));
    const TileFlags changed = s.depth_changes.flags();
    check(s.estimator.estimate(s.p.depth, src, depth, s.stream, &changed));
  } else {
    check(s.estimator.estimate(s.p.depth, src, depth, s.stream));
  }
  check(cudaEventRecord(s.marks[1], s.stream), "cudaEventRecord");
  // pseudo3dfilter: the frame's and the depth's changes within its reach,
  // the rest copied from its previous output plane.
  const bool filter_whole = !filter_compares || !s.filter_has_last;
  if (filter_compares) {
    check(s.filter_frame.compare(src, s.tolerance, s.filter_changes, s.stream));
    if (first)
      check(s.filter_changes.fill(true, s.stream));
    else
      check(mark_grid_changes_gpu(as_const(s.depth_planes[prev].view), as_const(depth), s.filter_changes, s.stream));
  }
  if (!filter_whole) {
    const int reach = bilateral_reach(s.p.filter, s.width, s.height);
    check(dilate_gpu(s.filter_changes, reach, reach, s.dirty, s.stream));
    check(s.dirty.summarize(s.stream));
    check(s.filter.run(s.p.filter, src, as_const(depth), filtered, s.stream, s.dirty.flags(),
                       as_const(s.filter_planes[prev].view)));
  } else {
    check(s.filter.run(s.p.filter, src, as_const(depth), filtered, s.stream));
  }
  check(cudaEventRecord(s.marks[2], s.stream), "cudaEventRecord");
  // pseudo3dwarp
  if (warp_compares) {
    check(s.warp_frame.compare(src, s.tolerance, s.warp_changes, s.stream));
    if (first)
      check(s.warp_changes.fill(true, s.stream));
    else
      check(mark_grid_changes_gpu(as_const(s.filter_planes[prev].view), as_const(filtered), s.warp_changes, s.stream));
    check(s.kept.decide(s.warp_changes, out, false, s.stream, warp_rows_reach(s.p.warp, src.width, src.height)));
    check(s.warp.render_packed(s.p.warp, s.p.pack, src, s.p.yuv, as_const(filtered), out, s.stream, nullptr,
                               s.kept.gate()));
    check(s.kept.finish(out, s.stream));
  } else {
    check(s.warp.render_packed(s.p.warp, s.p.pack, src, s.p.yuv, as_const(filtered), out, s.stream));
  }
  check(cudaEventRecord(s.marks[3], s.stream), "cudaEventRecord");
  check(cudaEventSynchronize(s.marks[3]), "cudaEventSynchronize");
  if (depth_compares && s.depth_frame.compared()) s.depth_backoff.observe(s.depth_changes.last_share() > 0);
  if (!filter_whole && s.filter_frame.compared()) s.filter_backoff.observe(s.dirty.last_share() > 0);
  const bool warp_compared = warp_compares && s.warp_frame.compared() && !first;
  s.warp_rows = warp_compared ? s.kept.last_rows_share() : 1.0;
  if (warp_compared) s.warp_backoff.observe(s.kept.last_busy());
  s.filter_has_last = filter_compares;
  s.end_frame(k, ms);
}

const HostFrame &GpuSceneChain::output() const { return impl_->host_out; }
double GpuSceneChain::warp_rows_share() const { return impl_->warp_rows; }

}  // namespace p3d::bench
