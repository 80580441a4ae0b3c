#include "stereo_packing.h"

#include "caps_geometry.h"
#include "colour_caps.h"
#include "stereo_caps.h"
#include "video_util.h"

namespace p3d::gst {

const char kNeedsSdrText[] = "An anaglyph needs SDR video: choose another layout for HDR (PQ or HLG) video";
const char kDepthMismatchText[] =
    "The output must keep the input's sample depth: 8-bit formats give 8-bit output, 10- and 16-bit formats "
    "(P010_10LE, I420_10LE, RGBA64_LE) give P010_10LE, I420_10LE or RGBA64_LE";
const char kNeedsSdrHint[] =
    "%s: choose another layout, which keeps the HDR signal, or convert the video to SDR first";

namespace {

const char *const kPropertyNames[N_PACK_PROPERTIES] = {"layout", "glasses", "anaglyph-method", "swap-eyes"};

GParamSpec *new_spec(PackProperty which, PackLayout default_layout, const char *layout_blurb) {
  const PackParams d;
  const auto flags = (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_PLAYING);
  switch (which) {
    case PACK_PROP_LAYOUT:
      return g_param_spec_enum("layout", "Layout",
                               layout_blurb ? layout_blurb
                                            : "Stereo format of the output (a change while playing renegotiates the "
                                              "output caps before the next frame)",
                               GST_TYPE_PSEUDO3D_LAYOUT, static_cast<gint>(default_layout), flags);
    case PACK_PROP_GLASSES:
      return g_param_spec_enum("glasses", "Anaglyph glasses", "Colour filters of the glasses (layout=anaglyph)",
                               GST_TYPE_PSEUDO3D_GLASSES, static_cast<gint>(d.glasses), flags);
    case PACK_PROP_ANAGLYPH_METHOD:
      return g_param_spec_enum("anaglyph-method", "Anaglyph method",
                               "How colours are mixed for the glasses (layout=anaglyph): Dubois least squares ghosts "
                               "least; colour keeps most colour; grey is the most comfortable. Encode anaglyphs as "
                               "RGB or 4:4:4: 4:2:0 chroma smears the red channel",
                               GST_TYPE_PSEUDO3D_ANAGLYPH_METHOD, static_cast<gint>(d.method), flags);
    case PACK_PROP_SWAP_EYES:
    default:
      return g_param_spec_boolean("swap-eyes", "Swap eyes",
                                  "Exchange the left and right views (cross-eyed viewing, reversed glasses); the "
                                  "output caps then say right-view-first",
                                  d.swap_eyes, flags);
  }
}

// Output size over input size per axis, as a ratio.
struct SizeRatio {
  gint wn, wd, hn, hd;
};
SizeRatio size_ratio(PairSource source, PackLayout layout, StereoInput arrangement) {
  SizeRatio r{};
  p3d::pack_size(layout, 1, 1, &r.wn, &r.hn);  // the layout's frame of views of 1 x 1
  const bool held = source == PairSource::InputFrame;
  r.wd = held && arrangement == StereoInput::SideBySide ? 2 : 1;
  r.hd = held && arrangement == StereoInput::TopBottom ? 2 : 1;
  return r;
}

}  // namespace

void install_pack_properties(GObjectClass *klass, guint first_id, PackLayout default_layout,
                             const char *layout_blurb) {
  for (guint i = 0; i < N_PACK_PROPERTIES; ++i)
    g_object_class_install_property(klass, first_id + i,
                                    new_spec(static_cast<PackProperty>(i), default_layout, layout_blurb));
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_LAYOUT, (GstPluginAPIFlags)0);
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_GLASSES, (GstPluginAPIFlags)0);
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_ANAGLYPH_METHOD, (GstPluginAPIFlags)0);
}

GParamSpec *pack_property_spec(const char *name) {
  for (guint i = 0; i < N_PACK_PROPERTIES; ++i)
    if (g_str_equal(name, kPropertyNames[i]))
      return new_spec(static_cast<PackProperty>(i), kPackDefaultLayout, nullptr);
  return nullptr;
}

bool declared_input(const PackingGeometry &g, StereoInput *arrangement) {
  if (g.input == GST_PSEUDO3D_INPUT_LAYOUT_FROM_CAPS) return false;
  *arrangement = static_cast<StereoInput>(g.input - 1);
  return true;
}

StereoPacking::StereoPacking(GstBaseTransform *owner, guint first_id, PairSource source, PackLayout default_layout)
    : owner_(owner), first_id_(first_id), source_(source), geometry_(PackingGeometry{default_layout}) {
  glasses_ = active_.glasses;
  method_ = active_.method;
  active_.layout = default_layout;
}

bool StereoPacking::set_property(guint prop_id, const GValue *value) {
  if (prop_id < first_id_ || prop_id >= first_id_ + N_PACK_PROPERTIES) return false;
  switch (prop_id - first_id_) {
    case PACK_PROP_GLASSES:
      GST_OBJECT_LOCK(owner_);
      glasses_ = static_cast<AnaglyphGlasses>(g_value_get_enum(value));
      GST_OBJECT_UNLOCK(owner_);
      break;
    case PACK_PROP_ANAGLYPH_METHOD:
      GST_OBJECT_LOCK(owner_);
      method_ = static_cast<AnaglyphMethod>(g_value_get_enum(value));
      GST_OBJECT_UNLOCK(owner_);
      break;
    case PACK_PROP_LAYOUT:
      request([&](PackingGeometry &g) { g.layout = static_cast<PackLayout>(g_value_get_enum(value)); });
      break;
    case PACK_PROP_SWAP_EYES:
    default: request([&](PackingGeometry &g) { g.swap_eyes = g_value_get_boolean(value); }); break;
  }
  return true;
}

bool StereoPacking::get_property(guint prop_id, GValue *value) {
  if (prop_id < first_id_ || prop_id >= first_id_ + N_PACK_PROPERTIES) return false;
  GST_OBJECT_LOCK(owner_);
  const PackingGeometry &g = geometry_.requested();
  switch (prop_id - first_id_) {
    case PACK_PROP_LAYOUT: g_value_set_enum(value, static_cast<gint>(g.layout)); break;
    case PACK_PROP_GLASSES: g_value_set_enum(value, static_cast<gint>(glasses_)); break;
    case PACK_PROP_ANAGLYPH_METHOD: g_value_set_enum(value, static_cast<gint>(method_)); break;
    case PACK_PROP_SWAP_EYES:
    default: g_value_set_boolean(value, g.swap_eyes); break;
  }
  GST_OBJECT_UNLOCK(owner_);
  return true;
}

PackingGeometry StereoPacking::requested() {
  GST_OBJECT_LOCK(owner_);
  const PackingGeometry g = geometry_.requested();
  GST_OBJECT_UNLOCK(owner_);
  return g;
}

PackingGeometry StereoPacking::negotiating() {
  GST_OBJECT_LOCK(owner_);
  const PackingGeometry g = geometry_.negotiating();
  GST_OBJECT_UNLOCK(owner_);
  return g;
}

GstStructure *StereoPacking::through(const GstStructure *in, SizeWay way, PackLayout layout,
                                     StereoInput arrangement) const {
  const SizeRatio r = size_ratio(source_, layout, arrangement);
  if (way == SizeWay::ToSrc) return gst_pseudo3d_sizes_forward(in, r.wn, r.wd, r.hn, r.hd);
  return gst_pseudo3d_sizes_back(in, r.wn, r.wd, r.hn, r.hd, way == SizeWay::BackRounded);
}

GstCaps *StereoPacking::output_caps(const GstStructure *in, const PackingGeometry &g) const {
  StereoInput arrangement = StereoInput::SideBySide;
  if (source_ == PairSource::InputFrame && !declared_input(g, &arrangement)) {
    bool right_first = false;
    const char *why = nullptr;
    if (!arrangement_from_structure(in, &arrangement, &right_first, &why)) arrangement = StereoInput::SideBySide;
  }
  GstStructure *s = through(in, SizeWay::ToSrc, g.layout, arrangement);
  if (source_ == PairSource::Rendered) {
    gst_pseudo3d_set_formats(s, formats_for(FormatKind::Packed, format_depths(in)));  // the rendered pair's, in's depth
    carry_colour_to_rgb(in, s);
  }
  set_multiview_fields(s, layout_signal(g.layout, g.swap_eyes), GST_FLAG_SET_MASK_EXACT);
  return packed_output_caps(s);  // the pair's own format, then 4:2:0
}

InputFit StereoPacking::frame_for(const PackingGeometry &g, const GstVideoInfo *in, PackedFrame *f,
                                  const char **why) const {
  PackParams &p = f->params;
  p.layout = g.layout;
  p.swap_eyes = g.swap_eyes;
  int vw = GST_VIDEO_INFO_WIDTH(in), vh = GST_VIDEO_INFO_HEIGHT(in);  // a rendered pair's views
  if (source_ == PairSource::InputFrame) {
    if (declared_input(g, &p.input))
      p.input_right_first = g.input_right_first;
    else if (!arrangement_from_multiview(GST_VIDEO_INFO_MULTIVIEW_MODE(in), GST_VIDEO_INFO_MULTIVIEW_FLAGS(in),
                                         &p.input, &p.input_right_first, why))
      return InputFit::NoPair;
    if (!input_view_size(p.input, GST_VIDEO_INFO_WIDTH(in), GST_VIDEO_INFO_HEIGHT(in), &vw, &vh)) {
      *why = p.input == StereoInput::TopBottom ? "a full top-bottom pair needs an even height"
                                               : "a full side-by-side pair needs an even width";
      return InputFit::NoViews;
    }
  }
  if (p.layout == PackLayout::Anaglyph && is_hdr_transfer(in->colorimetry.transfer)) {
    *why = "an anaglyph mixes the views' colours as SDR code values, and this input is HDR (PQ or HLG)";
    return InputFit::NeedsSdr;
  }
  pack_size(p.layout, vw, vh, &f->width, &f->height);
  return InputFit::Fits;
}

PackingGeometry StereoPacking::commit() {
  GST_OBJECT_LOCK(owner_);
  const PackingGeometry g = geometry_.commit();
  GST_OBJECT_UNLOCK(owner_);
  return g;
}

void StereoPacking::set_negotiated(const PackParams &negotiated, const GstVideoInfo *out) {
  PackParams p = negotiated;
  if (!GST_VIDEO_INFO_IS_RGB(out)) p.yuv = rgb_to_yuv(out);
  GST_OBJECT_LOCK(owner_);
  active_ = p;
  GST_OBJECT_UNLOCK(owner_);
}

StereoPacking::Boundary StereoPacking::frame_boundary(const GstVideoInfo *in, const GstVideoInfo *out) {
  GST_OBJECT_LOCK(owner_);
  const bool pending = geometry_.pending();
  const PackingGeometry want = geometry_.requested();
  GST_OBJECT_UNLOCK(owner_);
  if (!pending) return Boundary::Unchanged;
  PackedFrame f;
  const char *why = nullptr;
  if (frame_for(want, in, &f, &why) != InputFit::Fits) return Boundary::Renegotiate;  // which will say why
  const MultiviewSignal sig = layout_signal(f.params.layout, f.params.swap_eyes);
  if (f.width != GST_VIDEO_INFO_WIDTH(out) || f.height != GST_VIDEO_INFO_HEIGHT(out) ||
      sig.mode != GST_VIDEO_INFO_MULTIVIEW_MODE(out) || sig.flags != GST_VIDEO_INFO_MULTIVIEW_FLAGS(out))
    return Boundary::Renegotiate;
  GST_OBJECT_LOCK(owner_);
  geometry_.activate(want);
  f.params.yuv = active_.yuv;  // the output caps stay
  active_ = f.params;
  GST_OBJECT_UNLOCK(owner_);
  return Boundary::Applied;
}

PackParams StereoPacking::frame_params() {
  GST_OBJECT_LOCK(owner_);
  PackParams p = active_;
  p.glasses = glasses_;
  p.method = method_;
  GST_OBJECT_UNLOCK(owner_);
  return p;
}

FrameView StereoPacking::pair_target(const PackParams &p, int view_width, int view_height, const FrameView &dst) {
  if (pack_is_identity(p) && is_packed_rgb(dst.format)) return dst;
  FrameView pair;
  pair.format = is_packed_rgb(dst.format) ? dst.format : (is_deep(dst.format) ? PixelFormat::RGBA64 : PixelFormat::RGBA);
  pair.width = 2 * view_width;
  pair.height = view_height;
  pair.stride[0] = packed_pixel_bytes(pair.format) * pair.width;
  pair_.resize(static_cast<size_t>(pair.stride[0]) * pair.height);
  pair.plane[0] = pair_.data();
  return pair;
}

}  // namespace p3d::gst
