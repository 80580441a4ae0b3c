// Pseudo3DDepthMeta: the depth map of a buffer (see depth_plane.h). Copied
// with the buffer (shared, reference counted); dropped by transforms that
// change the frame geometry, since the depth no longer fits.
#pragma once

#include <gst/gst.h>

#include "depth_plane.h"

struct Pseudo3DDepthMeta {
  GstMeta meta;
  p3d::gst::DepthPlanePtr *plane;  // heap-held shared pointer (GstMeta is C)
};

GType pseudo3d_depth_meta_api_get_type(void);
#define PSEUDO3D_DEPTH_META_API_TYPE (pseudo3d_depth_meta_api_get_type())
const GstMetaInfo *pseudo3d_depth_meta_get_info(void);

// Attaches (or replaces) the buffer's depth. The buffer must be writable.
Pseudo3DDepthMeta *pseudo3d_buffer_set_depth(GstBuffer *buffer, p3d::gst::DepthPlanePtr plane);
// The buffer's depth plane, or null.
p3d::gst::DepthPlane *pseudo3d_buffer_get_depth(GstBuffer *buffer);
