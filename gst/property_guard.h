// Properties documented as settable only in NULL or READY
// (GST_PARAM_MUTABLE_READY: processing, cuda-device-id) are refused while the
// element is PAUSED or PLAYING, with a warning message on the bus, rather
// than half-applied to a running stream.
#pragma once

#include <gst/gst.h>

namespace p3d::gst {

// True when `pspec` may be set on `element` now; otherwise posts the warning
// and returns false (the caller leaves the value unchanged).
inline bool property_settable(GstElement *element, GParamSpec *pspec) {
  if (!(pspec->flags & GST_PARAM_MUTABLE_READY)) return true;
  GST_OBJECT_LOCK(element);
  const bool running = GST_STATE(element) > GST_STATE_READY || GST_STATE_NEXT(element) > GST_STATE_READY;
  GST_OBJECT_UNLOCK(element);
  if (!running) return true;
  GST_ELEMENT_WARNING(element, CORE, STATE_CHANGE,
                      ("Property '%s' cannot be changed while the element is paused or playing", pspec->name),
                      ("set it in the NULL or READY state; the value stays as it was"));
  return false;
}

}  // namespace p3d::gst
