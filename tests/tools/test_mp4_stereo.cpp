// The MP4 st3d box editor (tools/support/mp4_stereo.h) on files GStreamer
// writes: mp4mux's default (mdat, then moov, then a uuid box), mp4mux
// faststart=true (moov before mdat: every chunk offset moves), qtmux
// (.mov), and an mdat on each side of moov. After the edit ffprobe reads
// the layout from the box, GStreamer and ffmpeg still decode every frame
// (the offsets are right), a second edit replaces the box instead of
// adding one, and files that are not MP4, hold no video, are fragmented
// or damaged are refused and left as they were.
#include <gtest/gtest.h>

#include <glib/gstdio.h>

#include <algorithm>
#include <string>
#include <vector>

#include "element_helpers.h"
#include "mkv_files.h"
#include "mp4_stereo.h"
#include "stereo_readers.h"

using namespace p3d;
using namespace p3d::test;

namespace {

constexpr int kFrames = 12;

std::string clip(const std::string &name, const std::string &muxer) {
  const std::string path = mkv_out_dir() + "/" + name;
  const std::string error = run_to_eos("videotestsrc num-buffers=" + std::to_string(kFrames) +
                                       " ! video/x-raw,width=96,height=64,framerate=25/1 ! x264enc "
                                       "speed-preset=ultrafast ! h264parse ! " +
                                       muxer + " ! filesink location=" + path);
  return error.empty() ? path : "";
}

int count_of(const Bytes &b, const char *four) {
  int n = 0;
  for (size_t i = 0; i + 4 <= b.size(); ++i) n += std::equal(four, four + 4, b.begin() + i);
  return n;
}

struct Case {
  const char *name, *muxer;
};
const Case kCases[] = {{"default.mp4", "mp4mux"}, {"faststart.mp4", "mp4mux faststart=true"}, {"movie.mov", "qtmux"}};

}  // namespace

TEST(Mp4StereoBox, WrittenReadAndReplaced) {
  const bool ffprobe = have_program("ffprobe") && have_program("ffmpeg");
  for (const Case &c : kCases) {
    const std::string path = clip(c.name, c.muxer);
    ASSERT_FALSE(path.empty()) << c.name;
    const size_t before = read_bytes(path).size();
    std::string error;
    ASSERT_TRUE(mp4_set_stereo_box(path, Mp4StereoMode::LeftRight, &error)) << c.name << ": " << error;
    const Bytes once = read_bytes(path);
    EXPECT_EQ(once.size(), before + 13) << c.name << ": one 13-byte box added";
    EXPECT_EQ(count_of(once, "st3d"), 1) << c.name;
    ASSERT_TRUE(mp4_set_stereo_box(path, Mp4StereoMode::TopBottom, &error)) << c.name << ": " << error;
    const Bytes twice = read_bytes(path);
    EXPECT_EQ(twice.size(), once.size()) << c.name << ": the box is replaced, not added";
    EXPECT_EQ(count_of(twice, "st3d"), 1) << c.name;
    EXPECT_EQ(gst_decoded_frames(path, false, &error), kFrames) << c.name << ": " << error;
    if (ffprobe) {
      EXPECT_EQ(ffprobe_video(path).stereo_side_data, "top and bottom") << c.name;
      std::string out, err;
      EXPECT_EQ(run_program({"ffmpeg", "-v", "error", "-i", path, "-f", "null", "-"}, &out, &err), 0) << c.name;
      EXPECT_EQ(err, "") << c.name << ": ffmpeg decodes without complaint";
    }
  }
}

// mdat before moov and another, empty, after it: only offsets past moov
// move, so every frame still decodes.
TEST(Mp4StereoBox, OnlyOffsetsPastTheMovieBoxMove) {
  const std::string path = clip("mdat-both-sides.mp4", "mp4mux");
  ASSERT_FALSE(path.empty());
  Bytes b = read_bytes(path);
  const uint8_t empty_mdat[8] = {0, 0, 0, 8, 'm', 'd', 'a', 't'};
  b.insert(b.end(), empty_mdat, empty_mdat + 8);
  ASSERT_TRUE(write_bytes(path, b));
  std::string error;
  ASSERT_TRUE(mp4_set_stereo_box(path, Mp4StereoMode::LeftRight, &error)) << error;
  EXPECT_EQ(gst_decoded_frames(path, false, &error), kFrames) << error;
}

TEST(Mp4StereoBox, RefusesWhatIsNotAnMp4WithVideo) {
  const std::string text = mkv_out_dir() + "/not-mp4.mp4";
  ASSERT_TRUE(write_bytes(text, Bytes(300, 'x')));
  const std::string audio = mkv_out_dir() + "/audio-only.mp4";
  ASSERT_EQ(run_to_eos("audiotestsrc num-buffers=20 ! avenc_aac ! aacparse ! mp4mux ! filesink location=" + audio), "");
  const std::string fragmented = clip("fragmented.mp4", "mp4mux fragment-duration=200");
  ASSERT_FALSE(fragmented.empty());
  for (const std::string &path : {text, audio, fragmented}) {
    const Bytes before = read_bytes(path);
    std::string error;
    EXPECT_FALSE(mp4_set_stereo_box(path, Mp4StereoMode::LeftRight, &error)) << path;
    EXPECT_NE(error.find(path), std::string::npos) << error;
    EXPECT_EQ(read_bytes(path), before) << path << ": left as it was";
  }
}

// Damaged files: cut short at many points, or with bytes overwritten in
// the movie box. The editor never reads or writes out of bounds (the
// sanitizer build runs this too) and either writes its 13 bytes or
// refuses and leaves the file as it was.
TEST(Mp4StereoBox, DamagedFilesAreRefusedUnchanged) {
  const std::string good = clip("damaged-source.mp4", "mp4mux");
  ASSERT_FALSE(good.empty());
  const Bytes original = read_bytes(good);
  const std::string path = mkv_out_dir() + "/damaged.mp4";
  int refused = 0, written = 0;
  auto check = [&](const Bytes &damaged, const std::string &what) {
    ASSERT_TRUE(write_bytes(path, damaged));
    std::string error;
    if (mp4_set_stereo_box(path, Mp4StereoMode::LeftRight, &error)) {
      ++written;
      EXPECT_EQ(read_bytes(path).size(), damaged.size() + 13) << what;
    } else {
      ++refused;
      EXPECT_EQ(read_bytes(path), damaged) << what << ": " << error;
    }
  };
  for (size_t cut = 0; cut < original.size(); cut += 97)
    check(Bytes(original.begin(), original.begin() + cut), "cut at " + std::to_string(cut));
  // Overwrite words all through the movie box (mp4mux writes it after mdat).
  const char kMoov[] = "moov";
  const auto found = std::search(original.begin(), original.end(), kMoov, kMoov + 4);
  ASSERT_NE(found, original.end());
  const size_t moov = static_cast<size_t>(found - original.begin()) - 4;
  for (size_t at = moov; at + 4 <= original.size(); at += 29) {
    Bytes damaged = original;
    for (int k = 0; k < 4; ++k) damaged[at + k] = static_cast<uint8_t>(0xFF - k * 0x3F);
    check(damaged, "overwritten at " + std::to_string(at));
  }
  EXPECT_GT(refused, 0);
  EXPECT_GT(written, 0);
}
