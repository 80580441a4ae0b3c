#include "stage_adaptive.h"

#include "depth_meta.h"

namespace p3d::gst {

AdaptiveSettings adaptive_settings(GstPseudo3DBase *self, GstPseudo3DPath path) {
  AdaptiveSettings s;
  GST_OBJECT_LOCK(self);
  s.on = self->adaptive && path == GST_PSEUDO3D_PATH_CPU;
  s.tolerance = self->reuse_tolerance;
  GST_OBJECT_UNLOCK(self);
  return s;
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

bool OutputHistory::copy_into(const GstVideoInfo *info, GstVideoFrame *out) const {
  if (!last_ || !gst_video_info_is_equal(info, &info_)) return false;
  GstVideoFrame prev;
  if (!gst_video_frame_map(&prev, &info_, last_, GST_MAP_READ)) return false;
  const gboolean copied = gst_video_frame_copy(out, &prev);
  gst_video_frame_unmap(&prev);
  return copied;
}

void OutputHistory::keep(GstBuffer *out, const GstVideoInfo *info) {
  GstBuffer *old = last_;
  last_ = gst_buffer_ref(out);
  info_ = *info;
  if (old) gst_buffer_unref(old);
}

void OutputHistory::reset() {
  if (last_) gst_buffer_unref(last_);
  last_ = nullptr;
}

DepthPlanePtr frame_depth_plane(GstBuffer *buf) {
  auto *m = reinterpret_cast<Pseudo3DDepthMeta *>(gst_buffer_get_meta(buf, PSEUDO3D_DEPTH_META_API_TYPE));
  return m && m->plane ? *m->plane : nullptr;
}

}  // namespace p3d::gst
