// The adaptive stages' steps on the CPU (docs/architecture.md, "Adaptive
// work"): each stage compares its inputs with the previous frame's
// (change_map.h), recomputes the output that a changed tile can reach and
// keeps the rest of its previous output. With tolerance 0 each step's
// output is byte for byte what the stage computes without them. The
// elements (gst/) and pseudo3d-bench's scene mode call these.
#pragma once

#include <cstdint>
#include <vector>

#include "bilateral.h"
#include "bars.h"
#include "change_map.h"
#include "pack.h"
#include "warp.h"

namespace p3d {

// How much of a stage's work a change makes it redo, which decides when a
// frame is busy for it (computed whole, it costs about what the changes
// would): Tiles, the changed tiles and their reach (the depth, the filter:
// busy beyond ChangeBackOff::busy_on_cpu's share); Rows, whole rows of
// tiles (the pack: a change in every row); Spans, in each row of tiles the
// columns from its first changed tile to its last, widened by the warp's
// reach (the warp: spans over more than kWholeWarpShare of the picture,
// common/change_map.h).
enum class ChangeReach { Tiles, Rows, Spans };
bool busy_for(ChangeReach reach, const ChangeMap &changes);
// The warp's reach with these parameters: Spans where it renders column
// windows (BackgroundSmooth, None), Rows where it renders whole rows
// (Background; NeighborAverage renders the whole frame on any change,
// which only a change in every row makes worth it).
ChangeReach warp_change_reach(const WarpParams &params);

// A stage's inputs of the previous frame: the frame's bytes (a copy) and
// the depth map, which the caller holds on to (the stages never write a
// map once they hand it on); and the stage's back-off (ChangeBackOff,
// busy_on_cpu).
class StageInputs {
 public:
  // reach: what the stage redoes of a change (busy_for).
  explicit StageInputs(ChangeReach reach = ChangeReach::Tiles) : reach_(reach) {}
  // A stage whose reach follows its parameters (the warp's fill) sets it
  // before compare().
  void set_reach(ChangeReach reach) { reach_ = reach; }
  // Before a frame: whether it is compared (adaptive and not backing off).
  // When not, the history is dropped and the stage computes the frame
  // whole, dropping what it kept too.
  bool begin(bool adaptive);
  // The tiles in which this frame, or its depth map when `depth` is given,
  // differ from the previous call's. prev_depth: the previous call's depth
  // map (empty: none, every tile counts as changed); the same data pointer
  // as depth: the same map, unchanged. A comparison with the previous
  // inputs feeds the back-off.
  ChangeMap compare(const FrameView &frame, ImageView<const float> depth, ImageView<const float> prev_depth,
                    float tolerance);
  // Whether the last compare() had the previous call's inputs (else it
  // flagged every tile).
  bool compared() const { return compared_; }
  void reset() {
    frame_.reset();
    compared_ = false;
    backoff_.reset();
  }

 private:
  FrameHistory frame_;
  ChangeReach reach_;
  bool compared_ = false;
  ChangeBackOff backoff_;
};

// The filter of the pixels within bilateral_reach() of a changed tile.
// changes: the tiles whose guide or depth changed since the call that
// wrote prev_out (null: prev_out is unknown or other parameters made it).
// Returns false when the change reaches no tile: out is left untouched and
// prev_out is this frame's output. Otherwise out holds the whole output,
// prev_out's values where the change does not reach.
bool bilateral_filter_changed_cpu(const BilateralParams &params, const FrameView &guide, ImageView<const float> depth,
                                  ImageView<const float> prev_out, ImageView<float> out, const ChangeMap *changes,
                                  BilateralScratch &scratch);

// Where a changed frame's output starts from: the previous output, kept
// by the caller (dst's format and size), and the rows the call wrote.
// The rows it does not rewrite whole are copied from `previous`, so only
// `written` (one flag a row of dst: 4:2:0 rows in pairs, with their chroma
// row) can differ from it, which is all the caller's copy needs again.
struct KeptOutput {
  const FrameView *previous = nullptr;
  std::vector<uint8_t> written;
};

// The warp and the pack of what a changed source or depth reaches
// (warp_render_cpu's windows, the rows they write). changes: the tiles
// whose source or depth changed since the
// previous call (null: everything is computed); dst then holds that
// call's output, or kept->previous does, and pair (the frame the views
// are rendered into: dst itself where the layout is the pair, else a
// buffer kept between calls) its pair. Returns warp_render_cpu()'s hole
// count, or -1 when the frames do not fit (nothing written).
//
// active: the views rendered inside a rect only (bars.h, ActiveArea).
long long warp_pack_changed_cpu(const WarpParams &params, const PackParams &pack, const FrameView &src,
                                const YuvToRgb &m, ImageView<const float> depth, const FrameView &pair,
                                const FrameView &dst, WarpCpuScratch &scratch, const ChangeMap *changes,
                                const ActiveArea *active = nullptr, KeptOutput *kept = nullptr);


// The pack of the output rows that read a changed input row. changes: the
// tiles of the input that changed since the previous call (null: all);
// dst then holds that call's output, or kept->previous does. False when
// the frames do not fit.
bool pack_changed_cpu(const PackParams &params, const FrameView &in, const FrameView &dst, const ChangeMap *changes,
                      KeptOutput *kept = nullptr);

// Copies the rows of `from` into `to` (same format and size) whose flag
// in `rows` (one a row) equals `flagged`; a 4:2:0 chroma row goes with
// its two rows, flagged when either is.
void copy_flagged_rows(const FrameView &from, const FrameView &to, const std::vector<uint8_t> &rows, bool flagged);

}  // namespace p3d
