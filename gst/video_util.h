// The bridge between GStreamer video types and common/: formats, frame
// views of mapped GstVideoFrames, colorimetry, caps strings.
#pragma once

#include <gst/video/video.h>

#include "frame.h"

#define P3D_ALL_FORMATS "{ NV12, I420, RGBA, BGRA, RGBx, BGRx }"
#define P3D_PACKED_FORMATS "{ RGBA, BGRA, RGBx, BGRx }"
#define P3D_YUV420_FORMATS "{ NV12, I420 }"

namespace p3d::gst {

// FALSE for formats the plugin does not handle.
bool pixel_format_from_gst(GstVideoFormat f, PixelFormat *out);
// View of a mapped frame (host or device pointers, as mapped).
FrameView frame_view(const GstVideoFrame *frame);
// Y'CbCr -> R'G'B' of the info's colorimetry (BT.601 if unknown).
YuvToRgb yuv_params(const GstVideoInfo *info);
// R'G'B' -> Y'CbCr of the info's colorimetry (BT.601 if unknown).
RgbToYuv rgb_to_yuv(const GstVideoInfo *info);

// Raw video of `formats` up to max_side pixels wide and high, in both memory
// domains: CUDA memory first (preferred), then system memory.
GstCaps *caps_all_domains(const char *formats, int max_side, const char *extra_fields = nullptr);

}  // namespace p3d::gst
