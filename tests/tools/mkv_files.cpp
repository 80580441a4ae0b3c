#include "mkv_files.h"

#include <cstdio>
#include <fstream>
#include <iterator>

#include <glib/gstdio.h>

#include "ebml.h"
#include "element_helpers.h"

namespace p3d::test {

std::string make_stereo_mkv(const std::string &path, const StereoClip &clip) {
  char flags[32];
  std::snprintf(flags, sizeof flags, "0x%x", clip.flags);
  const std::string mux = std::string("matroskamux name=m") + (clip.streamable ? " streamable=true" : "") +
                          " ! filesink location=\"" + path + "\"";
  const std::string audio = "audiotestsrc num-buffers=" + std::to_string(clip.frames * 44100 / 30 / 1024 + 1) +
                            " ! audioconvert ! opusenc ! m. ";
  const std::string video = "videotestsrc num-buffers=" + std::to_string(clip.frames) +
                            " ! video/x-raw,format=I420,width=320,height=180,framerate=30/1"
                            " ! capssetter caps=\"video/x-raw,multiview-mode=" + clip.mode +
                            ",multiview-flags=(GstVideoMultiviewFlagsSet)" + flags +
                            ":0xffffffff,pixel-aspect-ratio=1/1\""
                            " ! x264enc frame-packing=auto speed-preset=ultrafast ! h264parse ! pseudo3dsignal ! m. ";
  // The muxer numbers its tracks in the order the pads are requested,
  // which is the order of the links here.
  return run_to_eos(mux + " " + (clip.audio_first ? audio + video : video));
}

std::string mkv_out_dir() {
  const std::string dir = output_dir() + "/mkvstereo";
  g_mkdir_with_parents(dir.c_str(), 0755);
  return dir;
}

Bytes read_bytes(const std::string &path) {
  std::ifstream f(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

bool write_bytes(const std::string &path, const Bytes &data) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char *>(data.data()), std::streamsize(data.size()));
  return bool(f);
}

std::vector<TopLevel> top_level_elements(const Bytes &file) {
  std::vector<TopLevel> out;
  ebml::Header h;
  if (!ebml::read_header(file.data(), file.size(), &h) || h.id != ebml::kIdEbml || h.size > file.size()) return out;
  size_t pos = size_t(h.header_len() + h.size);
  if (pos >= file.size() || !ebml::read_header(file.data() + pos, file.size() - pos, &h) || h.id != 0x18538067)
    return out;
  pos += size_t(h.header_len());
  while (pos < file.size() && ebml::read_header(file.data() + pos, file.size() - pos, &h)) {
    const bool unknown = h.size == ebml::kUnknownSize;
    out.push_back({h.id, pos, unknown ? UINT64_MAX : pos + h.header_len() + h.size});
    if (unknown || h.size > file.size()) break;
    pos += size_t(h.header_len() + h.size);
  }
  return out;
}

TopLevel tracks_element(const Bytes &file) {
  for (const TopLevel &t : top_level_elements(file))
    if (t.id == kIdTracks) return t;
  return {};
}

}  // namespace p3d::test
