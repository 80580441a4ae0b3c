// StereoPacking: what a stage that packs a stereo pair into a layout does
// for the packing, written once for pseudo3dpack (which packs the pair its
// input frame holds) and pseudo3dwarp (which packs the pair it renders):
//  * the properties layout, glasses, anaglyph-method and swap-eyes, with one
//    set of names, ranges, blurbs and flags (the default layout is the
//    stage's; pseudo3dconvert offers them for its warp with pseudo3dpack's);
//  * their values, read and written under the element's object lock; the
//    caps-deciding ones (layout, swap-eyes, and pseudo3dpack's declared
//    input) staged to a frame boundary (staged_geometry.h);
//  * the output caps and size for the geometry being negotiated, and the
//    parameters each frame is packed with: the geometry of the negotiated
//    caps with their 4:2:0 conversion, glasses and method as set now;
//  * the pair buffer of a stage that renders its pair on the CPU.
// The stage keeps what is its own: its other properties, its input caps,
// its refusals, pseudo3dpack's pass-through, the GPU calls.
#pragma once

#include <gst/base/gstbasetransform.h>
#include <gst/video/video.h>

#include <cstdint>
#include <vector>

#include "enums.h"
#include "frame.h"
#include "pack.h"
#include "staged_geometry.h"

namespace p3d::gst {

// Where the pair a stage packs comes from.
enum class PairSource {
  // pseudo3dpack: the input frame holds it, as input-layout declares or the
  // input caps' multiview fields say.
  InputFrame,
  // pseudo3dwarp: rendered from the input frame as a full side-by-side pair,
  // left view first, of two views of the input's size, in packed RGB.
  Rendered,
};

// The properties that decide the output caps (staged_geometry.h).
struct PackingGeometry {
  PackLayout layout = PackLayout::Anaglyph;
  bool swap_eyes = false;
  // pseudo3dpack's input-layout and input-right-first (PairSource::InputFrame).
  GstPseudo3DInputLayout input = GST_PSEUDO3D_INPUT_LAYOUT_FROM_CAPS;
  bool input_right_first = false;
  bool operator==(const PackingGeometry &o) const {
    return layout == o.layout && swap_eyes == o.swap_eyes && input == o.input &&
           input_right_first == o.input_right_first;
  }
};

// The pack's properties, at consecutive ids from a stage's first one.
enum PackProperty : guint {
  PACK_PROP_LAYOUT,
  PACK_PROP_GLASSES,
  PACK_PROP_ANAGLYPH_METHOD,
  PACK_PROP_SWAP_EYES,
  N_PACK_PROPERTIES,
};

// Installs the pack's properties at ids first_id.. (PackProperty order).
// layout_blurb: null for pseudo3dpack's; a stage whose default layout means
// something of its own (pseudo3dwarp: side-by-side is the pair it renders)
// says so in its own.
void install_pack_properties(GObjectClass *klass, guint first_id, PackLayout default_layout,
                             const char *layout_blurb = nullptr);
// pseudo3dpack's default layout.
constexpr PackLayout kPackDefaultLayout = PackLayout::Anaglyph;
// A new spec of the pack property `name` as pseudo3dpack has it (its
// blurbs and defaults), or null when no pack property has that name.
GParamSpec *pack_property_spec(const char *name);

// The arrangement input-layout declares, or false for from-caps.
bool declared_input(const PackingGeometry &g, StereoInput *arrangement);

// How a size goes through a packing stage: towards the source, or back to
// the input size that gives it exactly, or back to every input size whose
// rounded image it is (gst_pseudo3d_sizes_back()).
enum class SizeWay { ToSrc, BackExact, BackRounded };

// What a geometry makes of a negotiated input.
struct PackedFrame {
  PackParams params;  // layout, eye order and the pair's arrangement (glasses, method and yuv not set)
  int width = 0, height = 0;  // the output frame
};
enum class InputFit {
  Fits,
  NoPair,   // the input caps hold no stereo pair (PairSource::InputFrame, from-caps)
  NoViews,  // the frame cannot hold the pair as declared (a full top-bottom pair of odd height)
  NeedsSdr,  // an anaglyph of HDR input (colour_caps.h): refused rather than written as SDR
};

// The refusal of InputFit::NeedsSdr: its message, and its debug text
// with a %s for frame_for()'s *why.
extern const char kNeedsSdrText[];
extern const char kNeedsSdrHint[];
// The refusal of output caps of another sample depth than the input's.
extern const char kDepthMismatchText[];

class StereoPacking {
 public:
  // owner: the element (its object lock guards the values); first_id: the
  // id install_pack_properties() was given.
  StereoPacking(GstBaseTransform *owner, guint first_id, PairSource source, PackLayout default_layout);
  StereoPacking(const StereoPacking &) = delete;
  StereoPacking &operator=(const StereoPacking &) = delete;

  // For GstPseudo3DBase's `staged`.
  StagedGeometryBase *staged() { return &geometry_; }

  // set_property/get_property of the pack's properties: false for any
  // other id. A caps-deciding change asks for renegotiation.
  bool set_property(guint prop_id, const GValue *value);
  bool get_property(guint prop_id, GValue *value);

  // The requested geometry, and a change of it (pseudo3dpack's input
  // properties), under the lock; a change that differs from the active
  // value asks for renegotiation.
  PackingGeometry requested();
  template <typename Change>
  void request(Change &&change) {
    GST_OBJECT_LOCK(owner_);
    PackingGeometry g = geometry_.requested();
    change(g);
    const bool reconfigure = geometry_.request(g);
    GST_OBJECT_UNLOCK(owner_);
    if (reconfigure) gst_base_transform_reconfigure_src(owner_);
  }

  // transform_geometry: the geometry to negotiate with.
  PackingGeometry negotiating();
  // The output structure for input structure `in`, with the layout's size
  // and signalling, then its 4:2:0 variant (packed_output_caps()). An input
  // structure that holds no pair gets the caps of a full side-by-side one:
  // set_info then refuses it.
  GstCaps *output_caps(const GstStructure *in, const PackingGeometry &g) const;
  // A copy of `in` with its sizes taken through the stage `way`, for a pair
  // the input frame holds as `arrangement` (PairSource::InputFrame; a
  // rendered pair's views have the input's size).
  GstStructure *through(const GstStructure *in, SizeWay way, PackLayout layout,
                        StereoInput arrangement = StereoInput::SideBySide) const;

  // What geometry g makes of input `in`; *why says why it does not fit.
  InputFit frame_for(const PackingGeometry &g, const GstVideoInfo *in, PackedFrame *f, const char **why) const;
  // set_info: the negotiating geometry becomes active; returns it.
  PackingGeometry commit();
  // set_info, once the caps are accepted: frames are packed with
  // `negotiated`'s geometry, converted to the output's 4:2:0 if it is that.
  void set_negotiated(const PackParams &negotiated, const GstVideoInfo *out);

  // Before each frame (streaming thread): a pending request whose output
  // caps equal the negotiated ones (swap-eyes of an anaglyph, a declared
  // input the caps already said) becomes active at once; any other asks
  // for renegotiation.
  enum class Boundary { Unchanged, Applied, Renegotiate };
  Boundary frame_boundary(const GstVideoInfo *in, const GstVideoInfo *out);

  // The parameters the next frame is packed with.
  PackParams frame_params();

  // CPU path (streaming thread). The frame a stage renders its pair of two
  // view_width x view_height views into: `dst` itself where the output is
  // the pair in its format, else the pair buffer (in dst's packed RGB
  // format, RGBA for 4:2:0 output).
  FrameView pair_target(const PackParams &p, int view_width, int view_height, const FrameView &dst);

 private:
  GstBaseTransform *owner_;
  guint first_id_;
  PairSource source_;
  /* object lock */
  StagedGeometry<PackingGeometry> geometry_;
  AnaglyphGlasses glasses_;  // read per frame
  AnaglyphMethod method_;    // read per frame
  PackParams active_;        // the negotiated caps' geometry and 4:2:0 conversion
  /* streaming thread */
  std::vector<uint8_t> pair_;
};

}  // namespace p3d::gst
