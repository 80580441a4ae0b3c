// Pseudo3DDepthMeta: the depth map of a buffer (see depth_plane.h).
//
// The meta describes the pixels of its frame, so it registers the video,
// size and orientation tags, and the memory tag because the plane lives in
// the memory domain of the frame (host or one CUDA context). GStreamer's
// transforms decide by those tags:
//  * a copy of the whole buffer (gst_buffer_copy, make_writable, tee and
//    queue pass the buffer itself) keeps it, sharing the plane;
//  * GstBaseTransform never copies memory-tagged metas into a new output
//    buffer, so a scaler, a flip or rotation, a crop, videoconvert and
//    cudaupload/cudadownload all drop it, and the next pseudo3d stage says
//    that it needs pseudo3ddepth (a pseudo3ddepth there estimates afresh);
//  * where an element asks the meta to scale itself
//    (GST_VIDEO_META_TRANSFORM_IS_SCALE), a host plane is resampled to the
//    new size (bilinear) and a device plane is dropped;
//  * a copy of part of a buffer (a byte region) drops it.
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
