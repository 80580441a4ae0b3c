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

void warp_failed() { throw std::runtime_error("the warp's frames do not fit"); }

// DepthPlane::set_active: 0 in the plane outside r.
void zero_outside(cv::Mat &plane, PixelRect r) {
  for (const PixelRect &b : cells_outside(r, 0, plane.cols, plane.rows))
    if (!b.empty()) plane(cv::Rect(b.x0, b.y0, b.width(), b.height())).setTo(cv::Scalar(0));
}

}  // namespace

// ---- the warp's frames -------------------------------------------------------------

WarpTarget::WarpTarget(const PackParams &pack, int width, int height, PixelFormat input)
    : pair_is_output_(pack_is_identity(pack)), format_(stereo_format(input)) {
  pack_size(pack.layout, width, height, &out_width_, &out_height_);
  if (!pair_is_output_) pair_ = HostFrame(format_, 2 * width, height);
}

HostFrame WarpTarget::new_output() const { return HostFrame(format_, out_width_, out_height_); }

// ---- adaptive=false --------------------------------------------------------------------

namespace {

// The stages' automatic sizes are the frame's (frame_scaled), as the
// elements make them.
StageParams frame_scaled(StageParams p, int width, int height) {
  p.depth = p3d::frame_scaled(p.depth, width, height);
  p.filter = p3d::frame_scaled(p.filter, width, height);
  return p;
}

}  // namespace

FullChain::FullChain(const StageParams &p, int width, int height, PixelFormat input, bool crop)
    : p_(frame_scaled(p, width, height)),
      crop_(crop),
      depth_(height, width, CV_32FC1, cv::Scalar(0)),
      filtered_(height, width, CV_32FC1, cv::Scalar(0)),
      target_(p.pack, width, height, input),
      out_(target_.new_output()),
      rect_(whole_picture(width, height)) {}

void FullChain::frame(const FrameView &src, StageMs *ms) {
  Stopwatch sw;
  if (crop_) {  // pseudo3ddepth's observe_bars, in the tracker's order
    if (bars_.previous_due()) bars_.observe(counts_);
    bar_counts_cpu(src, bar_luma_threshold(p_.yuv), &counts_);
    if (bars_.counted()) bars_.observe(counts_);
  }
  const PixelRect rect = crop_ ? bars_.active(src.width, src.height) : whole_picture(src.width, src.height);
  if (rect != rect_) {  // pseudo3ddepth's frame_rect: a new picture, a new history; 0 outside
    estimator_.reset();
    depth_.setTo(cv::Scalar(0));
    filtered_.setTo(cv::Scalar(0));
    if (rect.x0 != 0 || rect.x1 != src.width)
      active_pair_ = HostFrame(target_.pair(out_.view()).format, 2 * rect.width(), rect.height());
    rect_ = rect;
  }
  const FrameView active = sub_frame(src, rect);
  estimator_.estimate(p_.depth, active, sub_image(depth_view_of(depth_), rect));
  ms->depth = sw.lap();
  bilateral_filter_cpu(p_.filter, active, sub_image(const_view(depth_), rect), sub_image(depth_view_of(filtered_), rect));
  ms->filter = sw.lap();
  const FrameView dst = out_.view(), pair = target_.pair(dst);
  const ActiveArea area{rect, active_pair_.view()};
  if (warp_pack_changed_cpu(p_.warp, p_.pack, src, p_.yuv, const_view(filtered_), pair, dst, warp_scratch_, nullptr,
                            &area) < 0)
    warp_failed();
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
    : p_(frame_scaled(p, width, height)),
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
  shares_ = {input.fraction(), filter_changes.fraction(), warp_changes.fraction(), warp_changes.span_share()};
}

// gstpseudo3ddepth.cpp process_ip: the bars counted (again only where the
// frame changed) and decided in the tracker's order; only the blocks of
// changed tiles are summed again; when no block depth changed the frame
// gets the previous plane itself. A new rect starts the estimator and the planes over. Backing
// off (StageInputs::begin): the whole estimate into a new plane.
AdaptiveChain::Plane AdaptiveChain::depth(const FrameView &src, ChangeMap *changes) {
  const bool compare = depth_inputs_.begin(true);
  *changes = compare ? depth_inputs_.compare(src, {}, {}, tolerance_) : ChangeMap(src.width, src.height, true);
  if (bars_.previous_due()) bars_.observe(counts_);
  if (changes->any() || counts_.rows.empty())
    bar_counts_cpu(src, bar_luma_threshold(p_.yuv), &counts_, compare ? changes : nullptr);
  if (bars_.counted()) bars_.observe(counts_);
  const PixelRect rect = bars_.active(src.width, src.height);
  if (rect != rect_) {
    estimator_.reset();
    depth_last_.reset();
    rect_ = rect;
    changes->mark_all();
    if (rect.x0 != 0 || rect.x1 != src.width)
      active_pair_ = HostFrame(target_.pair(out_.view()).format, 2 * rect.width(), rect.height());
  }
  if (!compare) {
    depth_last_.reset();
    Plane plane = depth_pool_.acquire();
    zero_outside(*plane, rect);
    estimator_.estimate(p_.depth, sub_frame(src, rect), sub_image(depth_view_of(*plane), rect));
    return plane;
  }
  const ChangeMap active_changes = changes->cropped(rect);
  estimator_.estimate_blocks(p_.depth, sub_frame(src, rect), &active_changes);
  if (estimator_.output_changed() || !depth_last_) {
    Plane plane = depth_pool_.acquire();
    zero_outside(*plane, rect);
    estimator_.expand(sub_image(depth_view_of(*plane), rect));
    depth_last_ = std::move(plane);
  }
  return depth_last_;
}

// gstpseudo3dfilter.cpp filter_adaptive: the tiles a changed guide or depth
// reaches are filtered into a new plane holding the rest of the previous
// output; none reached: the previous output itself. Inside the rect.
// Backing off: the whole filter into a new plane, nothing kept. A flat
// depth map (bilateral_keeps) is the output itself.
AdaptiveChain::Plane AdaptiveChain::filter(const FrameView &src, const Plane &depth, ChangeMap *changes) {
  const bool flat = bilateral_keeps(sub_image(const_view(*depth), rect_));
  if (!filter_inputs_.begin(true)) {
    filter_depth_.reset();
    filter_last_.reset();
    *changes = ChangeMap(src.width, src.height, true);
    if (flat) return depth;
    Plane out = filter_pool_.acquire();
    zero_outside(*out, rect_);
    bilateral_filter_cpu(p_.filter, sub_frame(src, rect_), sub_image(const_view(*depth), rect_),
                         sub_image(depth_view_of(*out), rect_));
    return out;
  }
  const ImageView<const float> prev_depth = filter_depth_ ? const_view(*filter_depth_) : ImageView<const float>();
  *changes = filter_inputs_.compare(src, const_view(*depth), prev_depth, tolerance_);
  filter_depth_ = depth;
  const bool whole = !filter_last_ || filter_rect_ != rect_;
  filter_rect_ = rect_;
  if (flat) {
    filter_last_ = depth;
    if (whole) changes->mark_all();
    return depth;
  }
  Plane out = filter_pool_.acquire();
  zero_outside(*out, rect_);
  const ImageView<const float> prev_out =
      filter_last_ ? sub_image(const_view(*filter_last_), rect_) : ImageView<const float>();
  const ChangeMap active_changes = changes->cropped(rect_);
  if (bilateral_filter_changed_cpu(p_.filter, sub_frame(src, rect_), sub_image(const_view(*depth), rect_), prev_out,
                                   sub_image(depth_view_of(*out), rect_), whole ? nullptr : &active_changes,
                                   filter_scratch_))
    filter_last_ = std::move(out);
  if (whole) changes->mark_all();
  return filter_last_;
}

// gstpseudo3dwarp.cpp render_cpu: a new output buffer, the columns a change
// reaches warped and their rows packed again, the other rows copied from
// the kept previous output (unless the change is busy), and the rows
// written copied into the kept one.
// Backing off: the whole frame, nothing kept.
void AdaptiveChain::warp(const FrameView &src, const Plane &depth, ChangeMap *changes) {
  const ChangeReach reach = warp_change_reach(p_.warp);
  warp_inputs_.set_reach(reach);
  const bool compare = warp_inputs_.begin(true);
  bool whole = true;
  if (compare) {
    const ImageView<const float> prev_depth = warp_depth_ ? const_view(*warp_depth_) : ImageView<const float>();
    *changes = warp_inputs_.compare(src, const_view(*depth), prev_depth, tolerance_);
    warp_depth_ = depth;
    whole = !have_output_ || busy_for(reach, *changes) || warp_rect_ != rect_;
  } else {
    warp_depth_.reset();
    have_output_ = seen_ = false;
    *changes = ChangeMap(src.width, src.height, true);
  }
  warp_rect_ = rect_;
  const FrameView dst = out_.view(), previous = kept_.view();
  const ActiveArea area{rect_, active_pair_.view()};
  KeptOutput kept{whole ? nullptr : &previous, {}};
  if (warp_pack_changed_cpu(p_.warp, p_.pack, src, p_.yuv, const_view(*depth), target_.pair(dst), dst, warp_scratch_,
                            whole ? nullptr : changes, &area, &kept) < 0)
    warp_failed();
  if (compare) {  // gst/stage_adaptive.cpp OutputHistory::update.
    const bool first = !seen_;
    seen_ = true;
    if (busy_for(reach, *changes) && !first) {
      have_output_ = false;
    } else if (whole || changes->any()) {  // kept.written: every row of a whole frame
      copy_flagged_rows(dst, kept_.view(), kept.written, true);
      have_output_ = true;
    }
  }
  if (whole) changes->mark_all();
}

}  // namespace p3d::bench
