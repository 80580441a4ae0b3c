#include "depth_meta.h"

#include <gst/video/video.h>

#include <new>

#include <opencv2/imgproc.hpp>

GType pseudo3d_depth_meta_api_get_type(void) {
  static GType type = 0;
  static const gchar *tags[] = {GST_META_TAG_VIDEO_STR, GST_META_TAG_VIDEO_SIZE_STR,
                                GST_META_TAG_VIDEO_ORIENTATION_STR, GST_META_TAG_MEMORY_STR, NULL};
  if (g_once_init_enter(&type)) {
    GType t = gst_meta_api_type_register("Pseudo3DDepthMetaAPI", tags);
    g_once_init_leave(&type, t);
  }
  return type;
}

static gboolean depth_meta_init(GstMeta *meta, gpointer, GstBuffer *) {
  reinterpret_cast<Pseudo3DDepthMeta *>(meta)->plane = new (std::nothrow) p3d::gst::DepthPlanePtr();
  return reinterpret_cast<Pseudo3DDepthMeta *>(meta)->plane != nullptr;
}

static void depth_meta_free(GstMeta *meta, GstBuffer *) {
  auto *m = reinterpret_cast<Pseudo3DDepthMeta *>(meta);
  delete m->plane;
  m->plane = nullptr;
}

// A host plane resampled to width x height; null for device planes or on failure.
static p3d::gst::DepthPlanePtr scaled_host_plane(const p3d::gst::DepthPlane &src, int width, int height) {
  if (src.on_device || width <= 0 || height <= 0 || src.width <= 0 || src.height <= 0) return nullptr;
  try {
    auto plane = std::make_shared<p3d::gst::DepthPlane>();
    plane->width = width;
    plane->height = height;
    plane->host.resize(static_cast<size_t>(width) * height);
    const cv::Mat in(src.height, src.width, CV_32FC1, const_cast<float *>(src.host.data()));
    cv::Mat out(height, width, CV_32FC1, plane->host.data());
    cv::resize(in, out, out.size(), 0, 0, cv::INTER_LINEAR);
    return plane;
  } catch (const std::exception &) {  // bad_alloc or cv::Exception: drop the meta rather than fail the copy
    return nullptr;
  }
}

static gboolean depth_meta_transform(GstBuffer *dest, GstMeta *meta, GstBuffer *, GQuark type, gpointer data) {
  auto *src = reinterpret_cast<Pseudo3DDepthMeta *>(meta);
  if (!src->plane || !*src->plane) return FALSE;
  p3d::gst::DepthPlanePtr plane;
  if (GST_META_TRANSFORM_IS_COPY(type)) {
    if (reinterpret_cast<GstMetaTransformCopy *>(data)->region) return FALSE;  // part of the bytes: not a frame
    plane = *src->plane;  // the same frame: share the plane
  } else if (GST_VIDEO_META_TRANSFORM_IS_SCALE(type)) {
    const auto *scale = reinterpret_cast<GstVideoMetaTransform *>(data);
    const p3d::gst::DepthPlane &in = **src->plane;
    // Only a scale of the frame the depth belongs to can be followed.
    if (GST_VIDEO_INFO_WIDTH(scale->in_info) != in.width || GST_VIDEO_INFO_HEIGHT(scale->in_info) != in.height)
      return FALSE;
    plane = scaled_host_plane(in, GST_VIDEO_INFO_WIDTH(scale->out_info), GST_VIDEO_INFO_HEIGHT(scale->out_info));
    if (!plane) return FALSE;
  } else {
    return FALSE;  // any other geometry change: the depth no longer fits
  }
  return pseudo3d_buffer_set_depth(dest, std::move(plane)) != nullptr;
}

const GstMetaInfo *pseudo3d_depth_meta_get_info(void) {
  static const GstMetaInfo *info = NULL;
  if (g_once_init_enter(&info)) {
    const GstMetaInfo *i = gst_meta_register(PSEUDO3D_DEPTH_META_API_TYPE, "Pseudo3DDepthMeta", sizeof(Pseudo3DDepthMeta),
                                             depth_meta_init, depth_meta_free, depth_meta_transform);
    g_once_init_leave(&info, i);
  }
  return info;
}

Pseudo3DDepthMeta *pseudo3d_buffer_set_depth(GstBuffer *buffer, p3d::gst::DepthPlanePtr plane) {
  auto *m = reinterpret_cast<Pseudo3DDepthMeta *>(gst_buffer_get_meta(buffer, PSEUDO3D_DEPTH_META_API_TYPE));
  if (!m) m = reinterpret_cast<Pseudo3DDepthMeta *>(gst_buffer_add_meta(buffer, pseudo3d_depth_meta_get_info(), NULL));
  if (!m) return nullptr;
  *m->plane = std::move(plane);
  return m;
}

p3d::gst::DepthPlane *pseudo3d_buffer_get_depth(GstBuffer *buffer) {
  auto *m = reinterpret_cast<Pseudo3DDepthMeta *>(gst_buffer_get_meta(buffer, PSEUDO3D_DEPTH_META_API_TYPE));
  return m && m->plane ? m->plane->get() : nullptr;
}
