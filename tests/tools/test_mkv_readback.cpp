// mkv_set_stereo_mode on files written as the project writes them
// (x264enc frame-packing=auto ! h264parse ! pseudo3dsignal ! matroskamux),
// read back by every reader: GStreamer (matroskademux ! h264parse, and
// decodebin to EOS), ffprobe (stream SAR and stereo_mode tag), ffmpeg
// (frame side data) and mkvinfo. Every file is made once and patched in a
// copy; each reader checks the unpatched original too, so that its checks
// are seen to be able to fail. Readers that are not installed skip.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include <gst/gst.h>

#include "mkv_files.h"
#include "stereo_readers.h"
#include "mkv_stereo.h"

namespace p3d::test {
namespace {

enum class Variant {
  Plain,
  AudioFirst,  // an Opus track before the video track
  Streamable,  // matroskamux streamable=true: no SeekHead, Segment of unknown size
  Mkvmerge,    // remuxed by mkvmerge: no room inside Tracks, a Void behind it
};

struct Case {
  const char *name;
  MkvStereoLayout layout;
  bool right_first;
  const char *gst_mode;  // multiview-mode to encode and to read back
  unsigned flags;        // encoded flags (half aspect where GStreamer guesses it too)
  int stereo_mode;       // Matroska StereoMode mkvinfo must show; -1: none written
  const char *ff_tag;    // ffprobe's stereo_mode tag; "" none
  const char *ff_frame;  // ffmpeg's frame side data; "" none
  Variant variant = Variant::Plain;
};

constexpr unsigned kRvf = 0x1, kHalf = 0x4000;
const Case kCases[] = {
    // StereoMode 0 gives ffmpeg a "2D" side data from the container, but no
    // stream tag; x264 writes no SEI for mono.
    {"mono", MkvStereoLayout::Mono, false, "mono", 0, 0, "", "2D"},
    {"sbs_lr", MkvStereoLayout::SideBySide, false, "side-by-side", kHalf, 1, "left_right", "side by side"},
    {"sbs_rl", MkvStereoLayout::SideBySide, true, "side-by-side", kHalf | kRvf, 11, "right_left",
     "side by side (inverted)"},
    {"tb_lr", MkvStereoLayout::TopBottom, false, "top-bottom", kHalf, 3, "top_bottom", "top and bottom"},
    {"tb_rl", MkvStereoLayout::TopBottom, true, "top-bottom", kHalf | kRvf, 2, "bottom_top",
     "top and bottom (inverted)"},
    {"row_lr", MkvStereoLayout::RowInterleaved, false, "row-interleaved", kHalf, 7, "row_interleaved_lr",
     "interleaved lines"},
    {"row_rl", MkvStereoLayout::RowInterleaved, true, "row-interleaved", kHalf | kRvf, 6, "row_interleaved_rl",
     "interleaved lines (inverted)"},
    // 9 is not written (GStreamer reads it as side by side right first):
    // only the SEI tells, so ffprobe has no stream tag.
    {"col_lr", MkvStereoLayout::ColumnInterleaved, false, "column-interleaved", kHalf, -1, "", "interleaved columns"},
    {"col_rl", MkvStereoLayout::ColumnInterleaved, true, "column-interleaved", kHalf | kRvf, 8, "col_interleaved_rl",
     "interleaved columns (inverted)"},
    {"chk_lr", MkvStereoLayout::Checkerboard, false, "checkerboard", 0, 5, "checkerboard_lr", "checkerboard"},
    {"chk_rl", MkvStereoLayout::Checkerboard, true, "checkerboard", kRvf, 4, "checkerboard_rl",
     "checkerboard (inverted)"},
    {"audio_first_sbs_rl", MkvStereoLayout::SideBySide, true, "side-by-side", kHalf | kRvf, 11, "right_left",
     "side by side (inverted)", Variant::AudioFirst},
    {"streamable_tb_rl", MkvStereoLayout::TopBottom, true, "top-bottom", kHalf | kRvf, 2, "bottom_top",
     "top and bottom (inverted)", Variant::Streamable},
    {"mkvmerge_row_lr", MkvStereoLayout::RowInterleaved, false, "row-interleaved", kHalf, 7, "row_interleaved_lr",
     "interleaved lines", Variant::Mkvmerge},
};

bool is_mono(const Case &c) { return c.layout == MkvStereoLayout::Mono; }
bool has_audio(const Case &c) { return c.variant == Variant::AudioFirst; }

// A case's files, made once for all the reader tests.
struct Prepared {
  std::string skip;   // a reason to skip (a missing encoder or program)
  std::string error;  // making or patching failed
  std::string original, patched;
  int frames = 10;
};

const Prepared &prepare(const Case &c) {
  static std::map<std::string, Prepared> cache;
  auto found = cache.find(c.name);
  if (found != cache.end()) return found->second;
  Prepared &p = cache[c.name];
  if (has_audio(c) && !gst_registry_check_feature_version(gst_registry_get(), "opusenc", 1, 0, 0)) {
    p.skip = "no opusenc";
    return p;
  }
  if (c.variant == Variant::Mkvmerge && !have_program("mkvmerge")) {
    p.skip = "no mkvmerge";
    return p;
  }
  const std::string base = mkv_out_dir() + "/readback_" + c.name;
  p.original = base + "_orig.mkv";
  p.patched = base + ".mkv";
  StereoClip clip;
  clip.mode = c.gst_mode;
  clip.flags = c.flags;
  clip.frames = p.frames;
  clip.audio_first = has_audio(c);
  clip.streamable = c.variant == Variant::Streamable;
  const std::string encoded = c.variant == Variant::Mkvmerge ? base + "_src.mkv" : p.original;
  p.error = make_stereo_mkv(encoded, clip);
  if (p.error.empty() && c.variant == Variant::Mkvmerge) {
    std::string out;
    if (run_program({"mkvmerge", "-q", "-o", p.original, encoded}, &out) > 1) p.error = "mkvmerge: " + out;  // 1: warnings
  }
  if (!p.error.empty()) return p;
  if (!write_bytes(p.patched, read_bytes(p.original))) p.error = "cannot copy " + p.original;
  else if (!mkv_set_stereo_mode(p.patched, c.layout, c.right_first, &p.error)) p.error = "patch: " + p.error;
  return p;
}

class MkvReadback : public ::testing::TestWithParam<Case> {
 protected:
  void SetUp() override {
    p_ = &prepare(GetParam());
    if (!p_->skip.empty()) GTEST_SKIP() << p_->skip;
    ASSERT_EQ(p_->error, "");
  }
  const Prepared *p_ = nullptr;
};

// What the file variants are about: the patch found Tracks and the room.
TEST_P(MkvReadback, Structure) {
  const Case &c = GetParam();
  const Bytes original = read_bytes(p_->original), patched = read_bytes(p_->patched);
  ASSERT_EQ(patched.size(), original.size());
  const TopLevel before = tracks_element(original), after = tracks_element(patched);
  ASSERT_NE(before.end, 0u);
  EXPECT_EQ(after.begin, before.begin);
  if (c.variant == Variant::Mkvmerge) {
    EXPECT_GT(after.end, before.end) << "Tracks did not take in the Void behind it";
  } else {
    EXPECT_EQ(after.end, before.end);
  }
  const size_t rest = size_t(std::max(before.end, after.end));
  EXPECT_TRUE(std::equal(patched.begin() + std::ptrdiff_t(rest), patched.end(), original.begin() + std::ptrdiff_t(rest)))
      << "bytes changed behind Tracks";
  if (c.variant == Variant::Streamable) {
    for (const TopLevel &t : top_level_elements(original)) EXPECT_NE(t.id, kIdSeekHead) << "the file has a SeekHead";
  }
}

// GStreamer after h264parse: the layout, the eye order, square pixels; a
// demuxer that says anything says the same (h264parse prefers it to the
// SEI). And decodebin still plays every frame.
TEST_P(MkvReadback, GStreamer) {
  const Case &c = GetParam();
  const GstStereo before = gst_parsed_stereo(p_->original);
  ASSERT_EQ(before.error, "");
  EXPECT_EQ(before.demux_mode, "") << "the unpatched file has container stereo signalling";
  EXPECT_EQ(before.mode, is_mono(c) ? "" : c.gst_mode);  // from the SEI

  const GstStereo g = gst_parsed_stereo(p_->patched);
  ASSERT_EQ(g.error, "");
  if (is_mono(c)) {
    EXPECT_TRUE(g.mode.empty() || g.mode == "mono") << g.mode;
  } else {
    EXPECT_EQ(g.mode, c.gst_mode);
  }
  EXPECT_EQ(bool(g.flags & kRvf), c.right_first) << std::hex << g.flags;
  EXPECT_EQ(g.par_n, 1);
  EXPECT_EQ(g.par_d, 1);
  if (!g.demux_mode.empty() && g.demux_mode != "mono") {
    EXPECT_EQ(g.demux_mode, c.gst_mode);
    EXPECT_EQ(bool(g.demux_flags & kRvf), c.right_first) << std::hex << g.demux_flags;
  }
  std::printf("[ readback ] %s gst: demux '%s' 0x%x, h264parse '%s' 0x%x %d/%d\n", c.name, g.demux_mode.c_str(),
              g.demux_flags, g.mode.c_str(), g.flags, g.par_n, g.par_d);

  std::string error;
  EXPECT_EQ(gst_decoded_frames(p_->original, has_audio(c), &error), p_->frames) << error;
  EXPECT_EQ(gst_decoded_frames(p_->patched, has_audio(c), &error), p_->frames) << error;
}

// ffprobe's stream (SAR, stereo_mode tag) and ffmpeg's first frame.
TEST_P(MkvReadback, Ffmpeg) {
  if (!have_program("ffprobe") || !have_program("ffmpeg")) GTEST_SKIP() << "no ffprobe/ffmpeg";
  const Case &c = GetParam();
  const FfprobeVideo before = ffprobe_video(p_->original);
  ASSERT_TRUE(before.ok);
  EXPECT_EQ(before.stereo_mode, "");
  EXPECT_EQ(ffmpeg_frame_stereo(p_->original).size(), is_mono(c) ? 0u : 1u);  // the SEI's only

  const FfprobeVideo v = ffprobe_video(p_->patched);
  ASSERT_TRUE(v.ok);
  EXPECT_EQ(v.sar, "1:1");
  EXPECT_EQ(v.stereo_mode, c.ff_tag);
  const std::vector<std::string> frame = ffmpeg_frame_stereo(p_->patched);
  // One from the container (where a StereoMode is written), one from the SEI.
  EXPECT_EQ(frame.size(), (c.stereo_mode >= 0 ? 1u : 0u) + (is_mono(c) ? 0u : 1u));
  for (const std::string &f : frame) EXPECT_EQ(f, c.ff_frame);
  std::printf("[ readback ] %s ffmpeg: sar %s tag '%s' frame '%s' x%zu\n", c.name, v.sar.c_str(),
              v.stereo_mode.c_str(), frame.empty() ? "" : frame[0].c_str(), frame.size());
}

TEST_P(MkvReadback, Mkvinfo) {
  if (!have_program("mkvinfo")) GTEST_SKIP() << "no mkvinfo";
  const Case &c = GetParam();
  std::map<std::string, std::string> m = mkvinfo_video(p_->original);
  EXPECT_EQ(m.count("Stereo mode"), 0u);
  EXPECT_EQ(m.count("Display unit"), 0u);

  m = mkvinfo_video(p_->patched);
  if (c.stereo_mode < 0) {
    EXPECT_EQ(m.count("Stereo mode"), 0u) << m["Stereo mode"];
  } else {
    EXPECT_EQ(m["Stereo mode"].substr(0, m["Stereo mode"].find(' ')), std::to_string(c.stereo_mode));
  }
  EXPECT_EQ(m["Display unit"].substr(0, 1), "4");
  EXPECT_EQ(m["Display width"], "320");
  EXPECT_EQ(m["Display height"], "180");
  EXPECT_EQ(m["Pixel width"], "320");
  if (has_audio(c)) {
    std::string out;
    run_program({"mkvinfo", p_->patched}, &out);
    EXPECT_LT(out.find("Track type: audio"), out.find("Track type: video")) << "the audio track is not first";
  }
  std::printf("[ readback ] %s mkvinfo: Stereo mode '%s', Display unit '%s'\n", c.name, m["Stereo mode"].c_str(),
              m["Display unit"].c_str());
}

INSTANTIATE_TEST_SUITE_P(Files, MkvReadback, ::testing::ValuesIn(kCases),
                         [](const ::testing::TestParamInfo<Case> &i) { return std::string(i.param.name); });

}  // namespace
}  // namespace p3d::test
