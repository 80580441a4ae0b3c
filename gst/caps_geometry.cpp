#include "caps_geometry.h"

#include <algorithm>

// The int range lo..hi (an int: lo == hi) into `out`: an int when one value
// is left, else a range.
static void set_int_range(GValue *out, gint64 lo, gint64 hi) {
  if (lo == hi) {
    g_value_init(out, G_TYPE_INT);
    g_value_set_int(out, (gint)lo);
  } else {
    g_value_init(out, GST_TYPE_INT_RANGE);
    gst_value_set_int_range(out, (gint)lo, (gint)hi);
  }
}

// Maps a caps field's value through map(lo, hi, out): an int as the range
// v..v, an int range, or a list of them, item by item; other values are
// copied.
template <typename RangeMap>
static void map_value(const GValue *in, GValue *out, const RangeMap &map) {
  if (G_VALUE_HOLDS_INT(in)) {
    map(g_value_get_int(in), g_value_get_int(in), out);
  } else if (GST_VALUE_HOLDS_INT_RANGE(in)) {
    map(gst_value_get_int_range_min(in), gst_value_get_int_range_max(in), out);
  } else if (GST_VALUE_HOLDS_LIST(in)) {
    g_value_init(out, GST_TYPE_LIST);
    for (guint i = 0; i < gst_value_list_get_size(in); ++i) {
      GValue item = G_VALUE_INIT;
      map_value(gst_value_list_get_value(in, i), &item, map);
      gst_value_list_append_and_take_value(out, &item);
    }
  } else {
    g_value_init(out, G_VALUE_TYPE(in));
    g_value_copy(in, out);
  }
}

template <typename RangeMap>
static void map_field(GstStructure *s, const char *field, const RangeMap &map) {
  const GValue *v = gst_structure_get_value(s, field);
  if (!v) return;
  GValue mapped = G_VALUE_INIT;
  map_value(v, &mapped, map);
  gst_structure_take_value(s, field, &mapped);
}

void gst_pseudo3d_scale_field(GstStructure *s, const char *field, gint num, gint den) {
  if (num == den) return;
  auto scale = [&](gint v) -> gint64 { return CLAMP((gint64)v * num / den, 1, G_MAXINT); };
  map_field(s, field, [&](gint lo, gint hi, GValue *out) {
    if (lo == hi) return set_int_range(out, scale(lo), scale(lo));
    const gint64 a = scale(lo);  // a range stays a range (but for G_MAXINT itself)
    set_int_range(out, a, std::max(scale(hi), std::min<gint64>(a + 1, G_MAXINT)));
  });
}

// The values x >= 1 with lo <= x * num / den <= hi (floor): ceil(lo * den /
// num) .. floor(((hi + 1) * den - 1) / num). None (an odd size, doubled):
// the smallest x above, whose image the caps then refuse.
void gst_pseudo3d_unscale_field(GstStructure *s, const char *field, gint num, gint den) {
  if (num == den) return;
  map_field(s, field, [&](gint lo, gint hi, GValue *out) {
    const gint64 a = CLAMP(((gint64)lo * den + num - 1) / num, 1, G_MAXINT);
    const gint64 b = CLAMP((((gint64)hi + 1) * den - 1) / num, 1, G_MAXINT);
    set_int_range(out, a, std::max(a, b));
  });
}

GstStructure *gst_pseudo3d_sizes_forward(const GstStructure *in, gint wn, gint wd, gint hn, gint hd) {
  GstStructure *s = gst_structure_copy(in);
  gst_pseudo3d_scale_field(s, "width", wn, wd);
  gst_pseudo3d_scale_field(s, "height", hn, hd);
  return s;
}

GstStructure *gst_pseudo3d_sizes_back(const GstStructure *in, gint wn, gint wd, gint hn, gint hd, gboolean rounded) {
  if (!rounded) return gst_pseudo3d_sizes_forward(in, wd, wn, hd, hn);  // the exact inverse
  GstStructure *s = gst_structure_copy(in);
  gst_pseudo3d_unscale_field(s, "width", wn, wd);
  gst_pseudo3d_unscale_field(s, "height", hn, hd);
  return s;
}

GstCaps *gst_pseudo3d_caps_of(GstStructure *s) {
  GstCaps *caps = gst_caps_new_empty();
  gst_caps_append_structure(caps, s);
  return caps;
}

void gst_pseudo3d_set_formats(GstStructure *s, const gchar *formats) {
  // formats is "{ A, B }": parse it through a throwaway caps string.
  gchar *str = g_strdup_printf("x, format=(string)%s", formats);
  GstStructure *tmp = gst_structure_from_string(str, NULL);
  g_free(str);
  gst_structure_set_value(s, "format", gst_structure_get_value(tmp, "format"));
  gst_structure_free(tmp);
  // Colorimetry belongs to the format family: let it be re-derived.
  gst_structure_remove_fields(s, "colorimetry", "chroma-site", NULL);
}
