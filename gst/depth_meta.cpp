#include "depth_meta.h"

#include <gst/video/video.h>

GType pseudo3d_depth_meta_api_get_type(void) {
  static GType type = 0;
  static const gchar *tags[] = {NULL};  // no tags: transforms decide by kind below
  if (g_once_init_enter(&type)) {
    GType t = gst_meta_api_type_register("Pseudo3DDepthMetaAPI", tags);
    g_once_init_leave(&type, t);
  }
  return type;
}

static gboolean depth_meta_init(GstMeta *meta, gpointer, GstBuffer *) {
  reinterpret_cast<Pseudo3DDepthMeta *>(meta)->plane = new p3d::gst::DepthPlanePtr();
  return TRUE;
}

static void depth_meta_free(GstMeta *meta, GstBuffer *) {
  auto *m = reinterpret_cast<Pseudo3DDepthMeta *>(meta);
  delete m->plane;
  m->plane = nullptr;
}

static gboolean depth_meta_transform(GstBuffer *dest, GstMeta *meta, GstBuffer *, GQuark type, gpointer data) {
  auto *src = reinterpret_cast<Pseudo3DDepthMeta *>(meta);
  if (GST_META_TRANSFORM_IS_COPY(type)) {
    auto *copy = reinterpret_cast<GstMetaTransformCopy *>(data);
    if (copy->region) return FALSE;  // a part of the frame: the depth map no longer matches
    auto *m = reinterpret_cast<Pseudo3DDepthMeta *>(gst_buffer_add_meta(dest, pseudo3d_depth_meta_get_info(), NULL));
    if (!m) return FALSE;
    *m->plane = *src->plane;
    return TRUE;
  }
  return FALSE;  // scaling and other geometry changes invalidate the depth
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
