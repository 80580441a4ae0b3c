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
// Not thread-safe by itself: every call is made with the element's object
// lock held. G needs operator==.
#pragma once

namespace p3d::gst {

template <typename G>
class StagedGeometry {
 public:
  explicit StagedGeometry(const G &initial = G()) : requested_(initial), configuring_(initial), active_(initial) {}

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
  // GstPseudo3DBaseClass::freeze_geometry's bracket: begin (true) or end.
  void freeze(bool frozen) {
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

  // Before a frame: whether the request still differs from the active value.
  bool pending() const { return !(requested_ == active_); }

 private:
  G requested_, configuring_, active_;
  int frozen_ = 0;  // nesting depth of the negotiation brackets
};

}  // namespace p3d::gst
