#include "stage_adaptive.h"

#include <cstring>

#include "depth_meta.h"

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
                                  const FrameView &out, bool whole, cudaStream_t stream, StageGate *gate) {
  P3D_CUDA_TRY_STATUS(inputs_.compare(frame, depth, tolerance, stream));
  P3D_CUDA_TRY_STATUS(output_.decide(inputs_.changes(), out, whole, stream));
  *gate = output_.gate();
  return {};
}

void WholeOutputGpu::end(bool ok) {
  if (!ok) {  // the histories may have moved on without the output
    reset();
    return;
  }
  // Any change makes such a stage compute the whole frame: it is busy.
  if (comparing_ && inputs_.compared()) backoff_.observe(output_.last_changed());
}

void WholeOutputGpu::reset() {
  inputs_.reset();
  output_.reset();
  backoff_.reset();
}
#endif

namespace {

// Copies plane `plane`'s rows between a mapped frame (its strides) and a
// packed copy (rows back to back): into the frame, or out of it.
void copy_rows(const GstVideoFrame *frame, guint plane, const uint8_t *from, uint8_t *to, bool into_frame) {
  const gsize row = static_cast<gsize>(GST_VIDEO_FRAME_COMP_WIDTH(frame, plane)) *
                    GST_VIDEO_FRAME_COMP_PSTRIDE(frame, plane);
  const gsize stride = static_cast<gsize>(GST_VIDEO_FRAME_PLANE_STRIDE(frame, plane));
  const gint rows = GST_VIDEO_FRAME_COMP_HEIGHT(frame, plane);
  if (into_frame)
    p3d::copy_rows(to, stride, from, row, row, rows);
  else
    p3d::copy_rows(to, row, from, stride, row, rows);
}

}  // namespace

bool OutputHistory::copy_into(const GstVideoInfo *info, GstVideoFrame *out) const {
  if (!valid_ || !gst_video_info_is_equal(info, &info_)) return false;
  for (guint p = 0; p < GST_VIDEO_FRAME_N_PLANES(out); ++p)
    copy_rows(out, p, planes_[p].data(), static_cast<uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(out, p)), true);
  return true;
}

void OutputHistory::update(const GstVideoInfo *info, const GstVideoFrame *out, const ChangeMap &changes, bool whole) {
  const bool first = !seen_;
  seen_ = true;
  if (busy_for(reach_, changes) && !first) {
    valid_ = false;
    return;
  }
  if (!whole && !changes.any()) return;  // the copy holds these pixels already
  info_ = *info;
  for (guint p = 0; p < GST_VIDEO_FRAME_N_PLANES(out); ++p) {
    planes_[p].resize(static_cast<size_t>(GST_VIDEO_FRAME_COMP_WIDTH(out, p)) * GST_VIDEO_FRAME_COMP_PSTRIDE(out, p) *
                      GST_VIDEO_FRAME_COMP_HEIGHT(out, p));
    copy_rows(out, p, static_cast<const uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(out, p)), planes_[p].data(), false);
  }
  valid_ = true;
}

DepthPlanePtr frame_depth_plane(GstBuffer *buf) {
  auto *m = reinterpret_cast<Pseudo3DDepthMeta *>(gst_buffer_get_meta(buf, PSEUDO3D_DEPTH_META_API_TYPE));
  return m && m->plane ? *m->plane : nullptr;
}

}  // namespace p3d::gst
