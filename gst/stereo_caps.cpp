#include "stereo_caps.h"

#include "caps_geometry.h"
#include "colour_caps.h"
#include "video_util.h"

namespace p3d::gst {

namespace {
constexpr GstVideoMultiviewFlags kNone = GST_VIDEO_MULTIVIEW_FLAGS_NONE;

GstVideoMultiviewFlags flags_of(bool half, bool right_first) {
  guint f = kNone;
  if (half) f |= GST_VIDEO_MULTIVIEW_FLAGS_HALF_ASPECT;
  if (right_first) f |= GST_VIDEO_MULTIVIEW_FLAGS_RIGHT_VIEW_FIRST;
  return static_cast<GstVideoMultiviewFlags>(f);
}
}  // namespace

MultiviewSignal arrangement_signal(StereoInput arrangement, bool right_first) {
  switch (arrangement) {
    case StereoInput::SideBySide: return {GST_VIDEO_MULTIVIEW_MODE_SIDE_BY_SIDE, flags_of(false, right_first), 2};
    case StereoInput::SideBySideHalf: return {GST_VIDEO_MULTIVIEW_MODE_SIDE_BY_SIDE, flags_of(true, right_first), 2};
    case StereoInput::TopBottom: return {GST_VIDEO_MULTIVIEW_MODE_TOP_BOTTOM, flags_of(false, right_first), 2};
    case StereoInput::TopBottomHalf: return {GST_VIDEO_MULTIVIEW_MODE_TOP_BOTTOM, flags_of(true, right_first), 2};
    case StereoInput::RowInterleaved: return {GST_VIDEO_MULTIVIEW_MODE_ROW_INTERLEAVED, flags_of(true, right_first), 2};
    case StereoInput::ColumnInterleaved:
      return {GST_VIDEO_MULTIVIEW_MODE_COLUMN_INTERLEAVED, flags_of(true, right_first), 2};
    case StereoInput::Checkerboard:
    default: return {GST_VIDEO_MULTIVIEW_MODE_CHECKERBOARD, flags_of(true, right_first), 2};
  }
}

MultiviewSignal layout_signal(PackLayout layout, bool swap_eyes) {
  StereoInput arrangement;
  if (layout_arrangement(layout, &arrangement)) return arrangement_signal(arrangement, swap_eyes);
  switch (layout) {
    case PackLayout::Left:
      return {swap_eyes ? GST_VIDEO_MULTIVIEW_MODE_RIGHT : GST_VIDEO_MULTIVIEW_MODE_LEFT, kNone, 1};
    case PackLayout::Right:
      return {swap_eyes ? GST_VIDEO_MULTIVIEW_MODE_LEFT : GST_VIDEO_MULTIVIEW_MODE_RIGHT, kNone, 1};
    case PackLayout::Anaglyph:
    default: return {GST_VIDEO_MULTIVIEW_MODE_MONO, kNone, 1};
  }
}

bool arrangement_from_multiview(GstVideoMultiviewMode mode, GstVideoMultiviewFlags flags, StereoInput *arrangement,
                                bool *right_first, const char **why) {
  const guint unsupported = GST_VIDEO_MULTIVIEW_FLAGS_LEFT_FLIPPED | GST_VIDEO_MULTIVIEW_FLAGS_LEFT_FLOPPED |
                            GST_VIDEO_MULTIVIEW_FLAGS_RIGHT_FLIPPED | GST_VIDEO_MULTIVIEW_FLAGS_RIGHT_FLOPPED |
                            GST_VIDEO_MULTIVIEW_FLAGS_MIXED_MONO;
  const bool half = flags & GST_VIDEO_MULTIVIEW_FLAGS_HALF_ASPECT;
  *right_first = flags & GST_VIDEO_MULTIVIEW_FLAGS_RIGHT_VIEW_FIRST;
  switch (mode) {
    case GST_VIDEO_MULTIVIEW_MODE_SIDE_BY_SIDE:
      *arrangement = half ? StereoInput::SideBySideHalf : StereoInput::SideBySide;
      break;
    case GST_VIDEO_MULTIVIEW_MODE_TOP_BOTTOM:
      *arrangement = half ? StereoInput::TopBottomHalf : StereoInput::TopBottom;
      break;
    // Interleaved and checkerboard frames hold half of each view whatever
    // the flag says: both are read back at the frame's full size.
    case GST_VIDEO_MULTIVIEW_MODE_ROW_INTERLEAVED: *arrangement = StereoInput::RowInterleaved; break;
    case GST_VIDEO_MULTIVIEW_MODE_COLUMN_INTERLEAVED: *arrangement = StereoInput::ColumnInterleaved; break;
    case GST_VIDEO_MULTIVIEW_MODE_CHECKERBOARD: *arrangement = StereoInput::Checkerboard; break;
    case GST_VIDEO_MULTIVIEW_MODE_NONE:
    case GST_VIDEO_MULTIVIEW_MODE_MONO: *why = "plain 2D video (no multiview-mode, or mono)"; return false;
    case GST_VIDEO_MULTIVIEW_MODE_LEFT:
    case GST_VIDEO_MULTIVIEW_MODE_RIGHT: *why = "a single view (multiview-mode left or right)"; return false;
    default: *why = "a stereo mode pseudo3dpack does not read (quincunx, frame-by-frame or separate views)"; return false;
  }
  if (flags & unsupported) {
    *why = "stereo with flipped, flopped or mixed-mono views, which pseudo3dpack does not read";
    return false;
  }
  return true;
}

bool arrangement_from_structure(const GstStructure *s, StereoInput *arrangement, bool *right_first, const char **why) {
  const gchar *mode_str = gst_structure_get_string(s, "multiview-mode");
  GstVideoMultiviewMode mode =
      mode_str ? gst_video_multiview_mode_from_caps_string(mode_str) : GST_VIDEO_MULTIVIEW_MODE_NONE;
  guint flags = 0, mask = 0;
  if (!gst_structure_get_flagset(s, "multiview-flags", &flags, &mask)) flags = 0;
  return arrangement_from_multiview(mode, static_cast<GstVideoMultiviewFlags>(flags & mask), arrangement, right_first,
                                    why);
}

void set_multiview_fields(GstStructure *s, const MultiviewSignal &sig, guint mask) {
  gst_structure_set(s, "multiview-mode", G_TYPE_STRING, gst_video_multiview_mode_to_caps_string(sig.mode),
                    "multiview-flags", GST_TYPE_VIDEO_MULTIVIEW_FLAGSET, static_cast<guint>(sig.flags), mask, "views",
                    G_TYPE_INT, sig.views, NULL);
}

GstCaps *packed_output_caps(GstStructure *s) {
  GstStructure *yuv = gst_structure_copy(s);
  gst_pseudo3d_set_formats(yuv, formats_for(FormatKind::Yuv420, format_depths(s)));  // s's depth
  offer_yuv_colorimetry(s, yuv);
  gst_structure_set(yuv, "chroma-site", G_TYPE_STRING, "jpeg", NULL);
  return gst_caps_merge_structure(gst_pseudo3d_caps_of(s), yuv);
}

bool names_yuv420(const GstStructure *s) {
  const GValue *v = gst_structure_get_value(s, "format");
  if (!v) return false;
  auto is_yuv = [](const GValue *f) {
    const char *name = G_VALUE_HOLDS_STRING(f) ? g_value_get_string(f) : nullptr;
    return name && (g_str_equal(name, "NV12") || g_str_equal(name, "I420") || g_str_equal(name, "P010_10LE") ||
                    g_str_equal(name, "I420_10LE"));
  };
  if (!GST_VALUE_HOLDS_LIST(v)) return is_yuv(v);
  for (guint i = 0; i < gst_value_list_get_size(v); ++i)
    if (is_yuv(gst_value_list_get_value(v, i))) return true;
  return false;
}

}  // namespace p3d::gst
