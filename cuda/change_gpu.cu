// The adaptive stages' bookkeeping on the device (cuda/change_gpu.h).
#include "change_gpu.h"

#include <algorithm>
#include <vector>

#include "change_compare.cuh"

namespace p3d {

using change_detail::KeptPlanes;

namespace {

constexpr int kThreads = 256;

unsigned blocks_for(long long items, int per_block) {
  return static_cast<unsigned>((items + per_block - 1) / per_block);
}

// A thread a cell: the tiles with a pixel of a cell that differs are
// marked (several threads may store the same 1).
// A plain launch (<<< >>>), as every kernel of this file.
__global__ void mark_grid_changes_kernel(DepthGrid<const float> a, DepthGrid<const float> b, TileFlags map) {
  const int cx = blockIdx.x * blockDim.x + threadIdx.x, cy = blockIdx.y * blockDim.y + threadIdx.y;
  if (cx >= a.cells.width || cy >= a.cells.height) return;
  if (__float_as_uint(a.cells.at(cx, cy)) == __float_as_uint(b.cells.at(cx, cy))) return;
  const int x0 = cx << a.shift, y0 = cy << a.shift;
  const int x1 = min(a.width, (cx + 1) << a.shift), y1 = min(a.height, (cy + 1) << a.shift);
  uint8_t *flags = const_cast<uint8_t *>(map.flags);
  for (int ty = y0 / kChangeTile; ty <= (y1 - 1) / kChangeTile; ++ty)
    for (int tx = x0 / kChangeTile; tx <= (x1 - 1) / kChangeTile; ++tx) flags[static_cast<size_t>(ty) * map.tiles_x + tx] = 1;
}

// A thread a tile: ChangeMap::dilated.
// A plain launch (<<< >>>), as every kernel of this file.
__global__ void dilate_kernel(TileFlags in, int rx, int ry, uint8_t *out) {
  const int tx = blockIdx.x * blockDim.x + threadIdx.x, ty = blockIdx.y * blockDim.y + threadIdx.y;
  if (tx >= in.tiles_x || ty >= in.tiles_y) return;
  bool any = false;
  for (int y = max(0, ty - ry); y <= min(in.tiles_y - 1, ty + ry) && !any; ++y)
    for (int x = max(0, tx - rx); x <= min(in.tiles_x - 1, tx + rx) && !any; ++x)
      any = in.flags[static_cast<size_t>(y) * in.tiles_x + x] != 0;
  out[static_cast<size_t>(ty) * in.tiles_x + tx] = any ? 1 : 0;
}

// One block: the flagged tiles counted into *count.
// A plain launch (<<< >>>), as every kernel of this file.
__global__ void count_kernel(const uint8_t *flags, int tiles, unsigned *count) {
  __shared__ unsigned total;
  if (threadIdx.x == 0) total = 0;
  __syncthreads();
  unsigned n = 0;
  for (int i = threadIdx.x; i < tiles; i += blockDim.x) n += flags[i] ? 1u : 0u;
  if (n) atomicAdd(&total, n);
  __syncthreads();
  if (threadIdx.x == 0) *count = total;
}

// What KeptOutputGpu::decide marks for the warp: rows[y] for each row of
// a tiles_x x tiles_y map's picture of `height` rows (at most
// kMaxFrameSide); none where rows is null.
struct RowsRequest {
  int tiles_x = 0, tiles_y = 0, height = 0, reach = 0;
  uint8_t *rows = nullptr;
  unsigned *count = nullptr;
};

// The whole block: rows[y] = row_within_reach of the rows of tiles (in
// shared memory first), or 1 for every row (all); *count: the rows
// reached, whatever all says.
__device__ void mark_rows(const uint8_t *flags, const RowsRequest &r, bool all) {
  __shared__ uint8_t tile_rows[kMaxFrameSide / kChangeTile];
  __shared__ unsigned total;
  // A warp a row of tiles (each written by one lane: no race).
  const int lane = static_cast<int>(threadIdx.x % 32), warps = static_cast<int>(blockDim.x / 32);
  for (int ty = static_cast<int>(threadIdx.x / 32); ty < r.tiles_y; ty += warps) {
    bool any = false;
    for (int tx = lane; tx < r.tiles_x; tx += 32) any = any || flags[static_cast<size_t>(ty) * r.tiles_x + tx];
    any = __any_sync(0xffffffffu, any);
    if (lane == 0) tile_rows[ty] = any ? 1 : 0;
  }
  if (threadIdx.x == 0) total = 0;
  __syncthreads();
  unsigned reached = 0;
  for (int y = threadIdx.x; y < r.height; y += blockDim.x) {
    const bool within = row_within_reach(tile_rows, r.height, y, r.reach);
    reached += within ? 1u : 0u;
    r.rows[y] = all || within ? 1 : 0;
  }
  if (reached) atomicAdd(&total, reached);
  __syncthreads();
  if (threadIdx.x == 0) *r.count = total;
}

// One block: KeptOutputGpu::decide's rule from the flags, and the rows
// where asked; *changed (host memory) tells the host afterwards whether a
// tile changed. whole: the frame is computed whatever changed (every row).
// A plain launch (<<< >>>), as every kernel of this file.
constexpr int kDecideThreads = 1024;
__global__ void __launch_bounds__(kDecideThreads)
    decide_kernel(const uint8_t *flags, int tiles, bool whole, bool first, GateState *state, unsigned *changed,
                  RowsRequest rows) {
  const bool any = __syncthreads_or([&] {
    for (int i = threadIdx.x; i < tiles; i += blockDim.x)
      if (flags[i]) return true;
    return false;
  }());
  const bool all = __syncthreads_and([&] {
    for (int i = threadIdx.x; i < tiles; i += blockDim.x)
      if (!flags[i]) return false;
    return true;
  }());
  if (rows.rows) mark_rows(flags, rows, whole);
  if (threadIdx.x != 0) return;
  const bool run = whole || any || !state->kept_valid;
  const bool keep = run && (!all || first);
  state->run = run;
  state->keep = keep;
  state->kept_valid = run ? keep : 1;
  *changed = any ? 1u : 0u;
}

enum class CopyWhen : int { Run, Finish };

// Up to three planes' rows to copy between two frames: plane p's
// row_bytes[p] bytes of rows[p] rows.
struct PlaneCopies {
  uint8_t *to[3] = {}, *from[3] = {};
  size_t to_pitch[3] = {}, from_pitch[3] = {}, row_bytes[3] = {};
  int rows[3] = {};
  bool vec16[3] = {};
  int planes = 0;
};

// Copies rows between two frames, a plane a row of blocks (blockIdx.y):
// CopyWhen::Run copies `from` into `to` when the gate is open;
// CopyWhen::Finish copies `from` (the kept copy) into `to` (the output)
// when it is closed, and `to` into `from` when the frame is kept. 16-byte
// words where both planes allow.
// A plain launch (<<< >>>), as every kernel of this file.
__global__ void copy_rows_kernel(PlaneCopies c, const GateState *state, CopyWhen when) {
  bool forward;
  if (when == CopyWhen::Run) {
    if (state && !state->run) return;
    forward = true;
  } else {
    if (state->run && !state->keep) return;
    forward = !state->run;
  }
  const int p = static_cast<int>(blockIdx.y);
  uint8_t *dst = forward ? c.to[p] : c.from[p];
  const uint8_t *src = forward ? c.from[p] : c.to[p];
  const size_t dst_pitch = forward ? c.to_pitch[p] : c.from_pitch[p];
  const size_t src_pitch = forward ? c.from_pitch[p] : c.to_pitch[p];
  const bool vec16 = c.vec16[p];
  const size_t unit = vec16 ? 16 : 1, per_row = c.row_bytes[p] / unit;
  const size_t items = per_row * c.rows[p];
  for (size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x; i < items;
       i += static_cast<size_t>(gridDim.x) * blockDim.x) {
    const size_t y = i / per_row, k = i % per_row;
    if (vec16)
      reinterpret_cast<uint4 *>(dst + y * dst_pitch)[k] = reinterpret_cast<const uint4 *>(src + y * src_pitch)[k];
    else
      dst[y * dst_pitch + k] = src[y * src_pitch + k];
  }
}

// Adds a plane to c (none of no bytes).
void add_plane(PlaneCopies *c, uint8_t *to, size_t to_pitch, uint8_t *from, size_t from_pitch, size_t row_bytes,
               int rows) {
  if (rows <= 0 || row_bytes == 0) return;
  const int p = c->planes++;
  c->to[p] = to;
  c->from[p] = from;
  c->to_pitch[p] = to_pitch;
  c->from_pitch[p] = from_pitch;
  c->row_bytes[p] = row_bytes;
  c->rows[p] = rows;
  c->vec16[p] = row_bytes % 16 == 0 && to_pitch % 16 == 0 && from_pitch % 16 == 0 &&
                reinterpret_cast<uintptr_t>(to) % 16 == 0 && reinterpret_cast<uintptr_t>(from) % 16 == 0;
}

CudaStatus launch_copy(const PlaneCopies &c, const GateState *state, CopyWhen when, cudaStream_t stream) {
  if (c.planes == 0) return {};
  long long items = 0;
  for (int p = 0; p < c.planes; ++p)
    items = std::max(items, static_cast<long long>(c.row_bytes[p] / (c.vec16[p] ? 16 : 1)) * c.rows[p]);
  const dim3 grid(std::min<unsigned>(blocks_for(items, kThreads), 65535u), static_cast<unsigned>(c.planes));
  copy_rows_kernel<<<grid, kThreads, 0, stream>>>(c, state, when);
  P3D_CUDA_TRY_LAUNCH(copy_rows_kernel);
  return {};
}

// The planes of a frame's format and size in one pitched buffer (rows of
// each plane 16-byte aligned).
CudaStatus plane_layout(DeviceBuffer &buf, PixelFormat format, int width, int height, size_t offset[3],
                        size_t pitch[3], int *planes) {
  *planes = frame_plane_count(format);
  size_t total = 0;
  for (int p = 0; p < *planes; ++p) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(format, width, height, p, &row_bytes, &rows);
    pitch[p] = (static_cast<size_t>(row_bytes) + 15) / 16 * 16;
    offset[p] = total;
    total += pitch[p] * rows;
  }
  P3D_CUDA_TRY_STATUS(buf.ensure(total > 0 ? total : 16));
  return {};
}

}  // namespace

PinnedWord::~PinnedWord() {
  if (host_) cudaFreeHost(host_);
}

PinnedWord &PinnedWord::operator=(PinnedWord &&o) noexcept {
  if (this != &o) {
    if (host_) cudaFreeHost(host_);
    host_ = o.host_;
    device_ = o.device_;
    o.host_ = o.device_ = nullptr;
  }
  return *this;
}

CudaStatus PinnedWord::ensure() {
  if (host_) return {};
  void *h = nullptr;
  P3D_CUDA_TRY_ALLOC(cudaHostAlloc(&h, sizeof(unsigned), cudaHostAllocMapped), sizeof(unsigned));
  host_ = static_cast<unsigned *>(h);
  *host_ = 0;
  void *d = nullptr;
  P3D_CUDA_TRY(cudaHostGetDevicePointer(&d, h, 0));
  device_ = static_cast<unsigned *>(d);
  return {};
}

CudaStatus ChangeMapGpu::summarize(cudaStream_t stream) {
  P3D_CUDA_TRY_STATUS(count_.ensure());
  count_kernel<<<1, kThreads, 0, stream>>>(data(), static_cast<int>(tiles()), count_.device());
  P3D_CUDA_TRY_LAUNCH(count_kernel);
  return {};
}

double KeptOutputGpu::last_rows_share() const {
  return rows_height_ ? static_cast<double>(rows_count_.host()) / static_cast<double>(rows_height_) : 0.0;
}

bool KeptOutputGpu::last_busy() const {
  return rows_height_ > 0 ? last_rows_share() > kWholeWarpShare : last_changed();
}

double ChangeMapGpu::last_share() const {
  return tiles() ? static_cast<double>(count_.host()) / static_cast<double>(tiles()) : 0.0;
}

CudaStatus ChangeMapGpu::resize(int width, int height) {
  width_ = width > 0 ? width : 0;
  height_ = height > 0 ? height : 0;
  tiles_x_ = change_tiles(width_);
  tiles_y_ = change_tiles(height_);
  P3D_CUDA_TRY_STATUS(flags_.ensure(tiles() > 0 ? tiles() : 1));
  return {};
}

TileFlags ChangeMapGpu::flags() const {
  return TileFlags{flags_.as<const uint8_t>(), width_, height_, tiles_x_, tiles_y_, 0, 0};
}

CudaStatus ChangeMapGpu::fill(bool all, cudaStream_t stream) {
  if (tiles()) P3D_CUDA_TRY(cudaMemsetAsync(flags_.get(), all ? 1 : 0, tiles(), stream));
  return {};
}

CudaStatus ChangeMapGpu::download(ChangeMap *out, cudaStream_t stream) const {
  P3D_CUDA_TRY(cudaStreamSynchronize(stream));
  std::vector<uint8_t> host(tiles());
  if (!host.empty()) P3D_CUDA_TRY(cudaMemcpy(host.data(), flags_.get(), host.size(), cudaMemcpyDeviceToHost));
  *out = ChangeMap(width_, height_, false);
  for (int ty = 0; ty < tiles_y_; ++ty)
    for (int tx = 0; tx < tiles_x_; ++tx)
      if (host[static_cast<size_t>(ty) * tiles_x_ + tx]) out->mark(tx, ty);
  return {};
}

CudaStatus FrameHistoryGpu::compare(const FrameView &frame, float tolerance, ChangeMapGpu &out,
                                    cudaStream_t stream) {
  P3D_CUDA_TRY_STATUS(out.resize(frame.width, frame.height));
  if (out.tiles() == 0) return {};
  const bool fresh = !have_ || frame.format != format_ || frame.width != width_ || frame.height != height_;
  compared_ = !fresh;
  int planes = 0;
  if (fresh) {
    have_ = false;
    P3D_CUDA_TRY_STATUS(plane_layout(copy_, frame.format, frame.width, frame.height, offset_, pitch_, &planes));
  } else {
    planes = frame_plane_count(frame.format);
  }
  KeptPlanes kept{};
  for (int p = 0; p < planes; ++p) {
    kept.plane[p] = copy_.as<uint8_t>() + offset_[p];
    kept.pitch[p] = pitch_[p];
  }
  if (fresh) {
    for (int p = 0; p < planes; ++p) {
      int row_bytes = 0, rows = 0;
      frame_plane_size(frame.format, frame.width, frame.height, p, &row_bytes, &rows);
      P3D_CUDA_TRY(cudaMemcpy2DAsync(kept.plane[p], kept.pitch[p], frame.plane[p], frame.stride[p], row_bytes, rows,
                                     cudaMemcpyDeviceToDevice, stream));
    }
    P3D_CUDA_TRY_STATUS(out.fill(true, stream));
    format_ = frame.format;
    width_ = frame.width;
    height_ = frame.height;
    have_ = true;
    return {};
  }
  const TileFlags f = out.flags();
  const float units = tolerance * static_cast<float>(units_per_level(frame.format));
  if (is_deep(frame.format))
    return change_detail::launch_compare_deep(frame, kept, planes, units, out.data(), f.tiles_x, f.tiles_y, stream);
  return change_detail::launch_compare_of<uint8_t>(frame, kept, planes, units, out.data(), f.tiles_x, f.tiles_y,
                                                   stream);
}

CudaStatus mark_grid_changes_gpu(DepthGrid<const float> a, DepthGrid<const float> b, ChangeMapGpu &map,
                                 cudaStream_t stream) {
  if (map.tiles() == 0) return {};
  if (a.width != b.width || a.height != b.height || a.shift != b.shift || a.cells.width != b.cells.width ||
      a.cells.height != b.cells.height || a.width != map.width() || a.height != map.height() || a.empty())
    return map.fill(true, stream);
  const dim3 block(32, 8), grid(blocks_for(a.cells.width, 32), blocks_for(a.cells.height, 8));
  mark_grid_changes_kernel<<<grid, block, 0, stream>>>(a, b, map.flags());
  P3D_CUDA_TRY_LAUNCH(mark_grid_changes_kernel);
  return {};
}

CudaStatus dilate_gpu(const ChangeMapGpu &in, int reach_x, int reach_y, ChangeMapGpu &out, cudaStream_t stream) {
  P3D_CUDA_TRY_STATUS(out.resize(in.width(), in.height()));
  if (in.tiles() == 0) return {};
  const TileFlags f = in.flags();
  const dim3 block(32, 8), grid(blocks_for(f.tiles_x, 32), blocks_for(f.tiles_y, 8));
  dilate_kernel<<<grid, block, 0, stream>>>(f, reach_tiles(reach_x), reach_tiles(reach_y), out.data());
  P3D_CUDA_TRY_LAUNCH(dilate_kernel);
  return {};
}

CudaStatus KeptOutputGpu::decide(const ChangeMapGpu &changes, const FrameView &out, bool whole,
                                  cudaStream_t stream, int reach_rows) {
  if (!state_.get()) {
    P3D_CUDA_TRY_STATUS(state_.ensure(sizeof(GateState)));
    first_ = true;
  }
  P3D_CUDA_TRY_STATUS(changed_.ensure());
  // Output of another format or size (a layout changed while playing):
  // what is kept does not fit it, so the frame starts afresh.
  if (out.format != format_ || out.width != width_ || out.height != height_) first_ = true;
  if (first_) {
    // The copy is laid out for this output (decide() is never followed by
    // a copy of another size); nothing the copy held is read again.
    P3D_CUDA_TRY_STATUS(plane_layout(copy_, out.format, out.width, out.height, offset_, pitch_, &planes_));
    format_ = out.format;
    width_ = out.width;
    height_ = out.height;
    P3D_CUDA_TRY(cudaMemsetAsync(state_.get(), 0, sizeof(GateState), stream));
  }
  const bool with_rows = reach_rows >= 0 && changes.height() > 0 && changes.height() <= kMaxFrameSide;
  rows_height_ = with_rows ? changes.height() : 0;
  RowsRequest rows;
  if (with_rows) {
    P3D_CUDA_TRY_STATUS(rows_.ensure(static_cast<size_t>(changes.height())));
    P3D_CUDA_TRY_STATUS(rows_count_.ensure());
    const TileFlags f = changes.flags();
    rows = RowsRequest{f.tiles_x, f.tiles_y, f.height, reach_rows, rows_.as<uint8_t>(), rows_count_.device()};
  }
  decide_kernel<<<1, kDecideThreads, 0, stream>>>(changes.data(), static_cast<int>(changes.tiles()), whole || first_,
                                                  first_, state_.as<GateState>(), changed_.device(), rows);
  P3D_CUDA_TRY_LAUNCH(decide_kernel);
  first_ = false;
  return {};
}

CudaStatus KeptOutputGpu::finish(const FrameView &out, cudaStream_t stream) {
  if (out.format != format_ || out.width != width_ || out.height != height_)
    return CudaStatus{cudaErrorInvalidValue, "KeptOutputGpu::finish: the output decide() was given", __FILE__,
                      __LINE__};
  PlaneCopies c;
  for (int p = 0; p < planes_; ++p) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(out.format, out.width, out.height, p, &row_bytes, &rows);
    add_plane(&c, out.plane[p], out.stride[p], copy_.as<uint8_t>() + offset_[p], pitch_[p], row_bytes, rows);
  }
  return launch_copy(c, state_.as<const GateState>(), CopyWhen::Finish, stream);
}

CudaStatus copy_rows_gated(uint8_t *to, size_t to_pitch, const uint8_t *from, size_t from_pitch, size_t row_bytes,
                           int rows, StageGate gate, cudaStream_t stream) {
  PlaneCopies c;
  add_plane(&c, to, to_pitch, const_cast<uint8_t *>(from), from_pitch, row_bytes, rows);
  return launch_copy(c, gate.state, CopyWhen::Run, stream);
}

}  // namespace p3d
