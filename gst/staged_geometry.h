// Properties that decide the output caps (pack's layout, depth's method...)
// may be set from any thread at any time, but a frame must be processed with
// the values its negotiated caps were computed from. As in videoflip, such a
// value lives in three places:
//
//   requested    what the property was last set to (set_property);
//   configuring  what a negotiation works with (a CAPS event, the
//                renegotiation before a buffer, a caps, accept-caps or
//                allocation query): the request as it was when the outermost
//                one began, frozen until the last one ends, so that all the
//                transform_caps calls of one negotiation and its set_info
//                agree;
//   active       what the negotiated caps belong to: set_info commits the
//                configuring value, and every frame is processed with it.
//
// A request that differs from the active value asks for renegotiation
// (gst_base_transform_reconfigure_src); GstBaseTransform renegotiates before
// the next buffer, so a change takes effect at a frame boundary.
//
// A live request that the running stream cannot take (an RGBD method on a
// width that cannot be halved, a declared top-bottom input of odd height)
// must not stop the stream: the base renegotiates it before the frame, and
// when that fails, revert() goes back to the value of the caps in force
// (settle() records it after every negotiation that succeeded), and frames
// go on with it.
//
// Not thread-safe by itself: every call is made with the element's object
// lock held. G needs operator==.
#pragma once

namespace p3d::gst {

// What GstPseudo3DBase calls, whatever the stage's geometry type.
class StagedGeometryBase {
 public:
  virtual ~StagedGeometryBase() = default;
  // GstPseudo3DBase's bracket around each negotiation: begin (true) or end.
  virtual void freeze(bool frozen) = 0;
  // Whether the request still differs from the active value.
  virtual bool pending() const = 0;
  // The caps in force (negotiated and accepted downstream) belong to the
  // active value.
  virtual void settle() = 0;
  // The request could not be negotiated: request, configuring and active
  // value go back to the settled one.
  virtual void revert() = 0;
};

template <typename G>
class StagedGeometry final : public StagedGeometryBase {
 public:
  explicit StagedGeometry(const G &initial = G())
      : requested_(initial), configuring_(initial), active_(initial), settled_(initial) {}

  // set_property: returns true when the caps must be renegotiated.
  bool request(const G &g) {
    requested_ = g;
    return !(requested_ == active_);
  }
  const G &requested() const { return requested_; }

  // Around a negotiation. Brackets may nest (and come from two threads: a
  // caps query from the application while the streaming thread negotiates):
  // the outermost one freezes the request.
  void begin_negotiation() {
    if (frozen_++ == 0) configuring_ = requested_;
  }
  void end_negotiation() {
    if (frozen_ > 0) --frozen_;
  }
  void freeze(bool frozen) override {
    if (frozen)
      begin_negotiation();
    else
      end_negotiation();
  }

  // transform_caps: the value to negotiate with.
  const G &negotiating() const { return frozen_ ? configuring_ : requested_; }

  // set_info: the negotiated caps belong to negotiating()'s value.
  const G &commit() {
    active_ = negotiating();
    return active_;
  }
  const G &active() const { return active_; }

  // A request whose output caps equal the negotiated ones becomes active at
  // once (GstBaseTransform calls set_caps only when the caps change).
  void activate(const G &g) { active_ = g; }

  bool pending() const override { return !(requested_ == active_); }

  void settle() override { settled_ = active_; }
  void revert() override { requested_ = configuring_ = active_ = settled_; }

 private:
  G requested_, configuring_, active_, settled_;
  int frozen_ = 0;  // nesting depth of the negotiation brackets
};

}  // namespace p3d::gst
