// What the converter learns of an input file before it builds its
// pipeline, from its parsed streams (filesrc ! parsebin: nothing is
// decoded, so a damaged or huge picture costs nothing here and prints
// nothing; the conversion reports it).
#pragma once

#include <string>

namespace p3d::convert {

// Bits a sample of the file's first video stream: the bit-depth-luma its
// parser states (h264parse, h265parse, vp9parse, av1parse), else the
// depth of a raw stream's format. 0 where it cannot be known: not a
// regular file (a FIFO or a device is read once, by the conversion), no
// video stream, no parser for it, or no video pad within 10 s.
int video_sample_bits(const std::string &path);

}  // namespace p3d::convert
