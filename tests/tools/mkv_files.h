// Matroska files for the StereoMode editor's tests: encoded by GStreamer
// as the project writes them (x264enc frame-packing=auto ! h264parse !
// pseudo3dsignal ! matroskamux), and whole files as bytes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace p3d::test {

using Bytes = std::vector<uint8_t>;

struct StereoClip {
  std::string mode = "mono";  // GStreamer multiview-mode of the encoded frames
  unsigned flags = 0;         // GstVideoMultiviewFlags (0x1 right view first, 0x4000 half aspect)
  int frames = 10;            // 320x180 at 30 fps
  bool audio_first = false;   // an Opus track, requested from the muxer before the video
  bool streamable = false;    // matroskamux streamable=true: no SeekHead, no Cues, unknown sizes
};
// Writes the clip to `path`; "" or the pipeline's error.
std::string make_stereo_mkv(const std::string &path, const StereoClip &clip);
// A folder under output_dir() for this suite's files.
std::string mkv_out_dir();

Bytes read_bytes(const std::string &path);
bool write_bytes(const std::string &path, const Bytes &data);

// The Segment's children (SeekHead, Info, Tracks, Cluster...), walked from
// the EBML header; the walk stops at an unknown size or a bad header.
struct TopLevel {
  uint32_t id = 0;
  uint64_t begin = 0, end = 0;  // end: UINT64_MAX for an unknown size
};
std::vector<TopLevel> top_level_elements(const Bytes &file);
constexpr uint32_t kIdTracks = 0x1654AE6B;
constexpr uint32_t kIdSeekHead = 0x114D9B74;
// The Tracks element; begin == end == 0 if there is none.
TopLevel tracks_element(const Bytes &file);

}  // namespace p3d::test
