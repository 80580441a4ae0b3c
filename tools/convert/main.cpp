// pseudo3d-convert: a movie or a photo to 3D in one command.
//
//   pseudo3d-convert INPUT OUTPUT [options]      (see --help)
//
// Video goes through decodebin, pseudo3dconvert, an H.264/H.265 encoder,
// pseudo3dsignal and the muxer OUTPUT's extension names, audio and subtitles
// copied where the container takes them (convert_video.h); photos through
// the four stages one by one, written as a packed picture, MPO or JPS
// (convert_photo.h). Every failure ends with one line on stderr naming the
// file and a non-zero status: 2 for a usage error, 1 otherwise, 128 + signal
// when interrupted; no partial OUTPUT is left behind (output_file.h).
#include <sys/stat.h>
#include <unistd.h>

#include <gst/gst.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include "benchmark.h"
#include "convert_photo.h"
#include "convert_video.h"
#include "options.h"
#include "output_file.h"
#include "stage_settings.h"

namespace {

int fail(const std::string &error, int status) {
  std::fprintf(stderr, "pseudo3d-convert: %s\n", error.c_str());
  return status;
}

// Before any pipeline exists, so the message names the file plainly.
bool input_readable(const std::string &path, std::string *error) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0) {
    *error = path + ": " + std::strerror(errno);
    return false;
  }
  if (S_ISDIR(st.st_mode)) {
    *error = path + ": is a folder, not a file";
    return false;
  }
  // access(), not open(): opening a FIFO for a moment would take the
  // writer's data meant for the pipeline.
  if (access(path.c_str(), R_OK) != 0) {
    *error = path + ": " + std::strerror(errno);
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char **argv) {
  using namespace p3d::convert;
  Options o;
  std::string error;
  switch (parse_args(argc, argv, &o, &error)) {
    case ParseResult::ExitOk: return 0;
    case ParseResult::ExitUsage: return fail(error, 2);
    case ParseResult::Run: break;
  }
  if (!input_readable(o.input, &error)) return fail(error, 1);
  if (!o.benchmark && o.input == o.output) return fail(o.output + ": is the input too; choose another name", 2);
  install_interrupt_cleanup();

  gst_init(&argc, &argv);
  if (!ensure_plugin(&error)) return fail(error, 1);
  if (!check_stage_values(o, &error)) return fail(error, 2);

  bool ok;
  if (o.benchmark)
    ok = run_benchmark(o, &error);
  else if (is_photo(o.kind))
    ok = convert_photo(o, &error);
  else
    ok = convert_video(o, &error);
  if (!ok) return fail(error, 1);
  return 0;
}
