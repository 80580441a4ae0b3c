#include "colour_caps.h"

#include <initializer_list>

namespace p3d::gst {

namespace {

GstVideoColorMatrix matrix_of_primaries(GstVideoColorPrimaries primaries) {
  switch (primaries) {
    case GST_VIDEO_COLOR_PRIMARIES_BT2020: return GST_VIDEO_COLOR_MATRIX_BT2020;
    case GST_VIDEO_COLOR_PRIMARIES_SMPTE170M:
    case GST_VIDEO_COLOR_PRIMARIES_BT470BG: return GST_VIDEO_COLOR_MATRIX_BT601;
    default: return GST_VIDEO_COLOR_MATRIX_BT709;
  }
}

void append_string(GValue *list, gchar *text) {
  GValue item = G_VALUE_INIT;
  g_value_init(&item, G_TYPE_STRING);
  g_value_take_string(&item, text);
  gst_value_list_append_and_take_value(list, &item);
}

}  // namespace

bool stated_colorimetry(const GstStructure *s, GstVideoColorimetry *c) {
  const gchar *text = gst_structure_get_string(s, "colorimetry");
  return text && gst_video_colorimetry_from_string(c, text) && c->transfer != GST_VIDEO_TRANSFER_UNKNOWN &&
         c->primaries != GST_VIDEO_COLOR_PRIMARIES_UNKNOWN;
}

void carry_colour_to_rgb(const GstStructure *in, GstStructure *rgb) {
  GstVideoColorimetry c;
  if (!stated_colorimetry(in, &c)) return;
  c.range = GST_VIDEO_COLOR_RANGE_0_255;
  c.matrix = GST_VIDEO_COLOR_MATRIX_RGB;
  gchar *text = gst_video_colorimetry_to_string(&c);
  if (text) gst_structure_set(rgb, "colorimetry", G_TYPE_STRING, text, NULL);
  g_free(text);
}

void offer_yuv_colorimetry(const GstStructure *rgb, GstStructure *yuv) {
  GValue list = G_VALUE_INIT;
  gst_value_list_init(&list, 3);
  GstVideoColorimetry c;
  if (stated_colorimetry(rgb, &c)) {
    c.range = GST_VIDEO_COLOR_RANGE_16_235;
    const GstVideoColorMatrix first = matrix_of_primaries(c.primaries);
    for (GstVideoColorMatrix m : {first, GST_VIDEO_COLOR_MATRIX_BT709, GST_VIDEO_COLOR_MATRIX_BT601,
                                  GST_VIDEO_COLOR_MATRIX_BT2020}) {
      if (m == first && gst_value_list_get_size(&list) > 0) continue;
      c.matrix = m;
      if (gchar *text = gst_video_colorimetry_to_string(&c)) append_string(&list, text);
    }
  } else {
    for (const char *name : {"bt709", "bt601", "bt2020"}) append_string(&list, g_strdup(name));
  }
  gst_structure_take_value(yuv, "colorimetry", &list);
}

bool is_hdr_transfer(GstVideoTransferFunction transfer) {
  return transfer == GST_VIDEO_TRANSFER_SMPTE2084 || transfer == GST_VIDEO_TRANSFER_ARIB_STD_B67;
}

}  // namespace p3d::gst
