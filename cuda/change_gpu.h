// The adaptive stages' bookkeeping on the device (common/change_map.h on
// CUDA memory): which tiles of a stage's inputs changed since the previous
// frame, and whether the stage computes this frame or keeps its previous
// output. Kernels compare, merge and dilate the tile flags, and the
// stage's own kernels read them, so no frame waits for the host: a stage
// queues the same launches whatever changed, and a kernel with nothing to
// do returns at once.
//
// A stage's frame on the GPU (docs/architecture.md, "Adaptive work"):
//   compare   FrameHistoryGpu::compare (the frame against a kept copy, tile
//             by tile, as FrameHistory) and mark_grid_changes_gpu (the
//             depth grid against the previous frame's plane);
//   dilate    dilate_gpu, where an output reads a neighbourhood (the filter);
//   decide    KeptOutputGpu::decide, for a stage that keeps a copy of its
//             output (the warp, the pack): run when a tile changed or
//             nothing is kept; for the warp also the rows its changes
//             reach (warp_rows_reach), the only ones it renders again;
//   compute   the stage's kernels, each returning at once where the flags
//             (TileFlags::any_in) or the gate (StageGate) say so;
//   finish    KeptOutputGpu::finish: the kept copy into the output where
//             the stage did not run, the output into the copy where it did.
#pragma once

#include <cstdint>

#include "../common/change_map.h"
#include "cuda_check.h"
#include "device_buffer.h"

namespace p3d {

// A ChangeMap's flags on the device, by value into kernels: one byte a
// kChangeTile tile of a width x height picture, row-major. (ox, oy): where
// the picture a kernel works on starts in that picture (a sub-picture,
// such as the active rect inside bars); any_in() takes the kernel's
// coordinates. flags null: every tile counts as changed.
struct TileFlags {
  const uint8_t *flags = nullptr;
  int width = 0, height = 0, tiles_x = 0, tiles_y = 0;
  int ox = 0, oy = 0;

  // Whether a tile with a pixel of r (the kernel's coordinates, clipped to
  // the picture) is flagged.
  P3D_HD bool any_in(PixelRect r) const {
    if (!flags) return true;
    r.x0 += ox;
    r.x1 += ox;
    r.y0 += oy;
    r.y1 += oy;
    r.x0 = r.x0 < 0 ? 0 : r.x0;
    r.y0 = r.y0 < 0 ? 0 : r.y0;
    r.x1 = r.x1 > width ? width : r.x1;
    r.y1 = r.y1 > height ? height : r.y1;
    if (r.empty()) return false;
    for (int ty = r.y0 / kChangeTile; ty <= (r.y1 - 1) / kChangeTile; ++ty)
      for (int tx = r.x0 / kChangeTile; tx <= (r.x1 - 1) / kChangeTile; ++tx)
        if (flags[static_cast<size_t>(ty) * tiles_x + tx]) return true;
    return false;
  }
  // The same flags for the sub-picture starting at (x, y) of this one.
  TileFlags offset(int x, int y) const {
    TileFlags t = *this;
    t.ox += x;
    t.oy += y;
    return t;
  }
};

// One 32-bit word of mapped pinned host memory, which kernels write and
// the host reads after the stream has passed them.
class PinnedWord {
 public:
  PinnedWord() = default;
  ~PinnedWord();
  PinnedWord(PinnedWord &&o) noexcept : host_(o.host_), device_(o.device_) { o.host_ = o.device_ = nullptr; }
  PinnedWord &operator=(PinnedWord &&o) noexcept;
  PinnedWord(const PinnedWord &) = delete;
  PinnedWord &operator=(const PinnedWord &) = delete;
  CudaStatus ensure();
  unsigned *device() const { return device_; }
  unsigned host() const { return host_ ? *static_cast<volatile unsigned *>(host_) : 0u; }

 private:
  unsigned *host_ = nullptr, *device_ = nullptr;
};

// A ChangeMap held on the device.
class ChangeMapGpu {
 public:
  // A width x height picture's flags (contents undefined until written).
  CudaStatus resize(int width, int height);
  int width() const { return width_; }
  int height() const { return height_; }
  TileFlags flags() const;
  uint8_t *data() const { return flags_.as<uint8_t>(); }
  size_t tiles() const { return static_cast<size_t>(tiles_x_) * tiles_y_; }
  // Every tile changed (all) or none, queued on `stream`.
  CudaStatus fill(bool all, cudaStream_t stream);
  // For tests: the flags as a ChangeMap (synchronises the stream).
  CudaStatus download(ChangeMap *out, cudaStream_t stream) const;
  // Queues the count of the flagged tiles into host memory, where
  // last_share() reads it as a share of the tiles once the stream has
  // passed it (a stage's end-of-frame wait; ChangeBackOff's signal).
  CudaStatus summarize(cudaStream_t stream);
  double last_share() const;

 private:
  DeviceBuffer flags_;
  PinnedWord count_;
  int width_ = 0, height_ = 0, tiles_x_ = 0, tiles_y_ = 0;
};

// FrameHistory on the device: each frame compared with a copy of the one
// before, kept in device memory (tolerance as FrameHistory::compare: 0 any
// byte, t > 0 the mean |difference| of a tile's bytes over t, the copy then
// keeping the bytes of the last frame in which the tile counted as
// changed).
class FrameHistoryGpu {
 public:
  // Writes into `out` (resized to the frame) the tiles of `frame` (device
  // memory) that differ from the previous frame's: every tile when there
  // is none of this size and format. Records the changed tiles' bytes.
  CudaStatus compare(const FrameView &frame, float tolerance, ChangeMapGpu &out, cudaStream_t stream);
  void reset() { have_ = false; }
  // Whether the last compare() had a previous frame (else it flagged
  // every tile).
  bool compared() const { return compared_; }

 private:
  DeviceBuffer copy_;
  PixelFormat format_ = PixelFormat::RGBA;
  int width_ = 0, height_ = 0;
  size_t offset_[3] = {0, 0, 0}, pitch_[3] = {0, 0, 0};
  bool have_ = false, compared_ = false;
};

// Adds to `map` (a's picture's size) the tiles with a pixel of a cell in
// which grids a and b differ in any byte (compare_grids); every tile when
// their geometries differ.
CudaStatus mark_grid_changes_gpu(DepthGrid<const float> a, DepthGrid<const float> b, ChangeMapGpu &map,
                                 cudaStream_t stream);

// out = in.dilated(reach_x, reach_y) (ChangeMap::dilated); out is resized.
CudaStatus dilate_gpu(const ChangeMapGpu &in, int reach_x, int reach_y, ChangeMapGpu &out, cudaStream_t stream);

// The device's decision for a stage that keeps its output, written by
// KeptOutputGpu::decide before the stage's kernels and read by them.
struct GateState {
  int run;         // this frame is computed
  int keep;        // and copied into the kept output afterwards
  int kept_valid;  // the kept output holds the last computed frame's
};

// What a stage's kernels read: closed() when the frame is not computed
// (its output then comes from the kept copy). A default gate is open.
// rows (the warp's, KeptOutputGpu::decide with a reach): one flag a row of
// the picture, set where the row is rendered again; null: every row. Only
// a target that keeps the rows not rendered (a pair kept from frame to
// frame) may be rendered through a gate with rows.
struct StageGate {
  const GateState *state = nullptr;
  const uint8_t *rows = nullptr;
  P3D_HD bool closed() const { return state && !state->run; }
  // Whether rows y0 .. y0 + n - 1 are left as they are this frame.
  P3D_HD bool skips_rows(int y0, int n) const {
    if (closed()) return true;
    if (!rows) return false;
    for (int i = 0; i < n; ++i)
      if (rows[y0 + i]) return false;
    return true;
  }
  // The gate of the sub-picture starting at row y0.
  StageGate from_row(int y0) const { return StageGate{state, rows ? rows + y0 : nullptr}; }
  // The gate for a target that does not keep its rows: every row.
  StageGate every_row() const { return StageGate{state, nullptr}; }
};

// A stage's previous output, kept on the device, and the decision whether
// to compute the next one.
class KeptOutputGpu {
 public:
  // Queues the decision for a frame whose inputs changed in the tiles of
  // `changes`, to be written into `out`: run when a tile changed, nothing
  // of out's format and size is kept, or `whole` (the parameters changed:
  // what is kept was made otherwise). The output is kept after a frame
  // that did not change every tile, or after the first one.
  // reach_rows >= 0 (the warp: warp_rows_reach()) also marks the gate's
  // rows: those within reach_rows of a changed tile's rows
  // (row_within_reach); every row on the first decision (after reset(),
  // or for an output of another format or size) and with `whole`. A frame
  // that runs only because nothing is kept marks the rows of its changes
  // alone: the rows of the pair the warp keeps are its own, not the kept
  // output's.
  CudaStatus decide(const ChangeMapGpu &changes, const FrameView &out, bool whole, cudaStream_t stream,
                    int reach_rows = -1);
  StageGate gate() const {
    return StageGate{state_.as<const GateState>(), rows_height_ > 0 ? rows_.as<const uint8_t>() : nullptr};
  }
  // Whether a tile of the last decided frame's inputs changed, once the
  // stream has passed the decision (ChangeBackOff's signal for such a
  // stage: a frame computed only because nothing was kept is not busy).
  bool last_changed() const { return changed_.host() != 0; }
  // The share of the rows that the last decided frame's changes reach
  // (decide() with a reach; 0 without), once the stream has passed it:
  // the warp's ChangeBackOff signal.
  double last_rows_share() const;
  // ChangeBackOff's signal for such a stage, once the stream has passed
  // the decision: a tile changed (the stage computes the whole frame), or,
  // where the decision marked rows, changes that reach more than
  // kWholeWarpShare of them.
  bool last_busy() const;
  // After the stage's kernels: `out` (decide()'s) gets the kept copy when
  // the frame was not computed; the copy takes `out` when it was and is
  // kept.
  CudaStatus finish(const FrameView &out, cudaStream_t stream);
  // Nothing kept: the next frame is computed and is the first.
  void reset() { first_ = true; }

 private:
  DeviceBuffer state_, copy_, rows_;
  PinnedWord changed_, rows_count_;
  int rows_height_ = 0;  // the rows marked by the last decision (0: none)
  // The copy's frames: their format and size, each plane's place in copy_.
  PixelFormat format_ = PixelFormat::RGBA;
  int width_ = 0, height_ = 0, planes_ = 0;
  size_t offset_[3] = {0, 0, 0}, pitch_[3] = {0, 0, 0};
  bool first_ = true;
};

// Whether the filter on CUDA memory compares its inputs (adaptive): only
// on the full-resolution grid. On the automatic step 4 from 2160 rows its
// whole pass costs less than the comparison of the guide frame alone
// (docs/benchmarks.md, "Adaptive work per scene (GPU)"). Steps 2 and 3
// (a quarter and a ninth of the cells) take the same rule unmeasured: the
// stage computes every frame on a coarse grid whole.
inline bool filter_compares_on_gpu(int grid_shift) { return grid_shift == 0; }

// Copies `rows` rows of row_bytes bytes from one device plane to another
// when the gate is open (a stage's own copies, which must not run on a
// frame it keeps).
CudaStatus copy_rows_gated(uint8_t *to, size_t to_pitch, const uint8_t *from, size_t from_pitch, size_t row_bytes,
                           int rows, StageGate gate, cudaStream_t stream);

}  // namespace p3d
