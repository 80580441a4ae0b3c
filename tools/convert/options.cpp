#include "options.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>

#include "config.h"
#include "depth_estimate.h"
#include "pack.h"

namespace p3d::convert {

namespace {

struct ExtensionKind {
  const char *ext;
  OutputKind kind;
};
const ExtensionKind kExtensions[] = {
    {".mp4", OutputKind::Mp4}, {".m4v", OutputKind::Mp4}, {".mov", OutputKind::Mov},  {".mkv", OutputKind::Mkv},
    {".jpg", OutputKind::Jpeg}, {".jpeg", OutputKind::Jpeg}, {".png", OutputKind::Png}, {".mpo", OutputKind::Mpo},
    {".jps", OutputKind::Jps},
};

// Options that set a plugin property of the same name, and whether they
// take a value (swap-eyes is a flag).
struct StageOption {
  const char *name;
  bool takes_value;
};
const StageOption kStageOptions[] = {
    {"layout", true},        {"glasses", true},     {"anaglyph-method", true}, {"swap-eyes", false},
    {"max-disparity", true}, {"convergence", true}, {"hypothesis", true},    {"crop-bars", true},
};

// x264/x265 preset names, fastest first; the NVENC encoders get theirs
// mapped from them (encoder.cpp).
const char *const kPresets[] = {"ultrafast", "superfast", "veryfast", "faster", "fast",
                                "medium",    "slow",      "slower",   "veryslow", "placebo"};

bool known_preset(const std::string &p) {
  return std::any_of(std::begin(kPresets), std::end(kPresets), [&](const char *n) { return p == n; });
}

std::string preset_names() {
  std::string s;
  for (const char *n : kPresets) s += std::string(s.empty() ? "" : ", ") + n;
  return s;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

bool parse_int(const std::string &s, int lo, int hi, int *v) {
  if (!is_plain_decimal(s, lo < 0) || s.find('.') != std::string::npos || s.size() > 9) return false;
  const long x = std::strtol(s.c_str(), nullptr, 10);
  if (x < lo || x > hi) return false;
  *v = static_cast<int>(x);
  return true;
}

bool ends_with(const std::string &s, const char *suffix) {
  const size_t n = std::strlen(suffix);
  return s.size() >= n && lower(s.substr(s.size() - n)) == suffix;
}

}  // namespace

bool is_still_picture_name(const std::string &path) {
  for (const char *e : {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".pgm", ".bmp"})
    if (ends_with(path, e)) return true;
  return false;
}

bool is_photo(OutputKind k) {
  return k == OutputKind::Jpeg || k == OutputKind::Png || k == OutputKind::Mpo || k == OutputKind::Jps;
}

bool output_kind_of(const std::string &path, OutputKind *kind) {
  for (const ExtensionKind &e : kExtensions)
    if (ends_with(path, e.ext)) {
      *kind = e.kind;
      return true;
    }
  return false;
}

std::string Options::stage_value(const std::string &name, const std::string &fallback) const {
  std::string v = fallback;
  for (const auto &kv : stage_values)
    if (kv.first == name) v = kv.second;  // the last one given wins
  return v;
}

bool Options::has_stage_value(const std::string &name) const {
  return std::any_of(stage_values.begin(), stage_values.end(), [&](const auto &kv) { return kv.first == name; });
}

bool is_plain_decimal(const std::string &s, bool allow_sign) {
  size_t i = allow_sign && !s.empty() && s[0] == '-' ? 1 : 0;
  int digits = 0, dots = 0;
  for (; i < s.size(); ++i) {
    if (std::isdigit(static_cast<unsigned char>(s[i])))
      ++digits;
    else if (s[i] == '.')
      ++dots;
    else
      return false;
  }
  return digits > 0 && dots <= 1;
}

bool parse_time(const std::string &s, GstClockTime *t) {
  // Up to three ':'-separated fields, the last one may have a fraction;
  // minutes and seconds after a ':' stay below 60.
  double total = 0;
  size_t pos = 0;
  int fields = 0;
  while (true) {
    const size_t colon = s.find(':', pos);
    const std::string part = s.substr(pos, colon == std::string::npos ? std::string::npos : colon - pos);
    const bool last = colon == std::string::npos;
    if (!is_plain_decimal(part, false) || (!last && part.find('.') != std::string::npos)) return false;
    const double v = std::strtod(part.c_str(), nullptr);
    if (!std::isfinite(v) || (fields > 0 && v >= 60)) return false;
    total = total * 60 + v;
    if (++fields > 3) return false;
    if (last) break;
    pos = colon + 1;
  }
  // Up to a year: beyond it llround() leaves the range of a clock time.
  if (total > 366.0 * 24 * 3600) return false;
  *t = static_cast<GstClockTime>(std::llround(total * GST_SECOND));
  return true;
}

void print_usage(FILE *f) {
  std::fprintf(
      f,
      "usage: pseudo3d-convert INPUT OUTPUT [options]\n"
      "       pseudo3d-convert [options] -- INPUT OUTPUT\n"
      "       pseudo3d-convert --benchmark INPUT [--benchmark-out FILE.jsonl] [options]\n"
      "Converts a 2D video or photo into stereo 3D. OUTPUT's extension picks the result:\n"
      "  .mp4 .m4v .mov .mkv  video (H.264/H.265), audio and subtitles kept, 3D layout signalled\n"
      "  .jpg .png            the packed stereo picture (EXIF orientation applied, EXIF kept in JPEG)\n"
      "  .mpo                 two-image MPO (left, right) for 3D cameras, TVs and viewers\n"
      "  .jps                 cross-eyed side-by-side JPEG (right view on the left)\n"
      "3D options (the plugin's properties; see docs/elements.md):\n"
      "  --layout L            %s\n"
      "                        (default: side-by-side-half for video, side-by-side for photos)\n"
      "  --glasses G           %s (anaglyph)\n"
      "  --anaglyph-method M   %s\n"
      "  --swap-eyes           right view first\n"
      "  --max-disparity P     parallax in percent of the width (default 3)\n"
      "  --convergence C       depth on the screen plane, 0 (far) to 1 (near) (default 0.5)\n"
      "  --hypothesis H        %s\n"
      "  --crop-bars auto|off  leave letterbox and pillarbox bars out of the 3D, black and flat\n"
      "                        in both views (default auto)\n"
      "Video options:\n"
      "  --codec auto|h264|h265  (default auto: H.265 for video of more than 8 bits a sample,\n"
      "                        keeping its 10 bits, where an H.265 encoder is installed; else H.264)\n"
      "  --crf N               constant quality, lower is better (default 20 for H.264, 24 for H.265)\n"
      "  --preset P            ultrafast ... veryslow (default: medium)\n"
      "  --start T --duration T   convert a piece only (seconds or [HH:]MM:SS[.frac])\n"
      "  A photo into a video file becomes a still video of %d s at %d frames/s (--duration sets the length)\n"
      "General:\n"
      "  --processing auto|cpu|gpu   where the 3D conversion runs (default auto: GPU when usable)\n"
      "  --depth FILE          take the depth from FILE (a picture, or a video of the same length)\n"
      "                        instead of estimating it: 8- or 16-bit grey, any size\n"
      "  --depth-convention C  near-white (default), near-dark, or metric (distances, with\n"
      "  --depth-near N --depth-far N   the nearest and farthest distance in FILE's unit)\n"
      "  --depth-out FILE.png  photos: also write the depth map used (16-bit grey, white = near)\n"
      "  --force               overwrite OUTPUT if it exists\n"
      "  --quiet               no progress\n"
      "  --benchmark           time decoding alone against decoding and converting (encoder\n"
      "                        replaced by fakesink); --benchmark-out FILE appends JSON lines,\n"
      "                        --benchmark-runs N (default 2) repeats both\n"
      "  --help, --version\n"
      "  --                    ends the options: what follows are file names, even ones starting with '-'\n",
      enum_nicks(kPackLayoutNames).c_str(), enum_nicks(kGlassesNames).c_str(),
      enum_nicks(kAnaglyphMethodNames).c_str(), enum_nicks(kHypothesisNames).c_str(),
      static_cast<int>(kStillDuration / GST_SECOND), kStillFrameRate);
}

ParseResult parse_args(int argc, char **argv, Options *o, std::string *error) {
  std::vector<std::string> positional;
  bool video_option_given = false;
  std::string video_option;
  bool options_ended = false;
  for (int i = 1; i < argc; ++i) {
    // `--` ends the options, as for every POSIX tool: a file whose name
    // starts with '-' can then be given.
    if (options_ended) {
      positional.push_back(argv[i]);
      continue;
    }
    if (std::strcmp(argv[i], "--") == 0) {
      options_ended = true;
      continue;
    }
    std::string arg = argv[i], value;
    bool has_inline_value = false;
    if (arg.rfind("--", 0) == 0) {
      const size_t eq = arg.find('=');
      if (eq != std::string::npos) {
        value = arg.substr(eq + 1);
        arg = arg.substr(0, eq);
        has_inline_value = true;
      }
    }
    // The option's value: inline (--opt=v) or the next argument.
    auto take_value = [&](std::string *v) {
      if (has_inline_value) {
        *v = value;
        return true;
      }
      if (i + 1 >= argc) {
        *error = "option " + arg + " needs a value";
        return false;
      }
      *v = argv[++i];
      return true;
    };
    if (arg == "-h" || arg == "--help") {
      print_usage(stdout);
      return ParseResult::ExitOk;
    }
    if (arg == "--version") {
      std::printf("pseudo3d-convert %s\n", VERSION);
      return ParseResult::ExitOk;
    }
    if (arg.rfind("--", 0) == 0) {
      const std::string name = arg.substr(2);
      const StageOption *stage = nullptr;
      for (const StageOption &s : kStageOptions)
        if (name == s.name) stage = &s;
      std::string v;
      if (stage) {
        if (!stage->takes_value) {
          if (has_inline_value) {
            *error = "option " + arg + " takes no value";
            return ParseResult::ExitUsage;
          }
          v = "true";
        } else if (!take_value(&v)) {
          return ParseResult::ExitUsage;
        }
        o->stage_values.emplace_back(name, v);
        continue;
      }
      if (name == "quiet" || name == "force" || name == "benchmark") {
        if (has_inline_value) {
          *error = "option " + arg + " takes no value";
          return ParseResult::ExitUsage;
        }
        (name == "quiet" ? o->quiet : name == "force" ? o->force : o->benchmark) = true;
        continue;
      }
      if (name != "codec" && name != "crf" && name != "preset" && name != "start" && name != "duration" &&
          name != "processing" && name != "depth-out" && name != "benchmark-out" && name != "benchmark-runs" &&
          name != "depth" && name != "depth-convention" && name != "depth-near" && name != "depth-far") {
        *error = "unknown option '" + arg + "' (see --help)";
        return ParseResult::ExitUsage;
      }
      if (!take_value(&v)) return ParseResult::ExitUsage;
      bool ok = true;
      if (name == "codec") {
        ok = v == "auto" || v == "h264" || v == "h265";
        o->codec = v == "h265" ? Codec::H265 : v == "h264" ? Codec::H264 : Codec::Auto;
      } else if (name == "crf") {
        ok = parse_int(v, 0, 51, &o->crf);
      } else if (name == "preset") {
        ok = known_preset(v);
        o->preset = v;
      } else if (name == "start") {
        ok = parse_time(v, &o->start);
      } else if (name == "duration") {
        ok = parse_time(v, &o->duration) && o->duration > 0;
      } else if (name == "processing") {
        ok = v == "auto" || v == "cpu" || v == "gpu";
        o->processing = v == "cpu" ? Processing::Cpu : v == "gpu" ? Processing::Gpu : Processing::Auto;
      } else if (name == "depth-out") {
        ok = ends_with(v, ".png");
        o->depth_out = v;
      } else if (name == "depth") {
        ok = !v.empty();
        o->depth = v;
      } else if (name.rfind("depth-", 0) == 0) {  // checked against pseudo3ddepthmux later
        o->depth_values.emplace_back(name.substr(6), v);
      } else if (name == "benchmark-out") {
        o->benchmark_out = v;
      } else if (name == "benchmark-runs") {
        ok = parse_int(v, 1, 100, &o->benchmark_runs);
      }
      if (!ok) {
        *error = "invalid value '" + v + "' for " + arg;
        if (name == "preset") *error += " (" + preset_names() + ")";
        return ParseResult::ExitUsage;
      }
      if (name == "codec" || name == "crf" || name == "preset" || name == "start" || name == "duration") {
        video_option_given = true;
        video_option = arg;
      }
      continue;
    }
    if (arg == "-q") {
      o->quiet = true;
      continue;
    }
    if (arg == "-f") {
      o->force = true;
      continue;
    }
    if (arg.size() > 1 && arg[0] == '-') {
      *error = "unknown option '" + arg + "' (see --help)";
      return ParseResult::ExitUsage;
    }
    positional.push_back(arg);
  }

  const size_t wanted = o->benchmark ? 1 : 2;
  if (positional.size() != wanted) {
    *error = o->benchmark ? "--benchmark takes one INPUT (see --help)" : "expected INPUT and OUTPUT (see --help)";
    return ParseResult::ExitUsage;
  }
  o->input = positional[0];
  if (!o->depth_values.empty() && o->depth.empty()) {
    *error = "--depth-" + o->depth_values[0].first + " applies with --depth FILE only";
    return ParseResult::ExitUsage;
  }
  for (const char *estimated : {"hypothesis", "crop-bars"})
    if (!o->depth.empty() && o->has_stage_value(estimated)) {
      *error = std::string("--") + estimated + " does not apply with --depth (the depth comes from " + o->depth + ")";
      return ParseResult::ExitUsage;
    }
  if (o->benchmark) {
    if (!o->depth.empty()) {
      *error = "--depth does not apply to --benchmark";
      return ParseResult::ExitUsage;
    }
    return ParseResult::Run;
  }
  o->output = positional[1];
  if (!output_kind_of(o->output, &o->kind)) {
    const size_t dot = o->output.find_last_of("./");
    const std::string ext = dot != std::string::npos && o->output[dot] == '.' ? o->output.substr(dot) : "";
    *error = o->output + ": unknown output type '" + ext + "' (use .mp4, .m4v, .mov, .mkv, .jpg, .png, .mpo or .jps)";
    return ParseResult::ExitUsage;
  }
  if (is_photo(o->kind) && video_option_given) {
    *error = video_option + " applies to video outputs, not to " + o->output;
    return ParseResult::ExitUsage;
  }
  if (!o->depth.empty() && !is_still_picture_name(o->depth) && GST_CLOCK_TIME_IS_VALID(o->start)) {
    *error = "--start with a depth video is not supported (the depth video would play from its beginning): "
             "cut the video and its depth to the piece first";
    return ParseResult::ExitUsage;
  }
  if (!is_photo(o->kind) && !o->depth_out.empty()) {
    *error = "--depth-out applies to photo outputs, not to " + o->output;
    return ParseResult::ExitUsage;
  }
  if ((o->kind == OutputKind::Mpo || o->kind == OutputKind::Jps) && o->has_stage_value("layout")) {
    *error = "--layout does not apply to " + o->output + " (MPO holds two views, JPS is always side by side)";
    return ParseResult::ExitUsage;
  }
  if (o->crf > 50 && o->codec == Codec::H264) {
    *error = "invalid value '" + std::to_string(o->crf) + "' for --crf (0 to 50 for H.264)";
    return ParseResult::ExitUsage;
  }
  return ParseResult::Run;
}

}  // namespace p3d::convert
