// pseudo3d-mkvstereo: writes the stereo-3D layout into the container of a
// finished Matroska/WebM file (StereoMode, a display size GStreamer and
// ffmpeg read alike), in place, for players that ignore the H.264 frame-
// packing SEI. See tools/support/mkv_stereo.h.
#include <cstdio>
#include <cstring>
#include <string>

#include "mkv_stereo.h"

namespace {

void usage(FILE *f) {
  std::fprintf(f,
               "usage: pseudo3d-mkvstereo FILE.mkv LAYOUT [--right-first]\n"
               "  Writes StereoMode (plus DisplayWidth/DisplayHeight = the pixel size and DisplayUnit 4)\n"
               "  into the first video track of a finished Matroska/WebM file, in place; nothing else moves.\n"
               "  LAYOUT: mono, or a layout as pseudo3dpack names it: %s\n"
               "  (half layouts as the full ones, the anaglyph and single views as mono).\n"
               "  --right-first: the first view (left half, top half, first row/column/pixel) is the right eye.\n"
               "  Half or full views is not a Matroska property (players guess it from the aspect ratio),\n"
               "  so side-by-side and top-bottom cover both.\n"
               "  column-interleaved left-first writes no StereoMode: its value 9 is read by GStreamer as\n"
               "  side-by-side right-first; the H.264 SEI (pseudo3dsignal) carries the layout instead.\n",
               p3d::enum_nicks(p3d::kPackLayoutNames).c_str());
}

}  // namespace

int main(int argc, char **argv) {
  const char *positional[2] = {nullptr, nullptr};
  int count = 0;
  bool right_first = false;
  for (int i = 1; i < argc; ++i) {
    const char *a = argv[i];
    if (std::strcmp(a, "-h") == 0 || std::strcmp(a, "--help") == 0) {
      usage(stdout);
      return 0;
    }
    if (std::strcmp(a, "--right-first") == 0) {
      right_first = true;
    } else if (a[0] == '-' && a[1] != '\0') {
      std::fprintf(stderr, "pseudo3d-mkvstereo: unknown option '%s'\n", a);
      return 2;
    } else if (count < 2) {
      positional[count++] = a;
    } else {
      std::fprintf(stderr, "pseudo3d-mkvstereo: too many arguments (see --help)\n");
      return 2;
    }
  }
  if (count != 2) {
    usage(stderr);
    return 2;
  }
  p3d::MkvStereoLayout layout;
  if (!p3d::mkv_stereo_layout_from_name(positional[1], &layout)) {
    std::fprintf(stderr, "pseudo3d-mkvstereo: %s: unknown layout '%s' (see --help)\n", positional[0], positional[1]);
    return 2;
  }
  std::string error;
  if (!p3d::mkv_set_stereo_mode(positional[0], layout, right_first, &error)) {
    std::fprintf(stderr, "pseudo3d-mkvstereo: %s: %s\n", positional[0], error.c_str());
    return 1;
  }
  if (p3d::mkv_stereo_mode_written(layout, right_first))
    std::printf("%s: StereoMode %d\n", positional[0], p3d::mkv_stereo_mode_value(layout, right_first));
  else
    std::printf("%s: no StereoMode (GStreamer reads 9 as side-by-side right-first); the SEI carries the layout\n",
                positional[0]);
  return 0;
}
