#include "video_util.h"

#include "config.h"

#if HAVE_CUDA
#include <gst/cuda/gstcudamemory.h>
#endif

namespace p3d::gst {

bool pixel_format_from_gst(GstVideoFormat f, PixelFormat *out) {
  switch (f) {
    case GST_VIDEO_FORMAT_NV12: *out = PixelFormat::NV12; return true;
    case GST_VIDEO_FORMAT_I420: *out = PixelFormat::I420; return true;
    case GST_VIDEO_FORMAT_RGBA: *out = PixelFormat::RGBA; return true;
    case GST_VIDEO_FORMAT_BGRA: *out = PixelFormat::BGRA; return true;
    case GST_VIDEO_FORMAT_RGBx: *out = PixelFormat::RGBx; return true;
    case GST_VIDEO_FORMAT_BGRx: *out = PixelFormat::BGRx; return true;
    default: return false;
  }
}

FrameView frame_view(const GstVideoFrame *frame) {
  FrameView v;
  pixel_format_from_gst(GST_VIDEO_FRAME_FORMAT(frame), &v.format);
  v.width = GST_VIDEO_FRAME_WIDTH(frame);
  v.height = GST_VIDEO_FRAME_HEIGHT(frame);
  for (guint i = 0; i < GST_VIDEO_FRAME_N_PLANES(frame) && i < 3; ++i) {
    v.plane[i] = static_cast<uint8_t *>(GST_VIDEO_FRAME_PLANE_DATA(frame, i));
    v.stride[i] = GST_VIDEO_FRAME_PLANE_STRIDE(frame, i);
  }
  return v;
}

namespace {

// Kr/Kb of the info's matrix; unknown or RGB: BT.601, as most decoders
// assume for SD.
void matrix_kr_kb(const GstVideoInfo *info, gdouble *kr, gdouble *kb) {
  if (!gst_video_color_matrix_get_Kr_Kb(info->colorimetry.matrix, kr, kb)) {
    *kr = 0.299;
    *kb = 0.114;
  }
}

}  // namespace

YuvToRgb yuv_params(const GstVideoInfo *info) {
  gdouble kr = 0, kb = 0;
  matrix_kr_kb(info, &kr, &kb);
  return yuv_to_rgb_params(kr, kb, info->colorimetry.range == GST_VIDEO_COLOR_RANGE_0_255);
}

RgbToYuv rgb_to_yuv(const GstVideoInfo *info) {
  gdouble kr = 0, kb = 0;
  matrix_kr_kb(info, &kr, &kb);
  return rgb_to_yuv_params(kr, kb, info->colorimetry.range == GST_VIDEO_COLOR_RANGE_0_255);
}

GstCaps *caps_all_domains(const char *formats, int max_side, const char *extra_fields) {
  const char *extra = extra_fields ? extra_fields : "";
  // No interlace-mode field: caps without one mean progressive, and a
  // template that demanded "progressive" would refuse them in the subset
  // checks of ghost pads. Interlaced caps are refused in set_caps, with a
  // message.
  gchar *sys = g_strdup_printf("video/x-raw, format=(string)%s, width=(int)[ 1, %d ], height=(int)[ 1, %d ], "
                               "framerate=" GST_VIDEO_FPS_RANGE "%s",
                               formats, max_side, max_side, extra);
  GstCaps *caps = gst_caps_from_string(sys);
  g_free(sys);
#if HAVE_CUDA
  GstCaps *cuda = gst_caps_copy(caps);
  gst_caps_set_features_simple(cuda, gst_caps_features_new(GST_CAPS_FEATURE_MEMORY_CUDA_MEMORY, NULL));
  caps = gst_caps_merge(cuda, caps);
#endif
  return caps;
}

}  // namespace p3d::gst
