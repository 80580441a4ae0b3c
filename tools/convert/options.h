// Command line of pseudo3d-convert: what the user asked for, checked for
// form only (names, numbers, file kinds). Values of the plugin's own
// properties (layout, hypothesis...) are checked against the plugin in
// stage_settings.h once GStreamer is up.
#pragma once

#include <gst/gst.h>

#include <string>
#include <utility>
#include <vector>

namespace p3d::convert {

// What OUTPUT's extension asks for.
enum class OutputKind { Mp4, Mov, Mkv, Jpeg, Png, Mpo, Jps };

bool is_photo(OutputKind k);
// The kind for a file name by its extension (case-insensitive); false when
// the extension is not one the converter writes.
bool output_kind_of(const std::string &path, OutputKind *kind);

// A photo converted into a video file becomes a still video: this long
// unless --duration says otherwise, at this frame rate (a lone frame of no
// duration is played as nothing).
constexpr GstClockTime kStillDuration = 5 * GST_SECOND;
constexpr int kStillFrameRate = 25;

enum class Processing { Auto, Cpu, Gpu };
// Auto: H.265 for video of more than 8 bits a sample, H.264 otherwise
// (settle_codec, encoder.h).
enum class Codec { Auto, H264, H265 };

struct Options {
  std::string input, output;
  // Plugin properties given on the command line, by property name (the
  // option without its dashes), in command-line order: layout, glasses,
  // anaglyph-method, swap-eyes, max-disparity, convergence, hypothesis.
  std::vector<std::pair<std::string, std::string>> stage_values;
  Codec codec = Codec::Auto;
  int crf = -1;         // -1: the codec's default (encoder.h)
  std::string preset;   // empty: the encoder's default
  GstClockTime start = GST_CLOCK_TIME_NONE;
  GstClockTime duration = GST_CLOCK_TIME_NONE;
  Processing processing = Processing::Auto;
  bool quiet = false;
  bool force = false;
  std::string depth_out;  // photos: 16-bit grey PNG of the depth used
  // --depth FILE: the depth comes from this picture or video (depth_source.h)
  // instead of being estimated; depth_values: pseudo3ddepthmux's
  // convention, near and far from --depth-convention, --depth-near and
  // --depth-far, by property name, in command-line order.
  std::string depth;
  std::vector<std::pair<std::string, std::string>> depth_values;
  // --benchmark INPUT: decode-only against convert-to-fakesink (benchmark.h).
  bool benchmark = false;
  std::string benchmark_out;
  int benchmark_runs = 2;
  OutputKind kind = OutputKind::Mp4;

  // The value given for a plugin property, or `fallback`.
  std::string stage_value(const std::string &name, const std::string &fallback) const;
  bool has_stage_value(const std::string &name) const;
};

// Outcome of parsing: run, print help/version and leave with 0, or leave
// with the usage-error status after printing `error` (one line).
enum class ParseResult { Run, ExitOk, ExitUsage };

ParseResult parse_args(int argc, char **argv, Options *o, std::string *error);
void print_usage(FILE *f);

// Whether a --depth file is a still picture, by its extension (.png, .jpg,
// .jpeg, .tif, .tiff, .pgm, .bmp); anything else is taken as a video.
bool is_still_picture_name(const std::string &path);

// "90", "1:30", "01:02:03.5" -> nanoseconds; false if malformed.
bool parse_time(const std::string &s, GstClockTime *t);

// Whether s is a plain decimal number: digits with at most one '.', a
// leading '-' where allow_sign. strtod and GStreamer's deserialisers also
// take "", hex, exponents, "inf" and "nan", which no user means here.
bool is_plain_decimal(const std::string &s, bool allow_sign);

}  // namespace p3d::convert
