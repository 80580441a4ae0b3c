/**
 * SECTION:element-pseudo3dpack
 * @title: pseudo3dpack
 *
 * A stereo converter: reads a stereo frame (pseudo3dwarp's full side-by-side
 * pair, or any side-by-side, top-bottom, row/column-interleaved or
 * checkerboard frame, full or half resolution, either eye first, as its
 * caps' multiview-mode and multiview-flags declare) and writes it as an
 * anaglyph (red-cyan, green-magenta, amber-blue; Dubois, colour, half colour
 * or grey), side-by-side or top-bottom at full or half ("anamorphic")
 * resolution, row- or column-interleaved, checkerboard, or one view. The
 * output caps follow GStreamer's multiview conventions, so encoders and
 * muxers signal the packing: multiview-mode per layout, half-aspect on every
 * layout whose views are squeezed, the pixel-aspect-ratio of the input kept,
 * right-view-first exactly when swap-eyes puts the right view first.
 *
 * The output is in the input's packed RGB format (RGBA64_LE pairs keep
 * their 16 bits a sample), or 4:2:0 of the input's depth (NV12/I420,
 * P010_10LE/I420_10LE) when
 * downstream asks for it (an encoder's caps): the pair is packed and
 * converted in one pass (BT.709/BT.601/BT.2020 and the range from the
 * output caps' colorimetry, chroma the mean of each 2x2 block), on the GPU
 * when the frames are there, so no videoconvert and a third of the bytes
 * to download. The output caps keep the input's transfer and primaries
 * (PQ, HLG, BT.2020, BT.709; 4:2:0 output first offers the matrix of those
 * primaries) and its HDR fields (mastering-display-info,
 * content-light-level). An anaglyph mixes the views' colours as SDR code
 * values: PQ and HLG input is refused for it.
 *
 * Plain 2D input is refused: declare how the frame holds the pair with
 * input-layout (and input-right-first). An output in the input's own
 * arrangement and eye order passes buffers through.
 *
 * Every property can be changed while playing; a change that alters the
 * output caps is renegotiated before the next frame, and each frame is
 * packed with the values its caps belong to.
 *
 * ## Example launch lines
 * |[
 * gst-launch-1.0 videotestsrc ! pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp ! pseudo3dpack layout=anaglyph glasses=red-cyan anaglyph-method=dubois ! videoconvert ! autovideosink
 * gst-launch-1.0 filesrc location=sbs-film.mkv ! decodebin ! videoconvert ! pseudo3dpack layout=top-bottom-half ! videoconvert ! autovideosink
 * gst-launch-1.0 filesrc location=film.mp4 ! decodebin ! videoconvert ! pseudo3dconvert layout=side-by-side-half ! video/x-raw,format=I420 ! x264enc frame-packing=side-by-side ! mp4mux ! filesink location=film-3d.mp4
 * ]| The second line turns a film whose caps say side-by-side into half
 * top-bottom for a passive 3D TV; the third packs straight into the
 * encoder's I420.
 */
#include "gstpseudo3dpack.h"

#include "caps_geometry.h"
#include "enums.h"
#include "stage_adaptive.h"
#include "stage_gpu.h"
#include "stereo_caps.h"
#include "stereo_packing.h"
#include "video_util.h"

#if HAVE_CUDA
#include "pack_gpu.h"
#endif

GST_DEBUG_CATEGORY_STATIC(gst_pseudo3d_pack_debug);
#define GST_CAT_DEFAULT gst_pseudo3d_pack_debug

enum {
  PROP_0,
  PROP_PACK,  // the pack's properties: N_PACK_PROPERTIES ids from here (stereo_packing.h)
  PROP_INPUT_LAYOUT = PROP_PACK + p3d::gst::N_PACK_PROPERTIES,
  PROP_INPUT_RIGHT_FIRST,
};

// adaptive (stage_adaptive.h), streaming thread: the previous frame's
// input, parameters and output.
struct PackState {
  p3d::gst::InputHistory input{p3d::ChangeReach::Rows};  // the pack redoes whole rows
  p3d::gst::KeptParams<p3d::PackParams> params;
  p3d::gst::OutputHistory output{p3d::ChangeReach::Rows};
#if HAVE_CUDA
  // adaptive on CUDA memory (cuda/change_gpu.h).
  p3d::gst::WholeOutputGpu adaptive_gpu;
#endif

  void forget() {
    input.reset();
    params.reset();
    output.reset();
#if HAVE_CUDA
    adaptive_gpu.reset();
#endif
  }
};

struct _GstPseudo3DPack {
  GstPseudo3DBase parent;
  p3d::gst::StereoPacking *packing;
  PackState *state;
};

#define gst_pseudo3d_pack_parent_class parent_class
G_DEFINE_TYPE(GstPseudo3DPack, gst_pseudo3d_pack, GST_TYPE_PSEUDO3D_BASE);
GST_ELEMENT_REGISTER_DEFINE(pseudo3dpack, "pseudo3dpack", GST_RANK_NONE, GST_TYPE_PSEUDO3D_PACK);

static GstCaps *transform_geometry(GstPseudo3DBase *base, GstPadDirection from, const GstStructure *in) {
  p3d::gst::StereoPacking *packing = GST_PSEUDO3D_PACK(base)->packing;
  const p3d::gst::PackingGeometry g = packing->negotiating();
  // Input that holds no pair still gets output caps: set_info then refuses
  // it with a message that says how to declare the layout.
  if (from == GST_PAD_SINK) return packing->output_caps(in, g);  // the input's own format, then 4:2:0

  p3d::StereoInput input;
  const bool declared = p3d::gst::declared_input(g, &input);
  // Towards the sink, 4:2:0 output comes from any packed RGB input.
  const bool from_yuv = p3d::gst::names_yuv420(in);
  const char *packed = p3d::gst::formats_for(p3d::gst::FormatKind::Packed, p3d::gst::format_depths(in));

  // Towards the sink: the input sizes that give this output. A declared
  // layout says nothing about the input's caps. From-caps lists first a
  // structure that leaves multiview-mode open, so that upstream elements
  // that do not set it (2D video) keep it unset rather than fixating the
  // first stereo mode offered here, which would relabel 2D frames as a
  // pair: set_info then refuses them with a message. The arrangements
  // pseudo3dpack reads follow (either eye first).
  // The exact sizes first, then the rounded ones (gst_pseudo3d_sizes_back()).
  GstCaps *caps = gst_caps_new_empty();
  for (const auto way : {p3d::gst::SizeWay::BackExact, p3d::gst::SizeWay::BackRounded}) {
    GstStructure *open = packing->through(in, way, g.layout, declared ? input : p3d::StereoInput::SideBySide);
    gst_structure_remove_fields(open, "multiview-mode", "multiview-flags", "views", NULL);
    if (from_yuv) gst_pseudo3d_set_formats(open, packed);
    caps = gst_caps_merge_structure(caps, open);
    if (declared) continue;
    for (const auto &name : p3d::kStereoInputNames) {
      const p3d::StereoInput arrangement = name.value;
      GstStructure *s = packing->through(in, way, g.layout, arrangement);
      if (from_yuv) gst_pseudo3d_set_formats(s, packed);
      p3d::gst::set_multiview_fields(s, p3d::gst::arrangement_signal(arrangement, false),
                                     GST_VIDEO_MULTIVIEW_FLAGS_HALF_ASPECT);
      caps = gst_caps_merge_structure(caps, s);
    }
  }
  return caps;
}

// Output equal to the input: same arrangement, eye order and format.
static bool passes_through(const p3d::PackParams &p, const GstVideoInfo *in, const GstVideoInfo *out) {
  return p3d::pack_is_identity(p) && GST_VIDEO_INFO_FORMAT(in) == GST_VIDEO_INFO_FORMAT(out);
}

static gboolean set_info(GstPseudo3DBase *base, GstCaps *, GstVideoInfo *in, GstCaps *, GstVideoInfo *out) {
  GstPseudo3DPack *self = GST_PSEUDO3D_PACK(base);
  p3d::gst::PackedFrame f;
  const char *why = nullptr;
  const p3d::gst::InputFit fit = self->packing->frame_for(self->packing->commit(), in, &f, &why);
  if (fit == p3d::gst::InputFit::NoPair) {
    gchar *text = g_strdup_printf("pseudo3dpack needs a stereo pair, and its input is %s", why);
    gst_pseudo3d_base_refuse_caps(
        base, text, "%s",
        "declare how the frames hold the pair with input-layout=side-by-side (or side-by-side-half, top-bottom, "
        "top-bottom-half, row-interleaved, column-interleaved, checkerboard) and input-right-first=true if the right "
        "view comes first; to make 3D from 2D video, put pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp before "
        "pseudo3dpack, or use pseudo3dconvert");
    g_free(text);
    return FALSE;
  }
  if (fit == p3d::gst::InputFit::NeedsSdr)
    return gst_pseudo3d_base_refuse_caps(base, p3d::gst::kNeedsSdrText, p3d::gst::kNeedsSdrHint, why);
  if (fit != p3d::gst::InputFit::Fits || f.width != GST_VIDEO_INFO_WIDTH(out) ||
      f.height != GST_VIDEO_INFO_HEIGHT(out)) {
    return gst_pseudo3d_base_refuse_caps(base, "The input frame does not hold a stereo pair of the declared kind",
                                         "input %dx%d, output %dx%d: %s", GST_VIDEO_INFO_WIDTH(in),
                                         GST_VIDEO_INFO_HEIGHT(in), GST_VIDEO_INFO_WIDTH(out),
                                         GST_VIDEO_INFO_HEIGHT(out), why ? why : "the output size does not fit the layout");
  }
  if (p3d::gst::is_deep_info(in) != p3d::gst::is_deep_info(out))
    return gst_pseudo3d_base_refuse_caps(base, p3d::gst::kDepthMismatchText, "input %s, output %s",
                                         GST_VIDEO_INFO_NAME(in), GST_VIDEO_INFO_NAME(out));
  self->packing->set_negotiated(f.params, out);
  gst_base_transform_set_passthrough(GST_BASE_TRANSFORM(self), passes_through(f.params, in, out));
  return TRUE;
}

// A geometry applied at once may start or end the pass-through (a declared
// input layout that the caps already said, with the output in its
// arrangement): the allocation is then redone.
static gboolean frame_boundary(GstPseudo3DBase *base) {
  GstPseudo3DPack *self = GST_PSEUDO3D_PACK(base);
  GstBaseTransform *trans = GST_BASE_TRANSFORM(self);
  const auto boundary = self->packing->frame_boundary(&base->in_info, &base->out_info);
  if (boundary == p3d::gst::StereoPacking::Boundary::Applied) {
    const bool through = passes_through(self->packing->frame_params(), &base->in_info, &base->out_info);
    if (through != static_cast<bool>(gst_base_transform_is_passthrough(trans))) {
      gst_base_transform_set_passthrough(trans, through);
      gst_base_transform_reconfigure_src(trans);
    }
  }
  return boundary == p3d::gst::StereoPacking::Boundary::Renegotiate;
}

static GstFlowReturn process(GstPseudo3DBase *base, GstPseudo3DPath path, GstBuffer *, GstVideoFrame *in,
                             GstVideoFrame *out) {
  GstPseudo3DPack *self = GST_PSEUDO3D_PACK(base);
  const p3d::PackParams params = self->packing->frame_params();
  const p3d::FrameView src = p3d::gst::frame_view(in), dst = p3d::gst::frame_view(out);
  PackState *state = self->state;
  if (gst_pseudo3d_base_take_history_reset(base)) state->forget();
  const p3d::gst::AdaptiveSettings adaptive = p3d::gst::adaptive_settings(base);
#if HAVE_CUDA
  // Adaptive on the device: a frame whose input did not change is not
  // packed, the kept output is copied into it; while frames keep
  // changing, uncompared (ChangeBackOff).
  if (path == GST_PSEUDO3D_PATH_GPU) {
    if (!adaptive.on) state->forget();
    const bool keep = state->adaptive_gpu.begin(adaptive.on);
    const bool changed_params = keep && state->params.changed(params);
    const GstFlowReturn ret = p3d::gst::run_gpu(base, "packing the stereo pair", [&]() -> p3d::CudaStatus {
      cudaStream_t stream = base->gpu->stream();
      p3d::StageGate gate;
      if (keep)
        P3D_CUDA_TRY_STATUS(
            state->adaptive_gpu.decide(src, nullptr, adaptive.tolerance, dst, changed_params, stream, &gate));
      P3D_CUDA_TRY_STATUS(p3d::pack_gpu(params, src, dst, stream, gate));
      if (keep) P3D_CUDA_TRY_STATUS(state->adaptive_gpu.finish(dst, stream));
      return p3d::CudaStatus{};
    });
    state->adaptive_gpu.end(ret == GST_FLOW_OK);
    return ret;
  }
#else
  (void)path;
#endif
  // Adaptive: the output rows that read a changed input row are packed
  // again, the rest is the previous output.
  p3d::ChangeMap changes;
  p3d::FrameView previous;
  bool whole = true;
  // While frames keep changing, uncompared (ChangeBackOff): the history
  // is dropped, and so is the output kept.
  const bool compare = state->input.begin(adaptive.on);
  if (compare) {
    changes = state->input.compare(src, nullptr, adaptive.tolerance);
    // A change in every row of tiles: nothing of the previous output survives.
    whole = state->params.changed(params) || p3d::busy_for(p3d::ChangeReach::Rows, changes) ||
            !state->output.previous(&base->out_info, &previous);
  } else {
    state->params.reset();
    state->output.reset();
  }
  p3d::KeptOutput kept{whole ? nullptr : &previous, {}};  // the rows not packed again
  if (!p3d::pack_changed_cpu(params, src, dst, whole ? nullptr : &changes, &kept)) {
    GST_ELEMENT_ERROR(self, STREAM, FAILED, ("Frames do not fit the layout"),
                      ("input %dx%d, output %dx%d", src.width, src.height, dst.width, dst.height));
    return GST_FLOW_ERROR;
  }
  if (compare) state->output.update(&base->out_info, out, changes, whole, kept.written);
  return GST_FLOW_OK;
}

static void release(GstPseudo3DBase *base) {
  PackState *state = GST_PSEUDO3D_PACK(base)->state;
  state->forget();
#if HAVE_CUDA
  state->adaptive_gpu = p3d::gst::WholeOutputGpu();
#endif
}

static void gst_pseudo3d_pack_set_property(GObject *object, guint prop_id, const GValue *value, GParamSpec *pspec) {
  GstPseudo3DPack *self = GST_PSEUDO3D_PACK(object);
  if (self->packing->set_property(prop_id, value)) return;
  switch (prop_id) {
    case PROP_INPUT_LAYOUT:
      self->packing->request([&](p3d::gst::PackingGeometry &g) { g.input = g_value_get_enum(value); });
      break;
    case PROP_INPUT_RIGHT_FIRST:
      self->packing->request([&](p3d::gst::PackingGeometry &g) { g.input_right_first = g_value_get_boolean(value); });
      break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
}

static void gst_pseudo3d_pack_get_property(GObject *object, guint prop_id, GValue *value, GParamSpec *pspec) {
  GstPseudo3DPack *self = GST_PSEUDO3D_PACK(object);
  if (self->packing->get_property(prop_id, value)) return;
  switch (prop_id) {
    case PROP_INPUT_LAYOUT: g_value_set_enum(value, self->packing->requested().input); break;
    case PROP_INPUT_RIGHT_FIRST: g_value_set_boolean(value, self->packing->requested().input_right_first); break;
    default: G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec); break;
  }
}

static void gst_pseudo3d_pack_finalize(GObject *object) {
  delete GST_PSEUDO3D_PACK(object)->packing;
  delete GST_PSEUDO3D_PACK(object)->state;
  G_OBJECT_CLASS(parent_class)->finalize(object);
}

static void gst_pseudo3d_pack_class_init(GstPseudo3DPackClass *klass) {
  GObjectClass *gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass *element_class = GST_ELEMENT_CLASS(klass);
  GstPseudo3DBaseClass *base_class = GST_PSEUDO3D_BASE_CLASS(klass);
  const p3d::gst::PackingGeometry dg;
  const auto flags = (GParamFlags)(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS | GST_PARAM_MUTABLE_PLAYING);

  gobject_class->set_property = gst_pseudo3d_pack_set_property;
  gobject_class->get_property = gst_pseudo3d_pack_get_property;
  gobject_class->finalize = gst_pseudo3d_pack_finalize;

  p3d::gst::install_pack_properties(gobject_class, PROP_PACK, p3d::gst::kPackDefaultLayout);
  g_object_class_install_property(
      gobject_class, PROP_INPUT_LAYOUT,
      g_param_spec_enum("input-layout", "Input layout",
                        "How the input frames hold the stereo pair: from the caps' multiview-mode and "
                        "multiview-flags (pseudo3dwarp, 3D decoders and demuxers set them), or declared here for "
                        "input whose caps say nothing (plain 2D caps). While playing, a layout the frames cannot "
                        "hold (top-bottom of an odd height) is refused with a warning and the stream goes on",
                        GST_TYPE_PSEUDO3D_INPUT_LAYOUT, dg.input, flags));
  g_object_class_install_property(
      gobject_class, PROP_INPUT_RIGHT_FIRST,
      g_param_spec_boolean("input-right-first", "Input right view first",
                           "With a declared input-layout: the right view comes first (left half, top half, even "
                           "rows or columns); with from-caps the caps' right-view-first flag decides",
                           dg.input_right_first, flags));

  gst_element_class_set_static_metadata(element_class, "pseudo3d stereo packing", "Filter/Converter/Video",
                                        "Converts a stereo pair into anaglyph, side-by-side, top-bottom, "
                                        "interleaved or single-view output",
                                        "pseudo3d developers");
  // Packed RGB in; out the same format, or 4:2:0 of its depth for encoders.
  GstCaps *sink = p3d::gst::caps_all_domains(
      p3d::gst::formats_for(p3d::gst::FormatKind::Packed, p3d::gst::kAnyDepth), 2 * p3d::kMaxFrameSide);
  GstCaps *src = p3d::gst::caps_all_domains(P3D_ALL_FORMATS, 2 * p3d::kMaxFrameSide);
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("sink", GST_PAD_SINK, GST_PAD_ALWAYS, sink));
  gst_element_class_add_pad_template(element_class, gst_pad_template_new("src", GST_PAD_SRC, GST_PAD_ALWAYS, src));
  gst_caps_unref(sink);
  gst_caps_unref(src);

  base_class->transform_geometry = transform_geometry;
  base_class->set_info = set_info;
  base_class->frame_boundary = frame_boundary;
  base_class->process = process;
  base_class->release = release;

  GST_DEBUG_CATEGORY_INIT(gst_pseudo3d_pack_debug, "pseudo3dpack", 0, "pseudo3d stereo packing");
  gst_type_mark_as_plugin_api(GST_TYPE_PSEUDO3D_INPUT_LAYOUT, (GstPluginAPIFlags)0);
}

static void gst_pseudo3d_pack_init(GstPseudo3DPack *self) {
  self->packing = new p3d::gst::StereoPacking(GST_BASE_TRANSFORM(self), PROP_PACK, p3d::gst::PairSource::InputFrame,
                                              p3d::gst::kPackDefaultLayout);
  self->state = new PackState();
  GST_PSEUDO3D_BASE(self)->staged = self->packing->staged();
  gst_base_transform_set_in_place(GST_BASE_TRANSFORM(self), FALSE);
}
