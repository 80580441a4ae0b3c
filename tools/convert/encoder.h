// The video encoder: which one (x264/x265 on the CPU, NVENC when the GPU
// path runs and the machine has it), the raw format it is fed, and the
// quality flags mapped onto its properties.
#pragma once

#include <gst/gst.h>

#include <string>

#include "options.h"

namespace p3d::convert {

struct EncoderChoice {
  std::string factory;     // x264enc, x265enc, nvh264enc, nvh265enc
  std::string parser;      // h264parse, h265parse
  std::string raw_format;  // what the encoder is fed: I420, or Y444 for anaglyphs
  // What it is fed for input of more than 8 bits a sample, where the
  // output keeps them: I420_10LE (Y444_10LE for anaglyphs) for x265enc's
  // Main10, P010_10LE for NVENC's; empty where the output has 8 bits
  // (H.264).
  std::string deep_format;
  // Where deep_format is empty: what keeps 10 bits instead (for the note).
  std::string deep_hint;
  // Whether the encoder writes the frame-packing SEI that carries the stereo
  // layout in the stream (only x264 does; pseudo3dsignal sets its eye order).
  bool writes_stereo_sei = false;
};

// Settles --codec auto for the input: H.265 where the input's video has
// more than 8 bits a sample (input_bits: probe_input, input_probe.h) and
// an H.265 encoder for the processing is installed, so that 10-bit and
// HDR films keep their 10 bits (Main 10); H.264 otherwise. False with
// *error when it chose H.264 and --crf is out of H.264's range.
bool settle_codec(Options *o, Processing processing, int input_bits, std::string *error);

// Picks the encoder for the codec (settled), the processing in use and the layout.
// False with *error when no encoder for the codec is installed.
bool choose_encoder(const Options &o, Processing processing, const std::string &layout, EncoderChoice *choice,
                    std::string *error);

// The encoder element with quality (--crf: constant-quality mode), speed
// (--preset) and threads (all cores) set.
GstElement *make_encoder(const EncoderChoice &choice, const Options &o);

// What the output loses of the decoded video's colour signal with this
// encoder, as a note for the user; empty when nothing is lost. Deeper
// input than 8 bits keeps its depth where the choice has a deep_format
// and loses its low bits elsewhere; only x265enc and nvh265enc write the
// mastering-display and light-level
// metadata of HDR10 (the transfer, primaries and matrix every encoder
// writes from the caps).
std::string colour_loss(const GstCaps *decoded, const EncoderChoice &choice);

// Whether decoded caps have more than 8 bits a sample.
bool has_deep_samples(const GstCaps *decoded);

// Default constant quality per codec: about the same visual quality.
int default_crf(Codec codec);

// Whether a layout packs two views into the frame (the rest are 2D
// pictures: an anaglyph or one view).
bool is_stereo_layout(const std::string &layout);

}  // namespace p3d::convert
