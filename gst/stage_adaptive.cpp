#include "stage_adaptive.h"

#include <cstring>

#include "depth_meta.h"
#include "video_util.h"

namespace p3d::gst {

AdaptiveSettings adaptive_settings(GstPseudo3DBase *self) {
  AdaptiveSettings s;
  GST_OBJECT_LOCK(self);
  s.on = self->adaptive;
  s.tolerance = self->reuse_tolerance;
  GST_OBJECT_UNLOCK(self);
  return s;
}

bool InputHistory::begin(bool adaptive) {
  const bool compare = inputs_.begin(adaptive);
  if (!compare) depth_.reset();
  return compare;
}

ChangeMap InputHistory::compare(const FrameView &frame, const DepthPlanePtr &depth, float tolerance) {
  const ImageView<const float> prev = depth_ && !depth_->on_device ? as_const(depth_->view()) : ImageView<const float>();
  ChangeMap changes = inputs_.compare(frame, depth ? as_const(depth->view()) : ImageView<const float>(), prev, tolerance);
  depth_ = depth;
  return changes;
}

void InputHistory::reset() {
  inputs_.reset();
  depth_.reset();
}

#if HAVE_CUDA
CudaStatus InputHistoryGpu::compare(const FrameView &frame, const DepthPlanePtr &depth, float tolerance,
                                    cudaStream_t stream) {
  P3D_CUDA_TRY_STATUS(frame_.compare(frame, tolerance, changes_, stream));
  compared_ = frame_.compared() && (!depth || depth_);
  if (depth && depth != depth_) {
    if (depth_ && depth_->on_device)
      P3D_CUDA_TRY_STATUS(mark_grid_changes_gpu(as_const(depth_->grid()), as_const(depth->grid()), changes_, stream));
    else
      P3D_CUDA_TRY_STATUS(changes_.fill(true, stream));
  }
  depth_ = depth;
  return {};
}

void InputHistoryGpu::reset() {
  frame_.reset();
  depth_.reset();
}

bool WholeOutputGpu::begin(bool adaptive) {
  if (!adaptive) reset();
  comparing_ = adaptive && backoff_.compare_next();
  if (adaptive && !comparing_) {
    inputs_.reset();
    output_.reset();
  }
  return comparing_;
}

CudaStatus WholeOutputGpu::decide(const FrameView &frame, const DepthPlanePtr &depth, float tolerance,
                                  const FrameView &out, bool whole, cudaStream_t stream, StageGate *gate,
                                  int reach_rows) {
  P3D_CUDA_TRY_STATUS(inputs_.compare(frame, depth, tolerance, stream));
  P3D_CUDA_TRY_STATUS(output_.decide(inputs_.changes(), out, whole, stream, reach_rows));
  *gate = output_.gate();
  return {};
}

void WholeOutputGpu::end(bool ok) {
  if (!ok) {  // the histories may have moved on without the output
    reset();
    return;
  }
  if (comparing_ && inputs_.compared()) backoff_.observe(output_.last_busy());
}

void WholeOutputGpu::reset() {
  inputs_.reset();
  output_.reset();
  backoff_.reset();
}
#endif

namespace {

// Copies plane `plane`'s rows out of a mapped frame (its strides) into a
// packed copy (rows back to back).
void copy_rows_out(const GstVideoFrame *frame, guint plane, uint8_t *to) {
  const gsize row = static_cast<gsize>(GST_VIDEO_FRAME_COMP_WIDTH(frame, plane)) *
                    GST_VIDEO_FRAME_COMP_PSTRIDE(frame, plane);
  const gsize stride = static_cast<gsize>(GST_VIDEO_FRAME_PLANE_STRIDE(frame, plane));
  p3d::copy_rows(to, row, static_cast<const uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(frame, plane)), stride, row,
                 GST_VIDEO_FRAME_COMP_HEIGHT(frame, plane));
}

}  // namespace

bool OutputHistory::previous(const GstVideoInfo *info, FrameView *view) const {
  if (!valid_ || !gst_video_info_is_equal(info, &info_)) return false;
  FrameView v;
  if (!pixel_format_from_gst(GST_VIDEO_INFO_FORMAT(info), &v.format)) return false;
  v.width = GST_VIDEO_INFO_WIDTH(info);
  v.height = GST_VIDEO_INFO_HEIGHT(info);
  for (guint p = 0; p < GST_VIDEO_INFO_N_PLANES(info) && p < 3; ++p) {
    v.plane[p] = const_cast<uint8_t *>(planes_[p].data());
    v.stride[p] = GST_VIDEO_INFO_COMP_WIDTH(info, p) * GST_VIDEO_INFO_COMP_PSTRIDE(info, p);
  }
  *view = v;
  return true;
}

void OutputHistory::update(const GstVideoInfo *info, const GstVideoFrame *out, const ChangeMap &changes, bool whole,
                           const std::vector<uint8_t> &written) {
  const bool first = !seen_;
  seen_ = true;
  if (busy_for(reach_, changes) && !first) {
    valid_ = false;
    return;
  }
  if (!whole && !changes.any()) return;  // the copy holds these pixels already
  FrameView kept;
  if (!whole && written.size() == static_cast<size_t>(GST_VIDEO_INFO_HEIGHT(info)) && previous(info, &kept)) {
    copy_flagged_rows(frame_view(out), kept, written, true);
    return;
  }
  info_ = *info;
  for (guint p = 0; p < GST_VIDEO_FRAME_N_PLANES(out); ++p) {
    planes_[p].resize(static_cast<size_t>(GST_VIDEO_FRAME_COMP_WIDTH(out, p)) * GST_VIDEO_FRAME_COMP_PSTRIDE(out, p) *
                      GST_VIDEO_FRAME_COMP_HEIGHT(out, p));
    copy_rows_out(out, p, planes_[p].data());
  }
  valid_ = true;
}

DepthPlanePtr frame_depth_plane(GstBuffer *buf) {
  auto *m = reinterpret_cast<Pseudo3DDepthMeta *>(gst_buffer_get_meta(buf, PSEUDO3D_DEPTH_META_API_TYPE));
  return m && m->plane ? *m->plane : nullptr;
}

}  // namespace p3d::gst
