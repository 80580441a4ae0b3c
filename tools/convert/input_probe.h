// What the converter learns of an input file before it builds its
// pipeline, from its parsed streams (filesrc ! parsebin: nothing is
// decoded, so a damaged or huge picture costs nothing here and prints
// nothing; the conversion reports it).
#pragma once

#include <gst/gst.h>

#include <string>

namespace p3d::convert {

struct InputFacts {
  // Bits a sample of the first video stream: the bit-depth-luma its
  // parser states (h264parse, h265parse, vp9parse, av1parse), else the
  // depth of a raw stream's format; 0 where unknown.
  int bits = 0;
  // Whether that stream carries an orientation tag other than rotate-0
  // (phone video stored sideways).
  bool rotated = false;
};

// The facts of `path`'s first video stream, read up to its first parsed
// frame, an error or 10 s, whichever comes first (what was read by then
// is kept). Nothing is known (all 0) of what is not a regular file (a
// FIFO or a device is read once, by the conversion), or of a file with no
// video stream or no parser for it.
InputFacts probe_input(const std::string &path);

// Bits a sample that video caps state: a parser's bit-depth-luma, else the
// depth of a raw format; 0 when they do not say (also for null or empty
// caps). Parsed caps here, decoded caps for the encoder (encoder.h).
int caps_sample_bits(const GstCaps *caps);

// The orientation a tag list's GST_TAG_IMAGE_ORIENTATION asks for
// ("rotate-90", "flip-rotate-270", ...), empty for none ("rotate-0" or no
// such tag).
std::string tagged_rotation(const GstTagList *tags);

}  // namespace p3d::convert
