// The scene mode's CPU chain, adaptive off and on (scene_chain.h).
#include "scene_chain.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "bilateral.h"
#include "pack.h"
#include "warp.h"

namespace p3d::bench {

namespace {

ImageView<const float> const_view(const cv::Mat &m) { return depth_view_of(m); }

// gst_video_frame_copy of the previous output into this frame's: every
// plane, padding and all (both frames have one geometry).
void copy_frame(const HostFrame &from, HostFrame &to) {
  const FrameView a = from.view(), b = to.view();
  for (int i = 0; i < frame_plane_count(a.format); ++i) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(a.format, a.width, a.height, i, &row_bytes, &rows);
    std::memcpy(b.plane[i], a.plane[i], static_cast<size_t>(a.stride[i]) * rows);
  }
}

void warp_failed() { throw std::runtime_error("the warp's frames do not fit"); }

}  // namespace

// ---- the warp's frames -------------------------------------------------------------

WarpTarget::WarpTarget(const PackParams &pack, int width, int height, PixelFormat input)
    : pair_is_output_(pack_is_identity(pack)), format_(stereo_format(input)) {
  pack_size(pack.layout, width, height, &out_width_, &out_height_);
  if (!pair_is_output_) pair_ = HostFrame(format_, 2 * width, height);
}

HostFrame WarpTarget::new_output() const { return HostFrame(format_, out_width_, out_height_); }

// ---- adaptive=false --------------------------------------------------------------------

FullChain::FullChain(const StageParams &p, int width, int height, PixelFormat input)
    : p_(p),
      depth_(height, width, CV_32FC1, cv::Scalar(0)),
      filtered_(height, width, CV_32FC1, cv::Scalar(0)),
      target_(p.pack, width, height, input),
      out_(target_.new_output()) {}

void FullChain::frame(const FrameView &src, StageMs *ms) {
  Stopwatch sw;
  estimator_.estimate(p_.depth, src, depth_view_of(depth_));
  ms->depth = sw.lap();
  bilateral_filter_cpu(p_.filter, src, const_view(depth_), depth_view_of(filtered_));
  ms->filter = sw.lap();
  const FrameView dst = out_.view(), pair = target_.pair(dst);
  if (warp_render_cpu(p_.warp, src, p_.yuv, const_view(filtered_), pair, warp_scratch_) < 0) warp_failed();
  if (!target_.pair_is_output()) pack_cpu(p_.pack, pair, dst);
  ms->warp = sw.lap();
}

// ---- adaptive=true ---------------------------------------------------------------------

PlanePool::PlanePool(int width, int height, int ready) : width_(width), height_(height) {
  for (int i = 0; i < ready; ++i) planes_.push_back(std::make_shared<cv::Mat>(height, width, CV_32FC1, cv::Scalar(0)));
}

PlanePool::Plane PlanePool::acquire() {
  for (const Plane &p : planes_)
    if (p.use_count() == 1) return p;
  planes_.push_back(std::make_shared<cv::Mat>(height_, width_, CV_32FC1, cv::Scalar(0)));
  return planes_.back();
}

// Two planes a pool: the one the stage last handed on (which the next stage
// still holds as its previous input) and the new one.
AdaptiveChain::AdaptiveChain(const StageParams &p, int width, int height, PixelFormat input, float tolerance)
    : p_(p),
      tolerance_(tolerance),
      depth_pool_(width, height, 2),
      filter_pool_(width, height, 2),
      target_(p.pack, width, height, input),
      out_(target_.new_output()),
      kept_(target_.new_output()) {}

void AdaptiveChain::frame(const FrameView &src, StageMs *ms) {
  ChangeMap input, filter_changes, warp_changes;
  Stopwatch sw;
  const Plane depth_plane = depth(src, &input);
  ms->depth = sw.lap();
  const Plane filtered = filter(src, depth_plane, &filter_changes);
  ms->filter = sw.lap();
  warp(src, filtered, &warp_changes);
  ms->warp = sw.lap();
  const std::vector<uint8_t> rows = warp_changes.rows();
  shares_ = {input.fraction(), filter_changes.fraction(), warp_changes.fraction(),
             rows.empty() ? 0.0 : static_cast<double>(std::count(rows.begin(), rows.end(), 1)) / rows.size()};
}

// gstpseudo3ddepth.cpp process_ip: only the blocks of changed tiles are
// summed again; when no block depth changed the frame gets the previous
// plane itself.
AdaptiveChain::Plane AdaptiveChain::depth(const FrameView &src, ChangeMap *changes) {
  *changes = depth_history_.compare(src, tolerance_);
  estimator_.estimate_blocks(p_.depth, src, changes);
  if (estimator_.output_changed() || !depth_last_) {
    Plane plane = depth_pool_.acquire();
    estimator_.expand(depth_view_of(*plane));
    depth_last_ = std::move(plane);
  }
  return depth_last_;
}

// gstpseudo3dfilter.cpp filter_adaptive: the tiles a changed guide or depth
// reaches are filtered into a new plane holding the rest of the previous
// output; none reached: the previous output itself.
AdaptiveChain::Plane AdaptiveChain::filter(const FrameView &src, const Plane &depth, ChangeMap *changes) {
  const ImageView<const float> prev_depth = filter_depth_ ? const_view(*filter_depth_) : ImageView<const float>();
  *changes = filter_inputs_.compare(src, const_view(*depth), prev_depth, tolerance_);
  filter_depth_ = depth;
  const bool whole = !filter_last_;
  Plane out = filter_pool_.acquire();
  const ImageView<const float> prev_out = filter_last_ ? const_view(*filter_last_) : ImageView<const float>();
  if (bilateral_filter_changed_cpu(p_.filter, src, const_view(*depth), prev_out, depth_view_of(*out),
                                   whole ? nullptr : changes, filter_scratch_))
    filter_last_ = std::move(out);
  if (whole) changes->mark_all();
  return filter_last_;
}

// gstpseudo3dwarp.cpp render_cpu: a new output buffer that starts as a copy
// of the previous output (unless every tile changed), the rows a change
// reaches warped and packed again, and the output copied when it changed.
void AdaptiveChain::warp(const FrameView &src, const Plane &depth, ChangeMap *changes) {
  const ImageView<const float> prev_depth = warp_depth_ ? const_view(*warp_depth_) : ImageView<const float>();
  *changes = warp_inputs_.compare(src, const_view(*depth), prev_depth, tolerance_);
  warp_depth_ = depth;
  const bool whole = !have_output_ || changes->all_rows();
  if (!whole) copy_frame(kept_, out_);
  const FrameView dst = out_.view();
  if (warp_pack_changed_cpu(p_.warp, p_.pack, src, p_.yuv, const_view(*depth), target_.pair(dst), dst, warp_scratch_,
                            whole ? nullptr : changes) < 0)
    warp_failed();
  // gst/stage_adaptive.cpp OutputHistory::update.
  const bool first = !seen_;
  seen_ = true;
  if (changes->all_rows() && !first) {
    have_output_ = false;
  } else if (whole || changes->any()) {
    copy_frame(out_, kept_);
    have_output_ = true;
  }
  if (whole) changes->mark_all();
}

}  // namespace p3d::bench
