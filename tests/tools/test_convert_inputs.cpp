// pseudo3d-convert on the inputs of real films, clips made by GStreamer's
// encoders, converted and read back with ffprobe:
//  * HDR and 10-bit: HDR10 (PQ, mastering display, content light level),
//    HLG and 10-bit SDR. With H.265, the default for them, the output is
//    10-bit Main10 and states the input's transfer, primaries and matrix
//    and the same mastering-display and light-level values; 8-bit input
//    stays 8-bit and gets H.264 by default; H.264 asked for with HDR10
//    input is 8-bit and says what it leaves out; an anaglyph of HDR input
//    is refused with a message.
//  * Interlaced: 576i (SAR 64:45) and 1080i come out progressive, a frame
//    for each field, with the input's duration and SAR.
#include <gtest/gtest.h>

#include <glib/gstdio.h>
#include <gst/gst.h>

#include <string>
#include <vector>

#include "convert_helpers.h"
#include "element_helpers.h"
#include "stereo_readers.h"

using namespace p3d::test;

namespace {

const char kMastering[] = "34000:16000:13250:34500:7500:3000:15635:16450:10000000:1";

struct Clip {
  const char *name, *colorimetry;
  bool static_hdr;  // carries mastering-display-info and content-light-level
  const char *transfer, *primaries, *space;  // as ffprobe names them
};

const Clip kClips[] = {
    {"hdr10", "bt2100-pq", true, "smpte2084", "bt2020", "bt2020nc"},
    {"hlg", "bt2100-hlg", false, "arib-std-b67", "bt2020", "bt2020nc"},
    {"sdr10", "bt709", false, "bt709", "bt709", "bt709"},
};

bool have_element(const char *name) {
  GstElementFactory *f = gst_element_factory_find(name);
  if (f) gst_object_unref(f);
  return f != nullptr;
}

// 1 s of 10-bit HEVC at 160x96 stating the clip's colours (x265enc writes
// the VUI and the HDR10 SEI from the caps).
std::string make_hevc10(const std::string &dir, const Clip &c) {
  const std::string path = dir + "/" + c.name + ".mp4";
  std::string caps = std::string("video/x-raw,format=I420_10LE,width=160,height=96,framerate=25/1,colorimetry=") +
                     c.colorimetry;
  if (c.static_hdr)
    caps += std::string(",mastering-display-info=(string)") + kMastering + ",content-light-level=(string)1000:400";
  const std::string error = make_clip("videotestsrc num-buffers=25 pattern=ball ! " + caps +
                                      " ! x265enc speed-preset=ultrafast ! h265parse ! mp4mux ! filesink location=" +
                                      path);
  return error.empty() ? path : "";
}

// The key=value lines ffprobe gives for the first video frame, its side
// data (mastering display, content light level) included.
std::string ffprobe_first_frame(const std::string &path) {
  std::string out, err;
  run_program({"ffprobe", "-v", "error", "-select_streams", "v:0", "-read_intervals", "%+#1", "-show_frames", "-of",
               "default=noprint_wrappers=1", path},
              &out, &err);
  return out;
}

class ConvertInputs : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!have_element("x265enc")) GTEST_SKIP() << "x265enc is not installed (gstreamer1.0-plugins-bad)";
    if (!have_program("ffprobe")) GTEST_SKIP() << "ffprobe not installed (apt-get install ffmpeg)";
    dir_ = output_dir() + "/convert-inputs";
    g_mkdir_with_parents(dir_.c_str(), 0755);
  }
  std::string dir_;
};

}  // namespace

// Each clip through the converter into H.265 in MP4 (the default codec,
// --codec auto, for 10-bit input) and Matroska (--codec h265): the
// transfer, primaries and matrix ffprobe reads are the input's, and so are
// the mastering-display and light-level values of HDR10.
TEST_F(ConvertInputs, H265KeepsTheInputsColourSignal) {
  for (const Clip &c : kClips) {
    const std::string in = make_hevc10(dir_, c);
    ASSERT_FALSE(in.empty()) << c.name << ": could not make the clip";
    const std::string in_frame = ffprobe_first_frame(in);
    ASSERT_EQ(ffprobe_value(in_frame, "color_transfer"), c.transfer) << c.name << ": the clip itself";
    for (const char *ext : {".mp4", ".mkv"}) {
      const std::string out = dir_ + "/" + c.name + "-sbs" + ext;
      std::vector<std::string> args = {in, out, "--preset", "ultrafast", "--processing", "cpu", "--force"};
      if (std::string(ext) == ".mkv") args.insert(args.end(), {"--codec", "h265"});
      const ToolRun r = run_convert(args);
      ASSERT_EQ(r.status, 0) << c.name << ext << ": " << r.err;
      const std::string what = std::string(c.name) + ext;
      const std::string s = ffprobe_stream(
          out, "v:0", "codec_name,color_transfer,color_primaries,color_space,color_range,pix_fmt,profile");
      EXPECT_EQ(ffprobe_value(s, "codec_name"), "hevc") << what;
      EXPECT_EQ(ffprobe_value(s, "pix_fmt"), "yuv420p10le") << what;
      EXPECT_EQ(ffprobe_value(s, "profile"), "Main 10") << what;
      EXPECT_EQ(r.err.find("bits a sample"), std::string::npos) << what << ": no note of lost bits expected: " << r.err;
      EXPECT_EQ(ffprobe_value(s, "color_transfer"), c.transfer) << what;
      EXPECT_EQ(ffprobe_value(s, "color_primaries"), c.primaries) << what;
      EXPECT_EQ(ffprobe_value(s, "color_space"), c.space) << what;
      EXPECT_EQ(ffprobe_value(s, "color_range"), "tv") << what;
      const std::string out_frame = ffprobe_first_frame(out);
      for (const char *key : {"red_x", "red_y", "green_x", "green_y", "blue_x", "blue_y", "white_point_x",
                              "white_point_y", "min_luminance", "max_luminance", "max_content", "max_average"})
        EXPECT_EQ(ffprobe_value(out_frame, key), ffprobe_value(in_frame, key)) << what << ": " << key;
      if (c.static_hdr) {
        EXPECT_EQ(ffprobe_value(out_frame, "max_luminance"), "10000000/10000") << what;
        EXPECT_EQ(ffprobe_value(out_frame, "max_content"), "1000") << what;
        EXPECT_EQ(ffprobe_value(out_frame, "max_average"), "400") << what;
      }
    }
  }
}

// 8-bit SDR input stays 8-bit with either codec: H.265 Main, H.264 by default.
TEST_F(ConvertInputs, EightBitInputStaysEightBit) {
  const std::string in = dir_ + "/sdr8.mp4";
  ASSERT_EQ(make_clip("videotestsrc num-buffers=25 pattern=ball ! video/x-raw,format=I420,width=160,height=96,"
                      "framerate=25/1 ! x265enc speed-preset=ultrafast ! h265parse ! mp4mux ! filesink location=" +
                      in),
            "");
  for (const bool h265 : {true, false}) {
    const std::string out = dir_ + (h265 ? "/sdr8-h265.mp4" : "/sdr8-h264.mp4");
    std::vector<std::string> args = {in, out, "--preset", "ultrafast", "--processing", "cpu", "--force"};
    if (h265) args.insert(args.end(), {"--codec", "h265"});
    const ToolRun r = run_convert(args);
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string s = ffprobe_stream(out, "v:0", "codec_name,pix_fmt,profile");
    EXPECT_EQ(ffprobe_value(s, "codec_name"), h265 ? "hevc" : "h264");
    EXPECT_EQ(ffprobe_value(s, "pix_fmt"), "yuv420p");
    if (h265) {
      EXPECT_EQ(ffprobe_value(s, "profile"), "Main");
    }
  }
  // --crf 51 is H.265's alone: for 8-bit input --codec auto chose H.264.
  const ToolRun r = run_convert({in, dir_ + "/sdr8-crf51.mp4", "--crf", "51", "--processing", "cpu", "--force"});
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("0 to 50 for H.264, which --codec auto chose"), std::string::npos) << r.err;
}

// 10-bit H.264 (High 10) gets H.265 Main 10 by default too: the sample
// depth comes from h264parse's bit-depth-luma (input_probe.h).
TEST_F(ConvertInputs, TenBitH264GetsH265ByDefault) {
  const std::string in = dir_ + "/h264-10.mp4";
  ASSERT_EQ(make_clip("videotestsrc num-buffers=10 pattern=ball ! video/x-raw,format=I420_10LE,width=160,height=96,"
                      "framerate=25/1 ! x264enc speed-preset=ultrafast ! h264parse ! mp4mux ! filesink location=" +
                      in),
            "");
  ASSERT_EQ(ffprobe_value(ffprobe_stream(in, "v:0", "codec_name,pix_fmt"), "pix_fmt"), "yuv420p10le");
  const std::string out = dir_ + "/h264-10-sbs.mkv";
  const ToolRun r = run_convert({in, out, "--preset", "ultrafast", "--processing", "cpu", "--force"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("x265enc"), std::string::npos) << r.err;
  const std::string s = ffprobe_stream(out, "v:0", "codec_name,pix_fmt,profile");
  EXPECT_EQ(ffprobe_value(s, "codec_name"), "hevc");
  EXPECT_EQ(ffprobe_value(s, "pix_fmt"), "yuv420p10le");
  EXPECT_EQ(ffprobe_value(s, "profile"), "Main 10");
}

// H.264 of HDR10, asked for: the colours are stated, and the converter says that the
// mastering-display and light-level metadata is left out and how to keep it.
TEST_F(ConvertInputs, H264OfHdr10SaysWhatItLeavesOut) {
  const std::string in = make_hevc10(dir_, kClips[0]);
  ASSERT_FALSE(in.empty());
  const std::string out = dir_ + "/hdr10-h264.mp4";
  const ToolRun r =
      run_convert({in, out, "--codec", "h264", "--preset", "ultrafast", "--processing", "cpu", "--force"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("mastering-display and light-level metadata is not written by x264enc"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("--codec h265 keeps it"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("the input has 10 bits a sample; the output has 8 (--codec h265 keeps 10)"), std::string::npos)
      << r.err;
  const std::string s = ffprobe_stream(out, "v:0", "color_transfer,color_primaries,pix_fmt");
  EXPECT_EQ(ffprobe_value(s, "pix_fmt"), "yuv420p");
  EXPECT_EQ(ffprobe_value(s, "color_transfer"), "smpte2084");
  EXPECT_EQ(ffprobe_value(s, "color_primaries"), "bt2020");
}

// An anaglyph of PQ or HLG video: one line naming the reason, no output.
TEST_F(ConvertInputs, AnaglyphOfHdrIsRefused) {
  for (const Clip &c : kClips) {
    const std::string in = make_hevc10(dir_, c);
    ASSERT_FALSE(in.empty());
    const std::string out = dir_ + "/" + c.name + "-anaglyph.mp4";
    g_remove(out.c_str());
    const ToolRun r = run_convert({in, out, "--layout", "anaglyph", "--preset", "ultrafast", "--processing", "cpu",
                                   "--quiet"});
    if (c.static_hdr || std::string(c.transfer) == "arib-std-b67") {
      EXPECT_NE(r.status, 0) << c.name;
      EXPECT_NE(r.err.find("An anaglyph needs SDR video"), std::string::npos) << c.name << ": " << r.err;
      EXPECT_FALSE(g_file_test(out.c_str(), G_FILE_TEST_EXISTS)) << c.name;
    } else {
      EXPECT_EQ(r.status, 0) << c.name << ": " << r.err;
    }
  }
}

// Interlaced clips (top field first, as x264enc codes them): the output is
// progressive at the field rate, twice the frames over the same duration,
// with the input's sample aspect ratio.
TEST_F(ConvertInputs, InterlacedVideoIsDeinterlacedAtFieldRate) {
  struct Interlaced {
    const char *name;
    int width, height, frames;
    const char *par, *sar;
  };
  for (const Interlaced &c : {Interlaced{"576i", 720, 576, 25, "64/45", "64:45"},
                              Interlaced{"1080i", 1920, 1080, 10, "1/1", "1:1"}}) {
    const std::string in = dir_ + "/" + c.name + ".mp4", out = dir_ + "/" + c.name + "-sbs.mkv";
    const std::string clip_error = make_clip(
        "videotestsrc num-buffers=" + std::to_string(c.frames) + " pattern=ball ! video/x-raw,format=I420,width=" +
        std::to_string(c.width) + ",height=" + std::to_string(c.height) + ",framerate=25/1,pixel-aspect-ratio=" +
        c.par + ",interlace-mode=interleaved,field-order=top-field-first ! x264enc interlaced=true "
        "speed-preset=ultrafast ! h264parse ! mp4mux ! filesink location=" + in);
    ASSERT_EQ(clip_error, "") << c.name;
    const std::string probe_in = ffprobe_stream(in, "v:0", "field_order");
    ASSERT_EQ(ffprobe_value(probe_in, "field_order"), "tt") << c.name << ": the clip is not interlaced";
    const ToolRun r = run_convert({in, out, "--preset", "ultrafast", "--processing", "cpu", "--force"});
    ASSERT_EQ(r.status, 0) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find("deinterlaced to 50 frames/s"), std::string::npos) << c.name << ": " << r.err;
    std::string frames;
    run_program({"ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                 "stream=nb_read_frames,field_order,sample_aspect_ratio,r_frame_rate,width,height", "-of",
                 "default=noprint_wrappers=1", out},
                &frames);
    EXPECT_EQ(ffprobe_value(frames, "field_order"), "progressive") << c.name;
    EXPECT_EQ(ffprobe_value(frames, "nb_read_frames"), std::to_string(2 * c.frames)) << c.name;
    EXPECT_EQ(ffprobe_value(frames, "r_frame_rate"), "50/1") << c.name;
    EXPECT_EQ(ffprobe_value(frames, "sample_aspect_ratio"), c.sar) << c.name;
    EXPECT_EQ(ffprobe_value(frames, "width"), std::to_string(c.width)) << c.name;
    std::string format;
    run_program({"ffprobe", "-v", "error", "-show_entries", "format=duration", "-of", "default=noprint_wrappers=1",
                 out},
                &format);
    EXPECT_NEAR(std::stod("0" + ffprobe_value(format, "duration")), c.frames / 25.0, 0.021) << c.name;
  }
}
