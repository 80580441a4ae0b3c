// Audio and subtitle streams of a video conversion: copied as they are when
// the output container takes their codec (decodebin stops before the
// decoder), re-encoded otherwise (AAC; Opus/Vorbis where no AAC encoder is
// installed), dropped with a note when the container has no place for them.
// Every branch starts with an unbounded queue: the video branch holds
// seconds of frames (decoder, 3D stages, encoder look-ahead) before the
// muxer sees any, and a bounded queue on the other streams would fill and
// stall the demuxer that the video waits on (a deadlock).
#pragma once

#include <gst/gst.h>

#include <string>

#include "options.h"

namespace p3d::convert {

enum class StreamAction { Copy, Encode, Text, Drop };

struct StreamRoute {
  StreamAction action = StreamAction::Drop;
  const char *parser = nullptr;  // Copy: the parser that frames the stream for the muxer
  const char *mux_pad = nullptr;  // "audio_%u" or "subtitle_%u"
  std::string why;                // Drop: the reason, for the note
};

// decodebin's autoplug-continue: false (stop here, expose the stream
// encoded) for audio or subtitle caps the container takes as they are.
bool keep_encoded(const GstCaps *caps, OutputKind kind);

// What to do with a non-video stream decodebin exposed with `caps`.
StreamRoute route_stream(const GstCaps *caps, OutputKind kind);

// Builds and links the branch from `pad` (decodebin's) to a new request pad
// of `mux`, inside `bin`. Returns the branch's first sink pad (new ref; the
// caller may probe it) or null with *error.
GstPad *link_stream_branch(GstElement *bin, GstPad *pad, const GstCaps *caps, const StreamRoute &route,
                           OutputKind kind, GstElement *mux, std::string *error);

// A branch that swallows a stream the output does not take.
bool link_to_fakesink(GstElement *bin, GstPad *pad);

// A queue that never blocks its upstream (no limits).
GstElement *make_unbounded_queue();

}  // namespace p3d::convert
