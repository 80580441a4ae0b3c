// Depth from a file (--depth): a depth picture or a depth video, 8- or
// 16-bit grey in pseudo3ddepthmux's conventions (white = near by default),
// attached to each frame by pseudo3ddepthmux in place of pseudo3ddepth's
// estimate. The depth is resampled to the frame whatever its size, and a
// picture serves every frame (pseudo3ddepthmux keeps the last depth once
// its stream ended). The depth is read as it is stored: no rotation tag or
// EXIF orientation is applied to it, so it must match the picture as shown
// (upright).
#pragma once

#include <gst/gst.h>

#include <string>

#include "options.h"

namespace p3d::convert {

// The file decoded to grey, ending in `tail` (a launch-line fragment such
// as "m.depth", or "" to end at the queue):
//   filesrc name=depth_file ! decodebin name=depth_decoder ! videoconvert !
//   video/x-raw,format={ GRAY16_LE, GRAY8 } ! queue [! tail]
// Set the location with set_depth_location() after parsing. An error whose
// source path ("/GstPipeline:p/GstDecodeBin:depth_decoder/...") holds
// kDepthReaderMark came from this reader.
constexpr const char *kDepthReaderMark = ":depth_";
std::string depth_reader_description(const std::string &tail);
void set_depth_location(GstElement *pipeline, const std::string &path);

// o.depth is a file that can be read; else false with *error naming it.
bool depth_file_readable(const Options &o, std::string *error);

// Sets --depth-convention, --depth-near and --depth-far on a pseudo3ddepthmux.
void apply_depth_values(const Options &o, GstElement *mux);

// The video chain with the depth from o.depth, in place of pseudo3dconvert:
//   deinterlace ! [cudaupload ! CUDA memory !] pseudo3ddepthmux !
//   pseudo3dfilter ! pseudo3dwarp [! cudadownload]
// and the depth reader feeding the mux, as one bin with a "sink" and a
// "src" pad, the stages set from `o` (layout included) and to `processing`.
// Null with *error when an element is missing.
GstElement *make_depth_file_chain(const Options &o, Processing processing, std::string *error);

}  // namespace p3d::convert
