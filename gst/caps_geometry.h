// Caps arithmetic for elements that change the frame size: a caps field's
// sizes scaled by a ratio and back (ints, int ranges and lists of them),
// and the format field replaced. The stages' transform_geometry hooks
// (gstpseudo3dbase.h) build their caps with these.
#pragma once

#include <gst/gst.h>

G_BEGIN_DECLS

/* value * num / den for an int, an int range or a list of them (clamped
 * to 1..G_MAXINT). */
void gst_pseudo3d_scale_field(GstStructure *s, const char *field, gint num, gint den);
/* The way back through gst_pseudo3d_scale_field(s, field, num, den): every
 * value v with v * num / den (rounded down) among the field's values, so
 * that a size whose forward image is rounded (an odd width halved) still
 * passes the caps query, and set_info() can refuse it with its reason
 * instead of a bare not-negotiated. */
void gst_pseudo3d_unscale_field(GstStructure *s, const char *field, gint num, gint den);
/* A copy of structure `in` (input sizes) with the output sizes of an
 * element whose output width and height are input * wn / wd and
 * input * hn / hd (gst_pseudo3d_scale_field). */
GstStructure *gst_pseudo3d_sizes_forward(const GstStructure *in, gint wn, gint wd, gint hn, gint hd);
/* A copy of sink-side-bound structure `in` (output sizes) with the input
 * sizes that give them, for an element whose output width and height are
 * input * wn / wd and input * hn / hd: the exact inverse, or (`rounded`)
 * every size whose rounded image they are. A transform towards the sink
 * offers the exact structures first, so that a free upstream fixates a size
 * that works, and the rounded ones after them. */
GstStructure *gst_pseudo3d_sizes_back(const GstStructure *in, gint wn, gint wd, gint hn, gint hd, gboolean rounded);
/* Caps holding one structure (takes s). */
GstCaps *gst_pseudo3d_caps_of(GstStructure *s);
/* Sets the format field to `formats` ("{ A, B }" or one name) and drops the
 * colorimetry and chroma-site, which belong to the old format family. */
void gst_pseudo3d_set_formats(GstStructure *s, const gchar *formats);

G_END_DECLS
