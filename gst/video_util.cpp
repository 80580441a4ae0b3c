#include "video_util.h"

#include <cstring>

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
    case GST_VIDEO_FORMAT_P010_10LE: *out = PixelFormat::P010; return true;
    case GST_VIDEO_FORMAT_I420_10LE: *out = PixelFormat::I420_10; return true;
    case GST_VIDEO_FORMAT_RGBA64_LE: *out = PixelFormat::RGBA64; return true;
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
  return yuv_to_rgb_params(kr, kb, info->colorimetry.range == GST_VIDEO_COLOR_RANGE_0_255, is_deep_info(info) ? 10 : 8);
}

RgbToYuv rgb_to_yuv(const GstVideoInfo *info) {
  gdouble kr = 0, kb = 0;
  matrix_kr_kb(info, &kr, &kb);
  return rgb_to_yuv_params(kr, kb, info->colorimetry.range == GST_VIDEO_COLOR_RANGE_0_255, is_deep_info(info) ? 10 : 8);
}

const char *formats_for(FormatKind kind, unsigned depths) {
  static const char *const kTable[3][3] = {
      // 8-bit, deep, both
      {"{ RGBA, BGRA, RGBx, BGRx }", "RGBA64_LE", "{ RGBA, BGRA, RGBx, BGRx, RGBA64_LE }"},
      {"{ NV12, I420 }", "{ P010_10LE, I420_10LE }", "{ NV12, I420, P010_10LE, I420_10LE }"},
      {"{ NV12, I420, RGBA, BGRA, RGBx, BGRx }", "{ P010_10LE, I420_10LE, RGBA64_LE }", P3D_ALL_FORMATS},
  };
  const int column = depths == kDepth8 ? 0 : (depths == kDepth16 ? 1 : 2);
  return kTable[static_cast<int>(kind)][column];
}

namespace {

// The depth bit of a format name (0 for a name that is not a video format).
unsigned name_depth(const GValue *v) {
  if (!G_VALUE_HOLDS_STRING(v)) return 0;
  const GstVideoFormat f = gst_video_format_from_string(g_value_get_string(v));
  if (f == GST_VIDEO_FORMAT_UNKNOWN) return 0;
  return GST_VIDEO_FORMAT_INFO_DEPTH(gst_video_format_get_info(f), 0) > 8 ? kDepth16 : kDepth8;
}

// Whether a format name is one GStreamer 1.22's CUDA allocator holds, of
// the stages' formats: all but RGBA64_LE (which it aborts on).
bool cuda_memory_takes(const GValue *v) {
  if (!G_VALUE_HOLDS_STRING(v)) return false;
  static const char *const kCuda[] = {"NV12", "I420", "RGBA", "BGRA", "RGBx", "BGRx", "P010_10LE", "I420_10LE"};
  for (const char *name : kCuda)
    if (std::strcmp(g_value_get_string(v), name) == 0) return true;
  return false;
}

}  // namespace

unsigned format_depths(const GstStructure *s) {
  const GValue *v = gst_structure_get_value(s, "format");
  if (!v) return kAnyDepth;
  if (!GST_VALUE_HOLDS_LIST(v)) return name_depth(v);
  unsigned depths = 0;
  for (guint i = 0; i < gst_value_list_get_size(v); ++i) depths |= name_depth(gst_value_list_get_value(v, i));
  return depths;
}

bool keep_cuda_formats(GstStructure *s) {
  const GValue *v = gst_structure_get_value(s, "format");
  if (!v) return true;
  if (!GST_VALUE_HOLDS_LIST(v)) return cuda_memory_takes(v);
  GValue kept = G_VALUE_INIT;
  gst_value_list_init(&kept, gst_value_list_get_size(v));
  for (guint i = 0; i < gst_value_list_get_size(v); ++i) {
    const GValue *f = gst_value_list_get_value(v, i);
    if (cuda_memory_takes(f)) gst_value_list_append_value(&kept, f);
  }
  const guint n = gst_value_list_get_size(&kept);
  if (n == 1) {
    GValue one = G_VALUE_INIT;
    g_value_init(&one, G_TYPE_STRING);
    g_value_copy(gst_value_list_get_value(&kept, 0), &one);
    gst_structure_take_value(s, "format", &one);
    g_value_unset(&kept);
  } else if (n > 1) {
    gst_structure_take_value(s, "format", &kept);
  } else {
    g_value_unset(&kept);
  }
  return n > 0;
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
  for (guint i = gst_caps_get_size(cuda); i > 0; --i)
    if (!keep_cuda_formats(gst_caps_get_structure(cuda, i - 1))) gst_caps_remove_structure(cuda, i - 1);
  gst_caps_set_features_simple(cuda, gst_caps_features_new(GST_CAPS_FEATURE_MEMORY_CUDA_MEMORY, NULL));
  caps = gst_caps_merge(cuda, caps);
#endif
  return caps;
}

}  // namespace p3d::gst
