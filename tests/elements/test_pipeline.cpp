// Whole pipelines from gst_parse_launch: the four stages, the bin, and
// still-image and video outputs that the README's pictures come from.
#include <gtest/gtest.h>

#include <glib/gstdio.h>

#include "element_helpers.h"
#include "test_data.h"

using namespace p3d::test;

TEST(Pipeline, FourStagesToEos) {
  EXPECT_EQ("", run_to_eos("videotestsrc num-buffers=5 pattern=ball ! video/x-raw,width=320,height=240 ! "
                           "pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp ! pseudo3dpack ! fakesink"));
}

TEST(Pipeline, EveryLayoutToEos) {
  for (const char *layout : {"anaglyph", "side-by-side", "side-by-side-half", "top-bottom", "top-bottom-half",
                             "row-interleaved", "column-interleaved", "checkerboard", "left", "right"}) {
    EXPECT_EQ("", run_to_eos(std::string("videotestsrc num-buffers=2 ! video/x-raw,width=97,height=31,format=NV12 ! "
                                         "pseudo3dconvert layout=") +
                             layout + " swap-eyes=true ! videoconvert ! fakesink"))
        << layout;
  }
}

TEST(Pipeline, BinWithDecodedVideo) {
  const std::string avi = data_dir() + "/vtest.avi";
  ASSERT_TRUE(g_file_test(avi.c_str(), G_FILE_TEST_EXISTS)) << "run scripts/get-test-data.sh";
  const std::string out = output_dir() + "/vtest-sbs.mkv";
  EXPECT_EQ("", run_to_eos("filesrc location=" + avi + " ! decodebin ! identity eos-after=60 ! videoconvert ! video/x-raw,format=I420 ! "
                           "pseudo3dconvert layout=side-by-side-half ! videoconvert ! x264enc speed-preset=ultrafast "
                           "frame-packing=auto ! h264parse ! matroskamux ! filesink location=" + out,
                           180));
  GStatBuf st;
  ASSERT_EQ(g_stat(out.c_str(), &st), 0);
  EXPECT_GT(st.st_size, 10000);
}

TEST(Pipeline, StillImageToAnaglyphPng) {
  const std::string png = output_dir() + "/aloe-anaglyph.png";
  EXPECT_EQ("", run_to_eos("filesrc location=" + data_dir() + "/aloeL.jpg ! jpegdec ! videoconvert ! "
                           "video/x-raw,format=RGBA ! pseudo3dconvert max-disparity=4 ! videoconvert ! pngenc ! "
                           "filesink location=" + png));
  GStatBuf st;
  ASSERT_EQ(g_stat(png.c_str(), &st), 0);
  EXPECT_GT(st.st_size, 1000);
}

TEST(Pipeline, BadPropertyValueFailsToParse) {
  EXPECT_NE("", run_to_eos("videotestsrc num-buffers=1 ! pseudo3dpack layout=nonsense ! fakesink"));
}

// processing=gpu without a usable GPU fails to start with a message that
// says so (skipped where a GPU is present: then it simply runs).
TEST(Pipeline, ProcessingGpuWithoutGpuIsAClearError) {
  const std::string err = run_to_eos("videotestsrc num-buffers=1 ! pseudo3ddepth processing=gpu ! fakesink");
  if (err.empty()) GTEST_SKIP() << "a GPU is present";
  EXPECT_NE(err.find("processing=gpu"), std::string::npos) << err;
}
