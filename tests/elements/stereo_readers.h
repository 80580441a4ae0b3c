// What each reader makes of an MP4 or Matroska file's stereo signalling:
// GStreamer (in process: qtdemux/matroskademux ! h264parse, decodebin),
// ffprobe/ffmpeg and mkvinfo (as programs; tests skip where they are missing).
#pragma once

#include <map>
#include <string>
#include <vector>

namespace p3d::test {

// True when `name` is found in PATH.
bool have_program(const char *name);
// Runs argv (no shell; PATH searched) in folder `cwd` ("" for this
// process's) with the `env` entries ("NAME=value") added to this process's
// environment; returns the exit status, 128 + the signal that killed it, or
// -1 if it could not run (*err says why).
int run_program(const std::vector<std::string> &argv, std::string *out, std::string *err = nullptr,
                const std::string &cwd = "", const std::vector<std::string> &env = {});

// Caps after the demuxer (h264parse's sink) and after h264parse, where
// decodebin and playbin take the layout from. The demuxer follows the file
// name: qtdemux for .mp4/.mov, matroskademux otherwise.
struct GstStereo {
  std::string error;  // "" when the pipeline reached EOS
  std::string demux_mode;  // "" when the demuxer set no multiview-mode
  unsigned demux_flags = 0;
  std::string mode;
  unsigned flags = 0;  // GstVideoMultiviewFlags (0x1 right view first, 0x4000 half aspect)
  int par_n = 0, par_d = 0;
};
GstStereo gst_parsed_stereo(const std::string &file);
// Video frames decodebin delivers up to EOS; -1 with *error on failure.
// has_audio: the file has an audio track too (it needs a sink as well).
int gst_decoded_frames(const std::string &file, bool has_audio, std::string *error);

// ffprobe's first video stream: sample_aspect_ratio, the stereo_mode tag
// (Matroska) and the type of the stream's Stereo 3D side data (MP4's st3d
// box: "side by side", "top and bottom"), "" when absent. ok is false when
// ffprobe failed.
struct FfprobeVideo {
  bool ok = false;
  std::string sar;
  std::string stereo_mode;
  std::string stereo_side_data;
};
FfprobeVideo ffprobe_video(const std::string &file);
// Every AVStereo3D side data of the first decoded frame as ffmpeg's
// showinfo prints it ("side by side (inverted)"...): the container's first,
// then the H.264 SEI's.
std::vector<std::string> ffmpeg_frame_stereo(const std::string &file);
// mkvinfo --all: "Stereo mode", "Display width", "Display height",
// "Display unit", "Pixel width", "Pixel height" of the first video track,
// value text as printed ("11 (side by side (right first))").
std::map<std::string, std::string> mkvinfo_video(const std::string &file);

}  // namespace p3d::test
