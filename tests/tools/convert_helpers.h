// Helpers of the pseudo3d-convert tests: running the program, making small
// input clips, and reading files back the way players do (GStreamer in
// process: demuxer ! parser caps; ffprobe/ffmpeg when installed; MPO's MPF
// index parsed here, independently of the converter's writer).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace p3d::test {

struct ToolRun {
  int status = -1;  // exit status, 128 + signal, -1 when it did not start
  std::string out, err;
};
// Runs pseudo3d-convert with `args` and waits for it.
ToolRun run_convert(const std::vector<std::string> &args);
// The same in folder `cwd` ("" for this process's), with the `env` entries
// ("NAME=value") added to this process's environment.
ToolRun run_convert_in(const std::string &cwd, const std::vector<std::string> &args,
                       const std::vector<std::string> &env = {});
std::string convert_program();

// A launch line to EOS into `path` (run_to_eos with a timeout); "" on success.
std::string make_clip(const std::string &launch);

// What GStreamer reads back from an MP4/MKV file.
struct ReadBack {
  std::string video_caps;  // after h264parse/h265parse (the caps decodebin builds on)
  std::string multiview_mode;
  unsigned multiview_flags = 0;
  int width = 0, height = 0;
  int video_frames = 0;
  double video_start = -1, video_end = -1;  // seconds (first PTS, last PTS + duration)
  std::string audio_caps;
  int audio_buffers = 0;
  double audio_start = -1, audio_end = -1;
  uint64_t audio_checksum = 0;  // over the packets (header packets left out)
  std::string error;
};
ReadBack read_back(const std::string &path);

// "key=value" lines of `ffprobe -show_entries stream=...` for stream
// `selector` ("v:0", "a:0").
std::string ffprobe_stream(const std::string &path, const std::string &selector, const std::string &entries);
// The value of `key` in ffprobe's key=value output (first match).
std::string ffprobe_value(const std::string &text, const std::string &key);

std::vector<uint8_t> read_bytes(const std::string &path);

// The MP Index of an MPO file (CIPA DC-007), read from the first image's
// APP2 "MPF" segment.
struct MpoEntry {
  uint32_t attribute = 0, size = 0, offset = 0;  // offset from the MP header (0 for the first image)
  size_t file_offset = 0;                          // where the image starts in the file
};
struct MpoIndex {
  bool found = false;
  uint32_t number_of_images = 0;
  std::vector<MpoEntry> entries;
  std::string error;
};
MpoIndex parse_mpo(const std::vector<uint8_t> &file);

// The EXIF Orientation (0 if none) and whether `marker` appears in the
// APP1 EXIF segment of a JPEG file.
int jpeg_exif_orientation(const std::vector<uint8_t> &jpeg);
bool jpeg_exif_contains(const std::vector<uint8_t> &jpeg, const std::string &marker);
// `jpeg` with an APP1 EXIF segment (little-endian TIFF: Orientation and Make).
std::vector<uint8_t> add_exif(const std::vector<uint8_t> &jpeg, int orientation, const std::string &make);

// Files in `dir` whose name contains `part`.
std::vector<std::string> files_containing(const std::string &dir, const std::string &part);

}  // namespace p3d::test
