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
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <new>
#include <string>

#include "benchmark.h"
#include "convert_photo.h"
#include "convert_video.h"
#include "jpeg_meta.h"
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

// A JPEG cut short decodes without a word (jpegdec ends the data itself
// and leaves the missing rows grey): refused before any output is begun,
// for photo and video outputs alike. Regular files only: reading a FIFO
// here would take the data meant for the pipeline.
bool input_complete(const std::string &path, std::string *error) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return true;
  std::ifstream f(path, std::ios::binary);
  char soi[3] = {};
  if (!f.read(soi, 3) || soi[0] != '\xFF' || soi[1] != '\xD8' || soi[2] != '\xFF') return true;  // no JPEG
  f.seekg(0);
  const p3d::convert::Bytes bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (p3d::convert::jpeg_complete(bytes)) return true;
  *error = path + ": the JPEG data end before the picture does (a truncated or damaged file)";
  return false;
}

// Whether two paths name one file: the same inode where both exist, else
// the same canonical folder and name (an output not written yet).
bool same_file(const std::string &a, const std::string &b) {
  struct stat sa, sb;
  const bool ea = stat(a.c_str(), &sa) == 0, eb = stat(b.c_str(), &sb) == 0;
  if (ea && eb) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  if (ea != eb) return false;
  auto canonical = [](const std::string &p) {
    const size_t slash = p.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "." : slash == 0 ? "/" : p.substr(0, slash);
    char *real = realpath(dir.c_str(), nullptr);
    const std::string r = real ? std::string(real) + "/" + p.substr(slash == std::string::npos ? 0 : slash + 1) : p;
    std::free(real);
    return r;
  };
  return canonical(a) == canonical(b);
}

// OUTPUT and --depth-out may be neither the input nor each other: --force
// would otherwise replace the film or photo being converted.
bool distinct_files(const p3d::convert::Options &o, std::string *error) {
  if (same_file(o.input, o.output)) {
    *error = o.output + ": is the input too; choose another name";
    return false;
  }
  if (o.depth_out.empty()) return true;
  if (same_file(o.input, o.depth_out)) {
    *error = o.depth_out + ": --depth-out is the input too; choose another name";
    return false;
  }
  if (same_file(o.output, o.depth_out)) {
    *error = o.depth_out + ": --depth-out is OUTPUT too; choose another name";
    return false;
  }
  return true;
}

// Everything after gst_init(): the plugin, the stage values, then the
// conversion. Returns the exit status.
int run(const p3d::convert::Options &o) {
  using namespace p3d::convert;
  std::string error;
  if (!ensure_plugin(&error)) return fail(error, 1);
  if (!check_stage_values(o, &error)) return fail(error, 2);

  bool ok;
  // A picture within the size limit can still exceed the memory there is;
  // the converter's own buffers then end the run with a line, not an abort.
  try {
    if (o.benchmark)
      ok = run_benchmark(o, &error);
    else if (is_photo(o.kind))
      ok = convert_photo(o, &error);
    else
      ok = convert_video(o, &error);
  } catch (const std::bad_alloc &) {
    ok = false;
    error = o.input + ": out of memory";
  }
  return ok ? 0 : fail(error, 1);
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
  if (!input_readable(o.input, &error) || !input_complete(o.input, &error)) return fail(error, 1);
  if (!o.benchmark && !distinct_files(o, &error)) return fail(error, 2);
  // Progress and messages go to stderr; a reader that goes away (a pipe
  // into `head`) must not kill the conversion and leave its temporary file.
  std::signal(SIGPIPE, SIG_IGN);
  install_interrupt_cleanup();

  gst_init(&argc, &argv);
  const int status = run(o);
  // Every way out after gst_init() passes here, with every pipeline and
  // element released: GStreamer is deinitialised, so that its leaks tracer
  // (GST_TRACERS=leaks) checks what is still alive and reports it.
  gst_deinit();
  return status;
}
