// Small helpers for running GStreamer pipelines from the converter.
#pragma once

#include <gst/gst.h>

#include <functional>
#include <string>

namespace p3d::convert {

// The error message of an ERROR bus message as one line: the message, plus
// the flow reason ("not-negotiated"...) GStreamer keeps in the debug text.
std::string error_text(GstMessage *msg);

// The path of the element that posted `msg`
// ("/GstPipeline:p/GstDecodeBin:name/..."), "" if none.
std::string message_source_path(GstMessage *msg);

// Posts an error on `element`'s bus from any thread.
void post_error(GstElement *element, const std::string &text);

// Whether an element factory of this name is registered.
bool have_element(const char *factory);

// Whether `caps` give a width or height beyond the kMaxFrameSide pixels the
// 3D stages take (frame.h), with *message naming the size and the limit.
// Caps without a size pass. Checked on the caps decodebin sees before it
// plugs a decoder (typefind's, a parser's, a demuxer's), so a picture too
// large is refused before it is decoded, and an opaque "not-negotiated"
// after gigabytes of decoding becomes a line that says why.
bool too_large(const GstCaps *caps, std::string *message);

// Sets the pipeline to PLAYING and waits for EOS or an error (no main loop:
// for short pipelines). Returns false with *error.
bool run_until_eos(GstElement *pipeline, std::string *error);

// How a main-loop run ended.
struct LoopResult {
  bool ok = false;
  std::string error;           // the first error, one line
  bool from_filesink = false;  // the error concerns the output file
  std::string source;          // the path of the element that posted the error ("/pipeline/bin/element")
  std::string missing_plugin;  // decodebin's description of a missing decoder
};

// The application message a streaming thread posts when every input stream
// is linked (decodebin's no-more-pads); run_main_loop() then calls on_ready.
void post_ready(GstElement *pipeline);

// Runs `pipeline` in a GLib main loop until EOS or the first error.
// `on_ready` (main thread, may fail the run with *error) follows
// post_ready(); `tick` runs four times a second. The pipeline is left in
// NULL, so the files it wrote are closed.
LoopResult run_main_loop(GstElement *pipeline, const std::function<bool(std::string *)> &on_ready,
                         const std::function<void()> &tick);

}  // namespace p3d::convert
