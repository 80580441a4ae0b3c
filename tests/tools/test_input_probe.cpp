// probe_input (tools/convert/input_probe.h), what the converter reads of
// an input before it builds its pipeline, on clips made here: the sample
// depth of 8-bit H.264, 10-bit H.264 and 10-bit HEVC; an orientation tag
// (ffmpeg's rotate metadata); nothing from a FIFO, a damaged file or a
// file with no video, each within the probe's own time.
#include <gtest/gtest.h>

#include <glib/gstdio.h>
#include <gst/gst.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <string>

#include "convert_helpers.h"
#include "element_helpers.h"
#include "input_probe.h"
#include "stereo_readers.h"

using namespace p3d::test;
using p3d::convert::InputFacts;
using p3d::convert::probe_input;

namespace {

bool have_element(const char *name) {
  GstElementFactory *f = gst_element_factory_find(name);
  if (f) gst_object_unref(f);
  return f != nullptr;
}

class InputProbe : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = output_dir() + "/input-probe";
    g_mkdir_with_parents(dir_.c_str(), 0755);
  }
  // 10 frames of videotestsrc in `format`, encoded by `encoder` into MP4.
  std::string clip(const std::string &name, const std::string &format, const std::string &encoder) {
    const std::string path = dir_ + "/" + name + ".mp4";
    const std::string error = make_clip("videotestsrc num-buffers=10 ! video/x-raw,format=" + format +
                                        ",width=160,height=96,framerate=25/1 ! " + encoder + " ! mp4mux ! "
                                        "filesink location=" + path);
    EXPECT_EQ(error, "") << name;
    return path;
  }
  std::string dir_;
};

}  // namespace

TEST_F(InputProbe, SampleDepthOfTheParsedStream) {
  const InputFacts h264 = probe_input(clip("h264-8", "I420", "x264enc speed-preset=ultrafast ! h264parse"));
  EXPECT_EQ(h264.bits, 8);
  EXPECT_FALSE(h264.rotated);
  EXPECT_EQ(probe_input(clip("h264-10", "I420_10LE", "x264enc speed-preset=ultrafast ! h264parse")).bits, 10);
  if (!have_element("x265enc")) GTEST_SKIP() << "x265enc is not installed (gstreamer1.0-plugins-bad)";
  EXPECT_EQ(probe_input(clip("h265-10", "I420_10LE", "x265enc speed-preset=ultrafast ! h265parse")).bits, 10);
}

TEST_F(InputProbe, OrientationTag) {
  if (!have_program("ffmpeg")) GTEST_SKIP() << "ffmpeg not installed: no rotate metadata";
  const std::string plain = clip("plain", "I420", "x264enc speed-preset=ultrafast ! h264parse");
  const std::string tagged = dir_ + "/rotated.mp4";
  std::string out, err;
  ASSERT_EQ(run_program({"ffmpeg", "-v", "error", "-y", "-i", plain, "-c", "copy", "-metadata:s:v:0", "rotate=90",
                         tagged},
                        &out, &err),
            0)
      << err;
  const InputFacts facts = probe_input(tagged);
  EXPECT_TRUE(facts.rotated);
  EXPECT_EQ(facts.bits, 8);
  EXPECT_FALSE(probe_input(plain).rotated);
}

// Nothing is known, quickly, of what has no video to parse; a FIFO is not
// opened at all (the conversion reads it, once).
TEST_F(InputProbe, NothingFromWhatHasNoVideo) {
  const std::string damaged = dir_ + "/damaged.mp4", fifo = dir_ + "/fifo";
  std::ofstream(damaged) << std::string(4096, '\x5a');
  g_remove(fifo.c_str());
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const std::string audio = dir_ + "/audio.mka";
  ASSERT_EQ(make_clip("audiotestsrc num-buffers=20 ! vorbisenc ! matroskamux ! filesink location=" + audio), "");
  for (const std::string &path : {damaged, fifo, audio, dir_ + "/missing.mp4"}) {
    const auto t0 = std::chrono::steady_clock::now();
    const InputFacts facts = probe_input(path);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(facts.bits, 0) << path;
    EXPECT_FALSE(facts.rotated) << path;
    EXPECT_LT(seconds, 5.0) << path;
  }
  g_remove(fifo.c_str());
}
