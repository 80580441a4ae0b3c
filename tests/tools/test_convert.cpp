// pseudo3d-convert end to end: small generated clips with audio converted to
// MP4 and MKV in several layouts and read back (GStreamer in process,
// ffprobe where installed), the failure cases (missing input, existing
// output, unknown extension/option, an undecodable file, Ctrl-C), and the
// photo outputs (EXIF-rotated JPEG, MPO, JPS, depth map).
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <csignal>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <thread>

#include <glib/gstdio.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "convert_helpers.h"
#include "element_helpers.h"
#include "stereo_readers.h"

using namespace p3d::test;

namespace {

constexpr double kFrame = 1.0 / 25;  // the clips' frame duration: the A/V tolerance
constexpr unsigned kRightFirst = 0x1, kHalf = 0x4000;  // GstVideoMultiviewFlags

int line_count(const std::string &s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

// The stereo description ffmpeg gives the first frame, "" if none; every
// source of it (the container's, the H.264 SEI's) must agree.
std::string ffmpeg_stereo3d(const std::string &file) {
  const std::vector<std::string> all = ffmpeg_frame_stereo(file);
  for (const std::string &s : all)
    if (s != all.front()) return "disagreeing: " + all.front() + " / " + s;
  return all.empty() ? "" : all.front();
}

// A run that failed as every failure must: status 1, one line on stderr
// naming `mention`, neither OUTPUT nor a temporary file left in `dir`.
void expect_clean_failure(const ToolRun &r, const std::string &out, const std::string &mention,
                          const std::string &dir) {
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(mention), std::string::npos) << r.err;
  EXPECT_FALSE(g_file_test(out.c_str(), G_FILE_TEST_EXISTS));
  EXPECT_TRUE(files_containing(dir, ".p3d-").empty());
}

std::string slurp(const std::string &path) {
  std::ifstream f(path);
  return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

// The clips and the conversions every video test reads, made once.
struct Fixture {
  std::string dir, aac_mp4, vorbis_mkv, long_mkv;
  std::string sbs_mp4, tb_mkv, ana_mp4;
  ToolRun sbs_run, tb_run, ana_run;
  std::string setup_error;
};
Fixture *g_fx = nullptr;

// 2 s at 160x120, 25 frames/s, with 2 s of 48 kHz stereo audio.
std::string clip_launch(const std::string &path, const std::string &audio_encoder, const std::string &mux,
                        int seconds = 2, int width = 160, int height = 120) {
  return "videotestsrc num-buffers=" + std::to_string(25 * seconds) + " pattern=ball ! video/x-raw,format=I420,width=" +
         std::to_string(width) + ",height=" + std::to_string(height) +
         ",framerate=25/1 ! x264enc speed-preset=ultrafast ! h264parse ! " + mux + " name=m ! filesink location=" +
         path + " audiotestsrc num-buffers=" + std::to_string(50 * seconds) +
         " samplesperbuffer=960 ! audio/x-raw,rate=48000,channels=2 ! " + audio_encoder + " ! m.";
}

class Convert : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (g_fx) return;
    g_fx = new Fixture;
    Fixture &f = *g_fx;
    f.dir = output_dir() + "/convert";
    g_mkdir_with_parents(f.dir.c_str(), 0755);
    f.aac_mp4 = f.dir + "/clip-aac.mp4";
    f.vorbis_mkv = f.dir + "/clip-vorbis.mkv";
    f.long_mkv = f.dir + "/clip-long.mkv";
    f.setup_error = make_clip(clip_launch(f.aac_mp4, "avenc_aac ! aacparse", "mp4mux"));
    if (f.setup_error.empty()) f.setup_error = make_clip(clip_launch(f.vorbis_mkv, "vorbisenc", "matroskamux"));
    if (f.setup_error.empty())
      f.setup_error = make_clip(clip_launch(f.long_mkv, "vorbisenc", "matroskamux", 20, 640, 480));
    if (!f.setup_error.empty()) return;
    f.sbs_mp4 = f.dir + "/sbs-half.mp4";
    f.tb_mkv = f.dir + "/tb-right-first.mkv";
    f.ana_mp4 = f.dir + "/anaglyph.mp4";
    for (const std::string &p : {f.sbs_mp4, f.tb_mkv, f.ana_mp4}) g_remove(p.c_str());
    // Default options (side-by-side-half, H.264 crf 20, audio copied).
    f.sbs_run = run_convert({f.aac_mp4, f.sbs_mp4});
    f.tb_run = run_convert({f.vorbis_mkv, f.tb_mkv, "--layout", "top-bottom", "--swap-eyes", "--preset", "veryfast"});
    // MP4 takes no Vorbis: re-encoded (AAC).
    f.ana_run = run_convert({f.vorbis_mkv, f.ana_mp4, "--layout", "anaglyph", "--crf", "18", "--quiet"});
  }
  void SetUp() override { ASSERT_EQ("", g_fx->setup_error) << "could not make the test clips"; }
  const Fixture &fx() const { return *g_fx; }
};

void expect_same_timing(const ReadBack &in, const ReadBack &out) {
  EXPECT_EQ(out.video_frames, in.video_frames);
  EXPECT_NEAR(out.video_end - out.video_start, in.video_end - in.video_start, kFrame);
  ASSERT_GT(out.audio_buffers, 0) << "no audio in the output";
  EXPECT_NEAR(out.audio_end - out.audio_start, in.audio_end - in.audio_start, kFrame);
  // A/V sync: both streams start together, as in the input.
  EXPECT_NEAR(out.audio_start - out.video_start, in.audio_start - in.video_start, kFrame);
}

}  // namespace

TEST_F(Convert, Mp4SideBySideHalfCopiesAudioAndSignalsStereo) {
  const ToolRun &r = fx().sbs_run;
  ASSERT_EQ(r.status, 0) << r.err;
  const ReadBack in = read_back(fx().aac_mp4), out = read_back(fx().sbs_mp4);
  ASSERT_EQ(out.error, "");
  EXPECT_EQ(out.multiview_mode, "side-by-side") << out.video_caps;
  EXPECT_EQ(out.multiview_flags & (kHalf | kRightFirst), kHalf) << out.video_caps;
  EXPECT_NE(out.video_caps.find("pixel-aspect-ratio=(fraction)1/1"), std::string::npos) << out.video_caps;
  EXPECT_EQ(out.width, 160);
  EXPECT_EQ(out.height, 120);
  expect_same_timing(in, out);
  EXPECT_EQ(out.audio_caps.rfind("audio/mpeg", 0), 0u) << out.audio_caps;
  // Copied, not re-encoded: the very same AAC packets.
  EXPECT_EQ(out.audio_buffers, in.audio_buffers);
  EXPECT_EQ(out.audio_checksum, in.audio_checksum);
  // Progress (plain lines: stderr is no terminal here) and the summary.
  EXPECT_NE(r.err.find("100.0 %"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("frames/s"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("wrote " + fx().sbs_mp4), std::string::npos) << r.err;
  EXPECT_TRUE(files_containing(fx().dir, ".p3d-").empty());
}

TEST_F(Convert, MkvTopBottomRightFirstCopiesVorbis) {
  const ToolRun &r = fx().tb_run;
  ASSERT_EQ(r.status, 0) << r.err;
  const ReadBack in = read_back(fx().vorbis_mkv), out = read_back(fx().tb_mkv);
  ASSERT_EQ(out.error, "");
  EXPECT_EQ(out.multiview_mode, "top-bottom") << out.video_caps;
  EXPECT_EQ(out.multiview_flags & (kHalf | kRightFirst), kRightFirst) << out.video_caps;
  EXPECT_EQ(out.width, 160);
  EXPECT_EQ(out.height, 240);
  expect_same_timing(in, out);
  EXPECT_EQ(out.audio_caps.rfind("audio/x-vorbis", 0), 0u) << out.audio_caps;
  EXPECT_EQ(out.audio_checksum, in.audio_checksum);
}

// The converter edits the finished Matroska file's StereoMode (the SEI alone
// reaches only the players that parse H.264): every reader gets top-bottom,
// right view first, from the container.
TEST_F(Convert, MkvContainerStereoModeIsWritten) {
  ASSERT_EQ(fx().tb_run.status, 0) << fx().tb_run.err;
  const GstStereo gst = gst_parsed_stereo(fx().tb_mkv);
  ASSERT_EQ(gst.error, "");
  EXPECT_EQ(gst.demux_mode, "top-bottom") << "matroskademux read no StereoMode";
  EXPECT_EQ(gst.demux_flags & kRightFirst, kRightFirst);
  if (have_program("ffprobe")) {
    const FfprobeVideo probe = ffprobe_video(fx().tb_mkv);
    ASSERT_TRUE(probe.ok);
    EXPECT_EQ(probe.stereo_mode, "bottom_top");
  }
  if (have_program("mkvinfo")) {
    const auto track = mkvinfo_video(fx().tb_mkv);
    ASSERT_TRUE(track.count("Stereo mode")) << "mkvinfo shows no StereoMode";
    EXPECT_EQ(track.at("Stereo mode").rfind("2 ", 0), 0u) << track.at("Stereo mode");
  }
}

TEST_F(Convert, Mp4AnaglyphIs444AndReencodesVorbisToAac) {
  const ToolRun &r = fx().ana_run;
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err, "") << "--quiet prints nothing";
  const ReadBack in = read_back(fx().vorbis_mkv), out = read_back(fx().ana_mp4);
  ASSERT_EQ(out.error, "");
  EXPECT_TRUE(out.multiview_mode.empty() || out.multiview_mode == "mono") << out.video_caps;
  EXPECT_NE(out.video_caps.find("chroma-format=(string)4:4:4"), std::string::npos) << out.video_caps;
  EXPECT_EQ(out.width, 160);
  EXPECT_EQ(out.height, 120);
  EXPECT_EQ(out.video_frames, in.video_frames);
  EXPECT_NE(out.audio_caps.find("mpegversion=(int)4"), std::string::npos) << out.audio_caps;
  // AAC adds its encoder delay at most: within one frame.
  EXPECT_NEAR(out.audio_end - out.audio_start, in.audio_end - in.audio_start, kFrame);
}

// The summary line names each audio stream by the codec it had: a
// re-encoded one arrives decoded, and was described by its decoded caps
// ("Raw 32-bit floating-point audio" for this Vorbis); a copied one by its
// own caps.
TEST_F(Convert, SummaryNamesTheCodecAReencodedStreamHad) {
  const std::string out = fx().dir + "/summary-vorbis.mp4";
  g_remove(out.c_str());
  const ToolRun r = run_convert({fx().vorbis_mkv, out, "--preset", "ultrafast"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("audio re-encoded from Vorbis"), std::string::npos) << r.err;
  ASSERT_EQ(fx().sbs_run.status, 0);
  EXPECT_NE(fx().sbs_run.err.find("audio copied, MPEG-4 AAC"), std::string::npos) << fx().sbs_run.err;
}

TEST_F(Convert, FfprobeReadsLayoutEyeOrderAndAudio) {
  if (!have_program("ffprobe") || !have_program("ffmpeg")) GTEST_SKIP() << "ffprobe not installed (apt-get install ffmpeg)";
  ASSERT_EQ(fx().sbs_run.status, 0);
  ASSERT_EQ(fx().tb_run.status, 0);
  ASSERT_EQ(fx().ana_run.status, 0);
  const std::string v = "width,height,sample_aspect_ratio,pix_fmt,duration";
  const std::string sbs = ffprobe_stream(fx().sbs_mp4, "v:0", v);
  EXPECT_EQ(ffprobe_value(sbs, "width"), "160");
  EXPECT_EQ(ffprobe_value(sbs, "sample_aspect_ratio"), "1:1");
  EXPECT_EQ(ffmpeg_stereo3d(fx().sbs_mp4), "side by side");
  const std::string sbs_audio = ffprobe_stream(fx().sbs_mp4, "a:0", "codec_name,duration");
  EXPECT_EQ(ffprobe_value(sbs_audio, "codec_name"), "aac");
  EXPECT_NEAR(std::stod(ffprobe_value(sbs_audio, "duration")), std::stod(ffprobe_value(sbs, "duration")), kFrame);

  const std::string tb = ffprobe_stream(fx().tb_mkv, "v:0", v);
  EXPECT_EQ(ffprobe_value(tb, "height"), "240");
  EXPECT_EQ(ffprobe_value(tb, "sample_aspect_ratio"), "1:1");
  EXPECT_EQ(ffmpeg_stereo3d(fx().tb_mkv), "top and bottom (inverted)");
  EXPECT_EQ(ffprobe_value(ffprobe_stream(fx().tb_mkv, "a:0", "codec_name"), "codec_name"), "vorbis");

  EXPECT_EQ(ffprobe_value(ffprobe_stream(fx().ana_mp4, "v:0", v), "pix_fmt"), "yuv444p");
  EXPECT_EQ(ffmpeg_stereo3d(fx().ana_mp4), "");
  EXPECT_EQ(ffprobe_value(ffprobe_stream(fx().ana_mp4, "a:0", "codec_name"), "codec_name"), "aac");
}

// MP4 carries the layout in the Spherical Video V2 st3d box as well, for
// players that read the container: left-first side by side and top-bottom
// get one (ffprobe's stream side data), the anaglyph and the right eye
// first (which st3d cannot say) none; GStreamer still decodes every frame.
TEST_F(Convert, Mp4St3dBoxSaysTheLayout) {
  if (!have_program("ffprobe") || !have_program("ffmpeg")) GTEST_SKIP() << "ffprobe not installed (apt-get install ffmpeg)";
  ASSERT_EQ(fx().sbs_run.status, 0);
  EXPECT_EQ(ffprobe_video(fx().sbs_mp4).stereo_side_data, "side by side");
  EXPECT_EQ(ffprobe_video(fx().ana_mp4).stereo_side_data, "");
  const std::string tb = fx().dir + "/tb-half.mp4", swapped = fx().dir + "/sbs-swapped.mp4";
  const ToolRun tb_run =
      run_convert({fx().aac_mp4, tb, "--layout", "top-bottom-half", "--preset", "ultrafast", "--quiet", "--force"});
  ASSERT_EQ(tb_run.status, 0) << tb_run.err;
  EXPECT_EQ(ffprobe_video(tb).stereo_side_data, "top and bottom");
  const ToolRun swapped_run =
      run_convert({fx().aac_mp4, swapped, "--swap-eyes", "--preset", "ultrafast", "--quiet", "--force"});
  ASSERT_EQ(swapped_run.status, 0) << swapped_run.err;
  EXPECT_EQ(ffprobe_video(swapped).stereo_side_data, "");
  EXPECT_EQ(ffmpeg_stereo3d(swapped), "side by side (inverted)") << "the SEI still says it";
  std::string error;
  EXPECT_EQ(gst_decoded_frames(tb, true, &error), read_back(fx().aac_mp4).video_frames) << error;
}

TEST_F(Convert, StartAndDurationConvertAPiece) {
  const std::string out = fx().dir + "/piece.mkv";
  g_remove(out.c_str());
  const ToolRun r = run_convert({fx().aac_mp4, out, "--start", "0.5", "--duration", "1", "--layout", "row-interleaved"});
  ASSERT_EQ(r.status, 0) << r.err;
  const ReadBack rb = read_back(out);
  EXPECT_EQ(rb.multiview_mode, "row-interleaved") << rb.video_caps;
  // Frames overlapping [0.5 s, 1.5 s): 0.48 ... 1.48.
  EXPECT_GE(rb.video_frames, 25);
  EXPECT_LE(rb.video_frames, 26);
  EXPECT_NEAR(rb.video_end - rb.video_start, 1.0, 2 * kFrame);
  ASSERT_GT(rb.audio_buffers, 0);
  EXPECT_NEAR(rb.audio_end - rb.audio_start, 1.0, 2 * kFrame);
  EXPECT_NEAR(rb.audio_start, rb.video_start, kFrame);
}

// H.265 with a piece: the flushing seek reaches x265enc before its first
// caps, which made it fail to initialise ("Can not initialize x265
// encoder") until the converter kept such flushes from it.
TEST_F(Convert, H265PieceConverts) {
  GstElementFactory *x265 = gst_element_factory_find("x265enc");
  if (!x265) GTEST_SKIP() << "x265enc is not installed";
  gst_object_unref(x265);
  const std::string out = fx().dir + "/piece-h265.mkv";
  g_remove(out.c_str());
  const ToolRun r = run_convert({fx().aac_mp4, out, "--codec", "h265", "--start", "0.5", "--duration", "1", "--quiet",
                                 "--preset", "ultrafast"});
  ASSERT_EQ(r.status, 0) << r.err;
  const ReadBack rb = read_back(out);
  EXPECT_NE(rb.video_caps.find("video/x-h265"), std::string::npos) << rb.video_caps;
  EXPECT_GE(rb.video_frames, 25);
  EXPECT_LE(rb.video_frames, 26);
}

TEST_F(Convert, MissingInputIsOneLineAndNoOutput) {
  const std::string out = fx().dir + "/never.mp4";
  g_remove(out.c_str());
  expect_clean_failure(run_convert({fx().dir + "/no-such-film.mp4", out}), out, "no-such-film.mp4", fx().dir);
}

TEST_F(Convert, ExistingOutputNeedsForce) {
  const std::string out = fx().dir + "/exists.mp4";
  { std::ofstream(out) << "keep me"; }
  const ToolRun r = run_convert({fx().aac_mp4, out});
  EXPECT_NE(r.status, 0);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("exists.mp4"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(out), "keep me");
  EXPECT_TRUE(files_containing(fx().dir, ".p3d-").empty());
  const ToolRun forced = run_convert({fx().aac_mp4, out, "--force", "--quiet"});
  ASSERT_EQ(forced.status, 0) << forced.err;
  EXPECT_EQ(read_back(out).video_frames, 50);
}

TEST_F(Convert, UsageErrorsAreOneLine) {
  for (const std::vector<std::string> &args :
       {std::vector<std::string>{fx().aac_mp4, fx().dir + "/x.avi"}, {fx().aac_mp4, fx().dir + "/x.mp4", "--bogus"},
        {fx().aac_mp4, fx().dir + "/x.mp4", "--layout", "sideways"}, {fx().aac_mp4},
        // Values that strtod or GStreamer would take but no user means.
        {fx().aac_mp4, fx().dir + "/x.mp4", "--preset", "fastest"},
        {fx().aac_mp4, fx().dir + "/x.mp4", "--max-disparity", ""},
        {fx().aac_mp4, fx().dir + "/x.mp4", "--convergence", "0x1"},
        {fx().aac_mp4, fx().dir + "/x.mp4", "--max-disparity", "nan"},
        {fx().aac_mp4, fx().dir + "/x.mp4", "--start", "0x1"},
        {fx().aac_mp4, fx().dir + "/x.mp4", "--start", "1:99"},
        {fx().aac_mp4, fx().dir + "/x.mp4", "--duration", "1e1"},
        {fx().aac_mp4, fx().dir + "/x.mp4", "--duration", "99999999999999999999"},
        {fx().aac_mp4, fx().dir + "/x.mp4", "--crf", "+5"}, {fx().aac_mp4, fx().dir + "/x.mp4", "--crf", " 5"},
        {fx().aac_mp4, fx().dir + "/x.mp4", "--codec", "h266"}}) {
    const ToolRun r = run_convert(args);
    EXPECT_EQ(r.status, 2) << args.back();
    EXPECT_EQ(line_count(r.err), 1) << r.err;
  }
  const ToolRun ext = run_convert({fx().aac_mp4, fx().dir + "/x.avi"});
  EXPECT_NE(ext.err.find("x.avi"), std::string::npos) << ext.err;
  EXPECT_FALSE(g_file_test((fx().dir + "/x.mp4").c_str(), G_FILE_TEST_EXISTS));
}

// The input under another name (./, a symbolic link) is still the input:
// --force must not replace it, nor may --depth-out replace the input or
// OUTPUT.
TEST_F(Convert, InputUnderAnotherNameIsRefused) {
  const std::string in = fx().dir + "/own.mp4", link = fx().dir + "/own-link.mp4";
  g_remove(in.c_str());
  g_remove(link.c_str());
  ASSERT_EQ(make_clip("videotestsrc num-buffers=5 ! video/x-raw,format=I420,width=64,height=48 ! x264enc ! mp4mux ! "
                      "filesink location=" + in),
            "");
  const std::vector<uint8_t> before = read_bytes(in);
  ASSERT_EQ(symlink("own.mp4", link.c_str()), 0);  // beside the link, whatever the folder is called
  const std::string dotted = fx().dir + "/./own.mp4";
  for (const std::vector<std::string> &args : {std::vector<std::string>{in, dotted, "--force"}, {link, in, "--force"}}) {
    const ToolRun r = run_convert(args);
    EXPECT_EQ(r.status, 2) << args[1];
    EXPECT_NE(r.err.find("is the input too"), std::string::npos) << r.err;
  }
  EXPECT_EQ(read_bytes(in), before);
  const std::string photo = fx().dir + "/own.png", out = fx().dir + "/own-sbs.png";
  ASSERT_TRUE(cv::imwrite(photo, cv::Mat(24, 32, CV_8UC3, cv::Scalar(40, 90, 160))));
  const ToolRun depth_in = run_convert({photo, out, "--depth-out", fx().dir + "/./own.png", "--force"});
  EXPECT_EQ(depth_in.status, 2) << depth_in.err;
  const ToolRun depth_out = run_convert({photo, out, "--depth-out", fx().dir + "/./own-sbs.png", "--force"});
  EXPECT_EQ(depth_out.status, 2) << depth_out.err;
  EXPECT_FALSE(g_file_test(out.c_str(), G_FILE_TEST_EXISTS));
}

// --start past the end: an error and no file, not an empty "success".
TEST_F(Convert, StartPastTheEndIsAnError) {
  const std::string out = fx().dir + "/past-end.mp4";
  g_remove(out.c_str());
  expect_clean_failure(run_convert({fx().aac_mp4, out, "--start", "30", "--quiet"}), out, "past the end", fx().dir);
}

// A file cut short converts what it holds and says that the end is
// missing, rather than reporting the full length as done.
TEST_F(Convert, TruncatedInputIsReported) {
  const std::string cut = fx().dir + "/cut.mkv", out = fx().dir + "/from-cut.mkv";
  g_remove(out.c_str());
  const std::vector<uint8_t> whole = read_bytes(fx().long_mkv);
  ASSERT_GT(whole.size(), 1000u);
  std::ofstream(cut, std::ios::binary).write(reinterpret_cast<const char *>(whole.data()),
                                             static_cast<std::streamsize>(whole.size() / 2));
  const ToolRun r = run_convert({cut, out, "--quiet", "--preset", "ultrafast"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("warning"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("truncated"), std::string::npos) << r.err;
  const ReadBack rb = read_back(out);
  EXPECT_GT(rb.video_frames, 0);
  EXPECT_LT(rb.video_frames, 500);
  // A complete slideshow (a frame every 2 s) is not "truncated": its last
  // frame starts 2 s before the end and lasts until it.
  const std::string slow = fx().dir + "/slideshow.mp4", slow_out = fx().dir + "/from-slideshow.mp4";
  g_remove(slow_out.c_str());
  ASSERT_EQ(make_clip("videotestsrc num-buffers=4 ! video/x-raw,format=I420,width=64,height=48,framerate=1/2 ! "
                      "x264enc ! mp4mux ! "
                      "filesink location=" + slow),
            "");
  const ToolRun complete = run_convert({slow, slow_out, "--quiet", "--preset", "ultrafast"});
  ASSERT_EQ(complete.status, 0) << complete.err;
  EXPECT_EQ(complete.err.find("warning"), std::string::npos) << complete.err;
}

namespace {

// A copy of `from` at `to` that ends 64 bytes into the first `tag` found
// after the first `after` (Matroska's first Cluster; a fast-start MP4's
// mdat, after its moov): every stream is declared, no frame is whole.
bool cut_into(const std::string &from, const std::string &to, const std::string &tag, const std::string &after = "") {
  const std::vector<uint8_t> whole = read_bytes(from);
  const std::string text(whole.begin(), whole.end());
  const size_t from_at = after.empty() ? 0 : text.find(after);
  const size_t at = from_at == std::string::npos ? std::string::npos : text.find(tag, from_at);
  if (at == std::string::npos || at + 64 > whole.size()) return false;
  std::ofstream(to, std::ios::binary).write(text.data(), static_cast<std::streamsize>(at + 64));
  return true;
}

const std::string kMkvCluster("\x1F\x43\xB6\x75", 4);

}  // namespace

// A file that yields no frame, converted without --start: the error says
// no frame could be decoded, and does not blame a --start never given.
TEST_F(Convert, NoFramesWithoutStartDoesNotBlameStart) {
  const std::string cut = fx().dir + "/no-frame.mkv", out = fx().dir + "/from-no-frame.mp4";
  ASSERT_TRUE(cut_into(fx().vorbis_mkv, cut, kMkvCluster));
  g_remove(out.c_str());
  const ToolRun r = run_convert({cut, out, "--quiet"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("no video frames"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("--start"), std::string::npos) << r.err;
  EXPECT_FALSE(g_file_test(out.c_str(), G_FILE_TEST_EXISTS));
}

// Streams declared but no frame whole (an MKV cut into its first cluster, a
// fast-start MP4 cut into its mdat): decodebin exposes the video pad with
// unfixed caps, which must not reach gst_video_info_from_caps (a
// GStreamer-CRITICAL). One clean line instead. And the plan line names no
// empty decoder: a photo's jpegdec or pngdec is an image decoder.
TEST_F(Convert, FramelessStreamFailsWithoutCritical) {
  const std::string mp4 = fx().dir + "/faststart.mp4", cut_mkv = fx().dir + "/frameless.mkv",
                    cut_mp4 = fx().dir + "/frameless.mp4", out = fx().dir + "/from-frameless.mp4";
  ASSERT_EQ(make_clip("videotestsrc num-buffers=10 ! video/x-raw,format=I420,width=160,height=120,framerate=25/1 ! "
                      "x264enc ! "
                      "mp4mux faststart=true ! filesink location=" + mp4),
            "");
  ASSERT_TRUE(cut_into(fx().vorbis_mkv, cut_mkv, kMkvCluster));
  ASSERT_TRUE(cut_into(mp4, cut_mp4, "mdat", "moov"));
  for (const std::string &in : {cut_mkv, cut_mp4}) {
    g_remove(out.c_str());
    const ToolRun r = run_convert({in, out, "--quiet"});
    EXPECT_EQ(r.err.find("CRITICAL"), std::string::npos) << r.err;
    expect_clean_failure(r, out, in, fx().dir);
  }
  const std::string photo = fx().dir + "/plan-photo.jpg", from_photo = fx().dir + "/from-plan-photo.mkv";
  ASSERT_TRUE(cv::imwrite(photo, cv::Mat(48, 64, CV_8UC3, cv::Scalar(40, 90, 160))));
  g_remove(from_photo.c_str());
  const ToolRun r = run_convert({photo, from_photo, "--preset", "ultrafast"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err.find("CRITICAL"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("decoder )"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("decoder jpegdec"), std::string::npos) << r.err;
}

// 4:2:0 encoders take even sizes only: an odd picture loses its last column
// and row, says so, and converts in every layout that encodes as 4:2:0.
TEST_F(Convert, OddSizeIsCroppedToEven) {
  const std::string in = fx().dir + "/odd-85x49.mkv";
  g_remove(in.c_str());
  ASSERT_EQ(make_clip("videotestsrc num-buffers=5 ! video/x-raw,width=85,height=49,framerate=25/1 ! jpegenc ! "
                      "matroskamux ! filesink location=" + in),
            "");
  for (const std::string layout : {"side-by-side-half", "top-bottom", "checkerboard"}) {
    const std::string out = fx().dir + "/odd-" + layout + ".mp4";
    g_remove(out.c_str());
    const ToolRun r = run_convert({in, out, "--layout", layout, "--preset", "ultrafast", "--processing", "cpu"});
    ASSERT_EQ(r.status, 0) << layout << ": " << r.err;
    EXPECT_NE(r.err.find("odd width or height"), std::string::npos) << r.err;
    const ReadBack rb = read_back(out);
    EXPECT_EQ(rb.video_frames, 5) << layout;
    EXPECT_EQ(rb.width, 84) << layout;
    EXPECT_EQ(rb.height, layout == "top-bottom" ? 96 : 48) << layout;
  }
}

namespace {

// `source` (the 160x120 test clip) tagged as rotated by 90 degrees, at
// `path`. A failed ffmpeg run fails the test; *skip says why where this
// ffmpeg writes no rotation tag (empty when it did).
void make_rotated_clip(const std::string &source, const std::string &path, std::string *skip) {
  g_remove(path.c_str());
  const std::string tag = "ffmpeg -v error -y -i '" + source + "' -c copy -metadata:s:v rotate=90 '" + path + "'";
  ASSERT_EQ(std::system(tag.c_str()), 0);
  // Newer ffmpeg releases tag rotations with -display_rotation instead.
  std::string probe;
  run_program({"ffprobe", "-v", "error", "-select_streams", "v:0", "-show_entries", "stream_side_data=rotation", "-of",
               "default=nw=1", path},
              &probe);
  if (probe.find("rotation=") == std::string::npos) *skip = "this ffmpeg wrote no rotation: " + probe;
}

}  // namespace

// A phone video stored sideways with a rotation tag comes out upright (the
// depth hypotheses describe the upright scene, and the output carries no
// rotation): 160x120 stored, rotated 90 degrees, converted to 120x160.
TEST_F(Convert, RotatedVideoIsTurnedUpright) {
  if (!have_program("ffmpeg")) GTEST_SKIP() << "no ffmpeg to tag a rotation";
  const std::string rotated = fx().dir + "/rotated-90.mp4", out = fx().dir + "/from-rotated.mp4";
  g_remove(out.c_str());
  std::string skip;
  ASSERT_NO_FATAL_FAILURE(make_rotated_clip(fx().aac_mp4, rotated, &skip));
  if (!skip.empty()) GTEST_SKIP() << skip;
  const ToolRun r = run_convert(
      {rotated, out, "--layout", "top-bottom-half", "--quiet", "--preset", "ultrafast", "--processing", "cpu"});
  ASSERT_EQ(r.status, 0) << r.err;
  const ReadBack rb = read_back(out);
  EXPECT_EQ(rb.width, 120);
  EXPECT_EQ(rb.height, 160);
  EXPECT_EQ(rb.video_frames, 50);
}

// On the GPU path NVDEC's CUDA frames cannot be turned upright (no CUDA
// rotation in GStreamer 1.22): the converter refuses the rotated video with
// the reason and the way out, and leaves no output, instead of converting
// it sideways. Where the decoder is not NVDEC the frames arrive in system
// memory and are turned upright as on the CPU path. Skipped without a GPU.
TEST_F(Convert, RotatedVideoOnCudaMemoryIsRefusedWithTheWayOut) {
  if (!have_program("ffmpeg")) GTEST_SKIP() << "no ffmpeg to tag a rotation";
  const std::string rotated = fx().dir + "/rotated-90-gpu.mp4", out = fx().dir + "/from-rotated-gpu.mp4";
  g_remove(out.c_str());
  std::string skip;
  ASSERT_NO_FATAL_FAILURE(make_rotated_clip(fx().aac_mp4, rotated, &skip));
  if (!skip.empty()) GTEST_SKIP() << skip;
  const ToolRun r = run_convert(
      {rotated, out, "--layout", "top-bottom-half", "--quiet", "--preset", "ultrafast", "--processing", "gpu"});
  if (r.err.find("no usable NVIDIA GPU") != std::string::npos) GTEST_SKIP() << "no GPU: " << r.err;
  if (r.err.find("orientation tag rotate-") == std::string::npos) {  // decoded into system memory: upright
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(read_back(out).height, 160);
    return;
  }
  // One line naming the file, exit 1, no output and no temporary file left.
  expect_clean_failure(r, out, "--processing cpu", fx().dir);
}

// Progress goes to stderr; a reader that closes it (a pipe into `head`)
// must neither kill the conversion (SIGPIPE) nor leave its temporary file.
TEST_F(Convert, ClosedStderrPipeDoesNotStopTheConversion) {
  const std::string out = fx().dir + "/piped.mp4", status = fx().dir + "/piped.status";
  g_remove(out.c_str());
  const std::string cmd = "{ '" + convert_program() + "' '" + fx().aac_mp4 + "' '" + out + "' 2>&1; echo $? > '" +
                          status + "'; } | true";
  // The converter must ignore SIGPIPE itself: it gets the default action
  // here whatever this process does with the signal (InterruptLeavesNoOutput
  // ignores it, and an ignored signal stays ignored across exec).
  const auto previous = std::signal(SIGPIPE, SIG_DFL);
  const int rc = std::system(cmd.c_str());
  std::signal(SIGPIPE, previous);
  ASSERT_EQ(rc, 0);
  EXPECT_EQ(slurp(status), "0\n");
  EXPECT_EQ(read_back(out).video_frames, 50);
  EXPECT_TRUE(files_containing(fx().dir, ".p3d-").empty());
}

TEST_F(Convert, UndecodableInputFailsCleanly) {
  const std::string bad = fx().dir + "/not-a-film.mp4", out = fx().dir + "/from-bad.mkv";
  { std::ofstream(bad) << "this is no video\n"; }
  g_remove(out.c_str());
  expect_clean_failure(run_convert({bad, out}), out, "not-a-film.mp4", fx().dir);
}

// Ctrl-C in the middle: the input comes through a FIFO that stops after
// half the file, so the conversion is certainly running when SIGINT comes.
// The FIFO is also the case of a film piped in from another program.
TEST_F(Convert, InterruptLeavesNoOutput) {
  const std::string dir = fx().dir + "/interrupt", fifo = dir + "/input.mkv", out = dir + "/out.mkv";
  g_mkdir_with_parents(dir.c_str(), 0755);
  g_remove(out.c_str());
  g_remove(fifo.c_str());
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const std::vector<uint8_t> bytes = read_bytes(fx().long_mkv);
  std::signal(SIGPIPE, SIG_IGN);  // the writer outlives the reader
  const std::string program = convert_program();
  const char *argv[] = {program.c_str(), fifo.c_str(), out.c_str(), nullptr};
  GPid pid;
  gint err_fd = -1;
  ASSERT_TRUE(g_spawn_async_with_pipes(nullptr, const_cast<gchar **>(argv), nullptr, G_SPAWN_DO_NOT_REAP_CHILD, nullptr,
                                       nullptr, &pid, nullptr, nullptr, &err_fd, nullptr));
  std::mutex err_lock;
  std::string err;
  std::thread reader([&]() {
    char buf[512];
    ssize_t n;
    while ((n = read(err_fd, buf, sizeof buf)) > 0) {
      std::lock_guard<std::mutex> l(err_lock);
      err.append(buf, static_cast<size_t>(n));
    }
  });
  std::string write_error;
  std::thread writer([&]() {
    const int fd = open(fifo.c_str(), O_WRONLY);
    if (fd < 0) {
      std::lock_guard<std::mutex> l(err_lock);
      write_error = std::string("open: ") + g_strerror(errno);
      return;
    }
    for (size_t at = 0, half = bytes.size() / 2; at < half;) {
      const ssize_t n = write(fd, bytes.data() + at, half - at);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        std::lock_guard<std::mutex> l(err_lock);
        write_error = "write at " + std::to_string(at) + " of " + std::to_string(half) + ": " + g_strerror(errno);
        break;
      }
      at += static_cast<size_t>(n);
    }
    // Keep the FIFO open: the reader waits for more, mid-stream.
    for (int i = 0; i < 300 && kill(pid, 0) == 0; ++i) g_usleep(100000);
    close(fd);
  });
  // A progress line: frames are being converted and muxed.
  bool running = false;
  for (int i = 0; i < 300 && !running; ++i) {
    {
      std::lock_guard<std::mutex> l(err_lock);
      running = err.find("frames/s") != std::string::npos;
    }
    if (!running) g_usleep(100000);
  }
  {
    std::lock_guard<std::mutex> l(err_lock);
    EXPECT_TRUE(running) << "no progress line in 30 s; the converter said: " << err << "; feeding it: " << write_error;
  }
  EXPECT_EQ(files_containing(dir, ".p3d-").size(), 1u) << "the temporary output is there while converting";
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  writer.join();
  reader.join();
  close(err_fd);
  g_spawn_close_pid(pid);
  // One reader from start to end: GStreamer's filesrc would open and close
  // the FIFO once to probe it, and a write in that gap fails with EPIPE.
  EXPECT_EQ(write_error, "") << "the converter let go of its input";
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGINT);
  EXPECT_FALSE(g_file_test(out.c_str(), G_FILE_TEST_EXISTS));
  EXPECT_TRUE(files_containing(dir, ".p3d-").empty());
  g_remove(fifo.c_str());
}

TEST_F(Convert, BenchmarkModeWritesBothRates) {
  const std::string jsonl = fx().dir + "/bench.jsonl";
  g_remove(jsonl.c_str());
  const ToolRun r = run_convert({"--benchmark", fx().aac_mp4, "--benchmark-out", jsonl, "--benchmark-runs", "1"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string lines = slurp(jsonl);
  EXPECT_NE(lines.find("\"mode\": \"decode-only\""), std::string::npos) << lines;
  EXPECT_NE(lines.find("\"mode\": \"convert-fakesink\""), std::string::npos) << lines;
  EXPECT_NE(lines.find("\"frames\": 50"), std::string::npos) << lines;
  EXPECT_NE(lines.find("\"ratio\""), std::string::npos) << lines;
  EXPECT_NE(r.out.find("% of decoding"), std::string::npos) << r.out;
}

// ---- photos ----

namespace {

// A landscape-stored photo that EXIF orientation 6 turns upright (portrait,
// 120x160): blocky texture for the depth regions, and a red square at the
// upright top-left corner (the stored bottom-left).
std::string make_rotated_jpeg(const std::string &dir) {
  cv::Mat stored(120, 160, CV_8UC3);
  cv::RNG rng(7);
  for (int y = 0; y < stored.rows; y += 8)
    for (int x = 0; x < stored.cols; x += 8)
      stored(cv::Rect(x, y, 8, 8)).setTo(cv::Scalar(rng.uniform(60, 200), rng.uniform(60, 200), rng.uniform(60, 200)));
  stored(cv::Rect(0, 120 - 32, 32, 32)).setTo(cv::Scalar(0, 0, 255));
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", stored, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95});
  const std::vector<uint8_t> with_exif = add_exif(jpeg, 6, "P3DTEST");
  const std::string path = dir + "/portrait-exif6.jpg";
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char *>(with_exif.data()),
                                              static_cast<std::streamsize>(with_exif.size()));
  return path;
}

}  // namespace

TEST_F(Convert, PhotoJpegAppliesExifOrientationAndKeepsExif) {
  const std::string in = make_rotated_jpeg(fx().dir), out = fx().dir + "/photo-sbs.jpg",
                    depth = fx().dir + "/photo-depth.png";
  g_remove(out.c_str());
  g_remove(depth.c_str());
  const ToolRun r = run_convert({in, out, "--depth-out", depth});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<uint8_t> bytes = read_bytes(out);
  EXPECT_EQ(jpeg_exif_orientation(bytes), 1) << "the pixels are upright now";
  EXPECT_TRUE(jpeg_exif_contains(bytes, "P3DTEST")) << "the photo's EXIF is kept";
  // Full side-by-side of the upright 120x160 picture; the same with and
  // without honouring the orientation tag (it says 1).
  const cv::Mat sbs = cv::imread(out, cv::IMREAD_COLOR), raw = cv::imread(out, cv::IMREAD_COLOR | cv::IMREAD_IGNORE_ORIENTATION);
  ASSERT_FALSE(sbs.empty());
  EXPECT_EQ(sbs.cols, 240);
  EXPECT_EQ(sbs.rows, 160);
  EXPECT_EQ(raw.size(), sbs.size());
  const cv::Scalar corner = cv::mean(sbs(cv::Rect(6, 6, 14, 14)));  // BGR, left view's top-left
  EXPECT_GT(corner[2], 150) << corner;
  EXPECT_LT(corner[1], 110) << corner;
  // The depth used: upright, 16-bit, far at the top and near at the bottom
  // (top-bottom hypothesis) rather than across.
  const cv::Mat d = cv::imread(depth, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(d.empty());
  EXPECT_EQ(d.type(), CV_16UC1);
  EXPECT_EQ(d.cols, 120);
  EXPECT_EQ(d.rows, 160);
  const double top = cv::mean(d.rowRange(0, 40))[0], bottom = cv::mean(d.rowRange(120, 160))[0];
  const double left = cv::mean(d.colRange(0, 30))[0], right = cv::mean(d.colRange(90, 120))[0];
  EXPECT_GT(bottom - top, 0.3 * 65535) << "top " << top << " bottom " << bottom;
  EXPECT_LT(std::abs(left - right), (bottom - top) / 3) << "left " << left << " right " << right;
}

// --depth-out is pseudo3ddepthout's picture of the depth pseudo3dwarp
// renders from: the converter's PNG holds, sample for sample, what the
// elements write for the same picture and options.
TEST_F(Convert, PhotoDepthOutIsWhatPseudo3dDepthOutWrites) {
  cv::Mat picture(120, 160, CV_8UC3);
  cv::RNG rng(11);
  for (int y = 0; y < picture.rows; y += 8)
    for (int x = 0; x < picture.cols; x += 8)
      picture(cv::Rect(x, y, 8, 8)).setTo(cv::Scalar(rng.uniform(30, 220), rng.uniform(30, 220), rng.uniform(30, 220)));
  const std::string in = fx().dir + "/blocks.png", out = fx().dir + "/blocks-sbs.png",
                    depth = fx().dir + "/blocks-depth.png", raw = fx().dir + "/blocks-depth.raw";
  ASSERT_TRUE(cv::imwrite(in, picture));
  g_remove(out.c_str());
  g_remove(depth.c_str());
  const ToolRun r = run_convert({in, out, "--depth-out", depth, "--hypothesis", "center-near", "--quiet"});
  ASSERT_EQ(r.status, 0) << r.err;
  ASSERT_EQ(run_to_eos("filesrc location=" + in + " ! pngdec ! videoconvert ! video/x-raw,format=RGBA ! "
                       "pseudo3ddepth hypothesis=center-near ! pseudo3dfilter ! pseudo3ddepthout ! "
                       "video/x-raw,format=GRAY16_LE ! filesink location=" + raw),
            "");
  std::vector<uint8_t> grey = read_bytes(raw);  // rows of 320 bytes: no padding
  ASSERT_EQ(grey.size(), 160u * 120u * 2u);
  const cv::Mat expected(120, 160, CV_16UC1, grey.data());  // little-endian samples, as the host's
  const cv::Mat got = cv::imread(depth, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(got.empty());
  ASSERT_EQ(got.type(), CV_16UC1);
  ASSERT_EQ(got.size(), expected.size());
  EXPECT_EQ(cv::norm(got, expected, cv::NORM_INF), 0.0);
  double lo = 0, hi = 0;
  cv::minMaxLoc(expected, &lo, &hi);
  EXPECT_GT(hi - lo, 0.2 * 65535) << "a depth map, not a flat picture";
}

// A photo in pillarbox bars: by default (crop-bars=auto) its depth map is
// 0 in the bars and the picture's alone between them; --crop-bars off
// estimates the whole frame, bars included; a value that is not a name is
// refused with the names.
TEST_F(Convert, PhotoInBarsCropBarsAutoAndOff) {
  cv::Mat picture(120, 192, CV_8UC3, cv::Scalar(0, 0, 0));
  cv::RNG rng(12);
  for (int y = 0; y < picture.rows; y += 8)
    for (int x = 32; x < 160; x += 8)
      picture(cv::Rect(x, y, 8, 8)).setTo(cv::Scalar(rng.uniform(60, 220), rng.uniform(60, 220), rng.uniform(60, 220)));
  const std::string in = fx().dir + "/pillar.png", out = fx().dir + "/pillar-sbs.png",
                    depth = fx().dir + "/pillar-depth.png";
  ASSERT_TRUE(cv::imwrite(in, picture));
  const cv::Rect left_bar(0, 0, 32, 120), right_bar(160, 0, 32, 120);
  for (const char *crop : {"auto", "off"}) {
    g_remove(out.c_str());
    g_remove(depth.c_str());
    const ToolRun r = run_convert({in, out, "--depth-out", depth, "--crop-bars", crop, "--quiet"});
    ASSERT_EQ(r.status, 0) << r.err;
    const cv::Mat got = cv::imread(depth, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(got.type(), CV_16UC1);
    const double bars = std::max(cv::norm(got(left_bar), cv::NORM_INF), cv::norm(got(right_bar), cv::NORM_INF));
    if (std::string(crop) == "auto")
      EXPECT_EQ(bars, 0.0) << "the bars' depth";
    else
      EXPECT_GT(bars, 0.0) << "the bars estimated as picture";
  }
  const ToolRun bad = run_convert({in, out, "--crop-bars", "sideways", "--force", "--quiet"});
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("auto"), std::string::npos) << bad.err;
}

TEST_F(Convert, PhotoMpoHoldsTwoDisparityImages) {
  const std::string in = make_rotated_jpeg(fx().dir), out = fx().dir + "/photo.mpo";
  g_remove(out.c_str());
  const ToolRun r = run_convert({in, out, "--quiet"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<uint8_t> file = read_bytes(out);
  const MpoIndex idx = parse_mpo(file);
  ASSERT_TRUE(idx.found) << idx.error;
  EXPECT_EQ(idx.number_of_images, 2u);
  ASSERT_EQ(idx.entries.size(), 2u);
  const uint32_t kDisparity = 0x020002, kRepresentative = 1u << 29;
  EXPECT_EQ(idx.entries[0].attribute & 0xFFFFFF, kDisparity);
  EXPECT_TRUE(idx.entries[0].attribute & kRepresentative);
  EXPECT_EQ(idx.entries[1].attribute & 0xFFFFFF, kDisparity);
  EXPECT_EQ(idx.entries[0].offset, 0u);
  EXPECT_EQ(idx.entries[0].size, idx.entries[1].file_offset);
  ASSERT_EQ(idx.entries[1].file_offset + idx.entries[1].size, file.size());
  std::vector<cv::Mat> views;
  for (const MpoEntry &e : idx.entries) {
    const std::vector<uint8_t> jpeg(file.begin() + e.file_offset, file.begin() + e.file_offset + e.size);
    ASSERT_GE(jpeg.size(), 4u);
    EXPECT_EQ(jpeg[0], 0xFF);
    EXPECT_EQ(jpeg[1], 0xD8);
    EXPECT_EQ(jpeg[jpeg.size() - 2], 0xFF);
    EXPECT_EQ(jpeg[jpeg.size() - 1], 0xD9);
    views.push_back(cv::imdecode(jpeg, cv::IMREAD_COLOR));
    ASSERT_FALSE(views.back().empty());
    EXPECT_EQ(views.back().cols, 120);
    EXPECT_EQ(views.back().rows, 160);
  }
  EXPECT_GT(cv::norm(views[0], views[1], cv::NORM_L1) / views[0].total(), 1.0) << "two different views";
  // The second image carries its own MPF attributes.
  const std::vector<uint8_t> second(file.begin() + idx.entries[1].file_offset, file.end());
  EXPECT_NE(std::string(second.begin(), second.begin() + std::min<size_t>(second.size(), 400)).find("MPF"),
            std::string::npos);
}

TEST_F(Convert, PhotoJpsIsTheCrossEyedPair) {
  const std::string in = make_rotated_jpeg(fx().dir), jps = fx().dir + "/photo.jps", mpo = fx().dir + "/photo-pair.mpo";
  g_remove(jps.c_str());
  g_remove(mpo.c_str());
  ASSERT_EQ(run_convert({in, jps, "--quiet"}).status, 0);
  ASSERT_EQ(run_convert({in, mpo, "--quiet"}).status, 0);
  const cv::Mat pair = cv::imread(jps, cv::IMREAD_COLOR);
  ASSERT_EQ(pair.cols, 240);
  ASSERT_EQ(pair.rows, 160);
  const std::vector<uint8_t> file = read_bytes(mpo);
  const MpoIndex idx = parse_mpo(file);
  ASSERT_EQ(idx.entries.size(), 2u);
  auto view = [&](int i) {
    const MpoEntry &e = idx.entries[i];
    return cv::imdecode(std::vector<uint8_t>(file.begin() + e.file_offset, file.begin() + e.file_offset + e.size),
                        cv::IMREAD_COLOR);
  };
  const cv::Mat left = view(0), right = view(1);
  const cv::Mat jps_left_half = pair.colRange(0, 120), jps_right_half = pair.colRange(120, 240);
  // Right view on the left half, left view on the right half.
  EXPECT_GT(cv::PSNR(jps_left_half, right), 30);
  EXPECT_GT(cv::PSNR(jps_right_half, left), 30);
  EXPECT_GT(cv::PSNR(jps_left_half, right), cv::PSNR(jps_left_half, left) + 1);
}

// JPEG holds full-range Y'CbCr: black stays 0 and white 255 (TV range
// would read back as 16 and 235, a washed-out picture), in every JPEG the
// converter writes (.jpg here; .jps and .mpo share the encoder).
// Depth from a file (--depth) for a photo: the same depth given as 8-bit
// near-white and as 16-bit near-dark (--depth-convention) gives the same
// picture, another depth another picture, and the estimate another again;
// the MPO output takes it too, upright, with the photo's EXIF. The depth
// is the upright picture's (120x160), as the photo is shown.
TEST_F(Convert, PhotoDepthFileFollowsItsConvention) {
  const std::string in = make_rotated_jpeg(fx().dir);
  cv::Mat near_white(160, 120, CV_8U), steps(160, 120, CV_8U);
  for (int y = 0; y < 160; ++y)
    for (int x = 0; x < 120; ++x) {
      near_white.at<uint8_t>(y, x) = static_cast<uint8_t>(x < 60 ? 40 + y : 230 - y);
      steps.at<uint8_t>(y, x) = static_cast<uint8_t>(x < 60 ? 255 : 0);
    }
  cv::Mat near_dark16;
  near_white.convertTo(near_dark16, CV_16U, -257.0, 65535.0);  // 65535 - 257 v: the same depth, dark = near
  const std::string d8 = fx().dir + "/depth8.png", d16 = fx().dir + "/depth16-dark.png",
                    dsteps = fx().dir + "/depth-steps.png";
  ASSERT_TRUE(cv::imwrite(d8, near_white) && cv::imwrite(d16, near_dark16) && cv::imwrite(dsteps, steps));
  auto convert = [&](const std::string &out, std::vector<std::string> extra) {
    std::vector<std::string> args = {in, out, "--quiet", "--force", "--layout", "side-by-side"};
    args.insert(args.end(), extra.begin(), extra.end());
    const ToolRun r = run_convert(args);
    EXPECT_EQ(r.status, 0) << out << ": " << r.err;
    return cv::imread(out, cv::IMREAD_COLOR);
  };
  const cv::Mat from8 = convert(fx().dir + "/depth8.png.out.png", {"--depth", d8});
  const cv::Mat from16 = convert(fx().dir + "/depth16.png.out.png", {"--depth", d16, "--depth-convention", "near-dark"});
  const cv::Mat from_steps = convert(fx().dir + "/steps.png.out.png", {"--depth", dsteps});
  const cv::Mat estimated = convert(fx().dir + "/estimated.png.out.png", {});
  ASSERT_FALSE(from8.empty() || from16.empty() || from_steps.empty() || estimated.empty());
  EXPECT_EQ(from8.cols, 240);
  EXPECT_EQ(from8.rows, 160);
  EXPECT_EQ(cv::norm(from8, from16, cv::NORM_INF), 0) << "the same depth in two conventions";
  EXPECT_GT(cv::norm(from8, from_steps, cv::NORM_L1), 0) << "another depth";
  EXPECT_GT(cv::norm(from8, estimated, cv::NORM_L1), 0) << "the file's depth, not the estimate";

  const std::string mpo = fx().dir + "/depth-file.mpo";
  const ToolRun r = run_convert({in, mpo, "--quiet", "--force", "--depth", d8});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<uint8_t> file = read_bytes(mpo);
  const MpoIndex idx = parse_mpo(file);
  ASSERT_TRUE(idx.found) << idx.error;
  ASSERT_EQ(idx.entries.size(), 2u);
  const std::vector<uint8_t> first(file.begin(), file.begin() + idx.entries[0].size);
  EXPECT_TRUE(jpeg_exif_contains(first, "P3DTEST")) << "the photo's EXIF is kept";
  const cv::Mat left = cv::imdecode(first, cv::IMREAD_COLOR);
  EXPECT_EQ(left.cols, 120);
  EXPECT_EQ(left.rows, 160);
}

// Depth from a file for a video: a depth video and a depth picture of the
// same flat depth give the same frames (within the encoder's loss), a
// picture of other depth other frames; every frame of the input is
// converted. Bad uses are refused with one line: a missing depth file, an
// estimate option with --depth, a depth option without it, --start with a
// depth video.
TEST_F(Convert, VideoDepthFileVideoOrPicture) {
  if (!have_program("ffmpeg")) GTEST_SKIP() << "no ffmpeg to read the frames back";
  const std::string in = fx().dir + "/smpte.mp4";
  ASSERT_EQ(make_clip("videotestsrc num-buffers=25 pattern=smpte ! video/x-raw,width=160,height=120,framerate=25/1 ! "
                      "x264enc speed-preset=ultrafast ! h264parse ! mp4mux ! filesink location=" + in),
            "");
  const std::string flat_video = fx().dir + "/depth-flat.mkv";
  ASSERT_EQ(make_clip("videotestsrc num-buffers=25 pattern=solid-color foreground-color=0xff202020 ! "
                      "video/x-raw,width=80,height=60,framerate=25/1 ! x264enc speed-preset=ultrafast ! h264parse ! "
                      "matroskamux ! filesink location=" + flat_video),
            "");
  // Frames as grey bytes, through a file (ffmpeg's raw output).
  auto grey_frames = [&](const std::string &video, const std::vector<std::string> &limit) {
    const std::string raw = video + ".gray";
    std::vector<std::string> args = {"ffmpeg", "-v", "error", "-y", "-i", video};
    args.insert(args.end(), limit.begin(), limit.end());
    args.insert(args.end(), {"-f", "rawvideo", "-pix_fmt", "gray", raw});
    std::string out;
    EXPECT_EQ(run_program(args, &out), 0) << video;
    return read_bytes(raw);
  };
  // The first picture of the depth video as GStreamer decodes it to grey
  // (ffmpeg's grey differs: it keeps the limited-range values).
  const std::string flat_png = fx().dir + "/depth-flat.png", steps_png = fx().dir + "/depth-steps-video.png";
  ASSERT_EQ(make_clip("filesrc location=" + flat_video + " ! decodebin ! videoconvert ! video/x-raw,format=GRAY8 ! "
                      "pngenc snapshot=true ! filesink location=" + flat_png),
            "");
  cv::Mat steps(60, 80, CV_8U, cv::Scalar(0));
  steps(cv::Rect(0, 0, 40, 60)).setTo(255);
  ASSERT_TRUE(cv::imwrite(steps_png, steps));
  auto frames = [&](const std::string &depth) {
    const std::string out = fx().dir + "/with-" + depth.substr(depth.find_last_of('/') + 1) + ".mkv";
    const ToolRun r = run_convert({in, out, "--depth", depth, "--preset", "ultrafast", "--quiet", "--force"});
    EXPECT_EQ(r.status, 0) << depth << ": " << r.err;
    return grey_frames(out, {});
  };
  const std::vector<uint8_t> from_video = frames(flat_video), from_picture = frames(flat_png), from_steps = frames(steps_png);
  ASSERT_EQ(from_video.size(), 25u * 160u * 120u) << "every frame converted";
  ASSERT_EQ(from_picture.size(), from_video.size());
  ASSERT_EQ(from_steps.size(), from_video.size());
  auto mean_diff = [](const std::vector<uint8_t> &a, const std::vector<uint8_t> &b) {
    double sum = 0;
    for (size_t i = 0; i < a.size(); ++i) sum += std::abs(static_cast<int>(a[i]) - b[i]);
    return sum / a.size();
  };
  EXPECT_LT(mean_diff(from_video, from_picture), 0.5) << "the video's depth is the picture's";
  EXPECT_GT(mean_diff(from_steps, from_picture), 2.0) << "another depth moves the picture";

  for (const auto &args : std::vector<std::vector<std::string>>{
           {in, fx().dir + "/x.mkv", "--depth", fx().dir + "/none.png"},
           {in, fx().dir + "/x.mkv", "--depth", flat_png, "--hypothesis", "flat"},
           {in, fx().dir + "/x.mkv", "--depth-convention", "near-dark"},
           {in, fx().dir + "/x.mkv", "--depth", flat_video, "--start", "0.2"}}) {
    const ToolRun r = run_convert(args);
    EXPECT_NE(r.status, 0) << args[3];
    EXPECT_EQ(line_count(r.err), 1) << r.err;
  }
}

TEST_F(Convert, PhotoJpegKeepsFullRange) {
  cv::Mat bw(64, 128, CV_8UC3, cv::Scalar(0, 0, 0));
  bw.colRange(64, 128).setTo(cv::Scalar(255, 255, 255));
  const std::string in = fx().dir + "/black-white.png", out = fx().dir + "/black-white.jpg";
  ASSERT_TRUE(cv::imwrite(in, bw));
  g_remove(out.c_str());
  // Flat depth: both views are the picture, so the halves keep their values.
  const ToolRun r = run_convert({in, out, "--layout", "left", "--hypothesis", "flat", "--quiet"});
  ASSERT_EQ(r.status, 0) << r.err;
  const cv::Mat m = cv::imread(out, cv::IMREAD_GRAYSCALE);
  ASSERT_EQ(m.size(), bw.size());
  EXPECT_LE(cv::mean(m(cv::Rect(8, 8, 40, 48)))[0], 2.0);
  EXPECT_GE(cv::mean(m(cv::Rect(80, 8, 40, 48)))[0], 253.0);
}

TEST_F(Convert, PhotoPngIsThePackedPicture) {
  const std::string in = make_rotated_jpeg(fx().dir), out = fx().dir + "/photo-tb.png";
  g_remove(out.c_str());
  ASSERT_EQ(run_convert({in, out, "--layout", "top-bottom-half", "--quiet"}).status, 0);
  const cv::Mat m = cv::imread(out, cv::IMREAD_UNCHANGED);
  EXPECT_EQ(m.cols, 120);
  EXPECT_EQ(m.rows, 160);
}

// A JPEG cut short decodes without a word from jpegdec, which ends the data
// itself and leaves the missing rows grey: the converter refuses it, naming
// the file and why, for photo and video outputs alike. The whole file (a
// progressive JPEG: several scans) converts.
TEST_F(Convert, TruncatedJpegIsRefused) {
  cv::Mat noise(240, 320, CV_8UC3);
  cv::randu(noise, cv::Scalar::all(0), cv::Scalar::all(255));
  std::vector<uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", noise, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95, cv::IMWRITE_JPEG_PROGRESSIVE, 1}));
  const std::string whole = fx().dir + "/whole.jpg", cut = fx().dir + "/half.jpg";
  std::ofstream(whole, std::ios::binary).write(reinterpret_cast<const char *>(jpeg.data()),
                                               static_cast<std::streamsize>(jpeg.size()));
  std::ofstream(cut, std::ios::binary).write(reinterpret_cast<const char *>(jpeg.data()),
                                             static_cast<std::streamsize>(jpeg.size() / 2));
  const std::string from_whole = fx().dir + "/from-whole.png";
  g_remove(from_whole.c_str());
  const ToolRun ok = run_convert({whole, from_whole, "--quiet"});
  EXPECT_EQ(ok.status, 0) << ok.err;
  for (const std::string &out : {fx().dir + "/from-half.png", fx().dir + "/from-half.mp4"}) {
    g_remove(out.c_str());
    const ToolRun r = run_convert({cut, out, "--quiet"});
    expect_clean_failure(r, out, "truncated", fx().dir);
    EXPECT_NE(r.err.find("half.jpg"), std::string::npos) << r.err;
  }
}

namespace {

// ffprobe's count of decoded video frames (-1 if none given) and the
// file's duration in seconds (-1 if none).
struct FfprobeCount {
  int frames = -1;
  double duration = -1;
};
FfprobeCount ffprobe_count(const std::string &path) {
  std::string text;
  run_program({"ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
               "stream=nb_read_frames:format=duration", "-of", "default=nw=1", path},
              &text);
  FfprobeCount c;
  const std::string frames = ffprobe_value(text, "nb_read_frames"), duration = ffprobe_value(text, "duration");
  if (!frames.empty() && frames.find_first_not_of("0123456789") == std::string::npos) c.frames = std::stoi(frames);
  if (!duration.empty() && duration != "N/A") c.duration = std::stod(duration);
  return c;
}

}  // namespace

// A photo into a video file is a still video: 5 s at 25 frames/s by
// default, --duration for another length, so that players (and ffprobe)
// see frames and a duration; a lone frame of no duration played as nothing.
TEST_F(Convert, PhotoIntoVideoIsAStillVideo) {
  if (!have_program("ffprobe")) GTEST_SKIP() << "ffprobe not installed (apt-get install ffmpeg)";
  const std::string photo = fx().dir + "/still.png", mp4 = fx().dir + "/still.mp4", mkv = fx().dir + "/still.mkv";
  ASSERT_TRUE(cv::imwrite(photo, cv::Mat(96, 128, CV_8UC3, cv::Scalar(40, 90, 160))));
  g_remove(mp4.c_str());
  g_remove(mkv.c_str());
  const ToolRun r = run_convert({photo, mp4, "--preset", "ultrafast"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("5 s still video"), std::string::npos) << r.err;
  const FfprobeCount m = ffprobe_count(mp4);
  EXPECT_EQ(m.frames, 125);
  EXPECT_NEAR(m.duration, 5.0, 0.1);
  const ToolRun k = run_convert({photo, mkv, "--preset", "ultrafast", "--duration", "2", "--quiet"});
  ASSERT_EQ(k.status, 0) << k.err;
  const FfprobeCount c = ffprobe_count(mkv);
  EXPECT_EQ(c.frames, 50);
  EXPECT_NEAR(c.duration, 2.0, 0.1);
}

namespace {

uint32_t crc32(const std::string &bytes) {
  uint32_t c = 0xFFFFFFFFu;
  for (const char ch : bytes) {
    c ^= static_cast<uint8_t>(ch);
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return ~c;
}

std::string be32(uint32_t v) {
  return {static_cast<char>(v >> 24), static_cast<char>(v >> 16 & 0xFF), static_cast<char>(v >> 8 & 0xFF),
          static_cast<char>(v & 0xFF)};
}

// A PNG of a few bytes whose header declares width x height (8-bit RGB)
// and whose image data are cut off: refused from its header, it gives the
// size limit; decoded, it would fail otherwise (or take gigabytes).
void write_png_declaring(const std::string &path, uint32_t width, uint32_t height) {
  auto chunk = [](const std::string &type, const std::string &data) {
    return be32(static_cast<uint32_t>(data.size())) + type + data + be32(crc32(type + data));
  };
  const std::string ihdr = be32(width) + be32(height) + std::string("\x08\x02\x00\x00\x00", 5);
  const std::string png = std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) +
                          chunk("IDAT", std::string("\x78\x9c\x01\x00\x00\xff\xff", 7)) + chunk("IEND", "");
  std::ofstream(path, std::ios::binary) << png;
}

}  // namespace

// The 3D stages take at most 8192 pixels a side: larger pictures and videos
// are refused from their header (the parsers' caps), before anything is
// decoded, with a line naming the size and the limit: a 9000x10 PNG to a
// photo, a PNG declaring 20000x20000 to a video, an 8200x64 H.264 clip; a
// YUV4MPEG file, whose size only its decoder's caps give, too.
TEST_F(Convert, OversizedPicturesAreRefusedNamingTheLimit) {
  const std::string wide = fx().dir + "/wide-9000x10.png", huge = fx().dir + "/huge-20000.png",
                    clip = fx().dir + "/wide-8200x64.mkv", y4m = fx().dir + "/wide-9000x10.y4m";
  ASSERT_TRUE(cv::imwrite(wide, cv::Mat(10, 9000, CV_8UC3, cv::Scalar(40, 90, 160))));
  write_png_declaring(huge, 20000, 20000);
  ASSERT_EQ(make_clip("videotestsrc num-buffers=3 ! video/x-raw,format=I420,width=8200,height=64,framerate=25/1 ! "
                      "x264enc "
                      "speed-preset=ultrafast ! h264parse ! matroskamux ! filesink location=" + clip),
            "");
  ASSERT_EQ(make_clip("videotestsrc num-buffers=2 ! video/x-raw,format=I420,width=9000,height=10,framerate=25/1 ! "
                      "y4menc ! filesink location=" + y4m),
            "");
  const struct {
    std::string in, out, size;
  } cases[] = {{wide, fx().dir + "/from-wide.png", "9000x10"},
               {wide, fx().dir + "/from-wide.mp4", "9000x10"},
               {huge, fx().dir + "/from-huge.jpg", "20000x20000"},
               {huge, fx().dir + "/from-huge.mkv", "20000x20000"},
               {clip, fx().dir + "/from-wide-clip.mp4", "8200x64"},
               {y4m, fx().dir + "/from-y4m.mp4", "9000x10"},
               {y4m, fx().dir + "/from-y4m.png", "9000x10"}};
  for (const auto &c : cases) {
    g_remove(c.out.c_str());
    const ToolRun r = run_convert({c.in, c.out, "--quiet"});
    expect_clean_failure(r, c.out, "8192", fx().dir);
    EXPECT_NE(r.err.find(c.size), std::string::npos) << r.err;
  }
}

// `--` ends the options: what follows are file names, even one that starts
// with '-'; without it such a name is an unknown option.
TEST_F(Convert, DoubleDashEndsTheOptions) {
  const std::string dir = fx().dir + "/dash";
  g_mkdir_with_parents(dir.c_str(), 0755);
  const std::vector<uint8_t> clip = read_bytes(fx().aac_mp4);
  std::ofstream(dir + "/-x.mp4", std::ios::binary).write(reinterpret_cast<const char *>(clip.data()),
                                                        static_cast<std::streamsize>(clip.size()));
  g_remove((dir + "/-y.mkv").c_str());
  const ToolRun plain = run_convert_in(dir, {"-x.mp4", "out.mkv"});
  EXPECT_EQ(plain.status, 2) << plain.err;
  EXPECT_NE(plain.err.find("unknown option '-x.mp4'"), std::string::npos) << plain.err;
  const ToolRun r = run_convert_in(dir, {"--quiet", "--preset", "ultrafast", "--", "-x.mp4", "-y.mkv"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(read_back(dir + "/-y.mkv").video_frames, 50);
  const ToolRun help = run_convert({"--help"});
  EXPECT_NE(help.out.find("\n  --  "), std::string::npos) << help.out;
}

// The converter deinitialises GStreamer on its way out, so that the leaks
// tracer checks what is still alive then, and finds nothing: after a video
// and a photo conversion (with and without its depth map), and after a
// failed one.
TEST_F(Convert, LeaksTracerFindsNothingAlive) {
  const std::vector<std::string> env = {"GST_TRACERS=leaks", "GST_DEBUG=GST_TRACER:7,leaks:5", "GST_DEBUG_NO_COLOR=1"};
  const std::string out = fx().dir + "/leaks.mkv", photo = fx().dir + "/leaks.png",
                    photo_out = fx().dir + "/leaks.mpo", depth_out = fx().dir + "/leaks-depth.png",
                    bad = fx().dir + "/leaks-no-film.mp4", bad_out = fx().dir + "/leaks-failed.mkv";
  ASSERT_TRUE(cv::imwrite(photo, cv::Mat(48, 64, CV_8UC3, cv::Scalar(40, 90, 160))));
  { std::ofstream(bad) << "this is no video\n"; }
  g_remove(out.c_str());
  g_remove(photo_out.c_str());
  g_remove(depth_out.c_str());
  const ToolRun video = run_convert_in("", {fx().aac_mp4, out, "--quiet", "--preset", "ultrafast"}, env);
  const ToolRun still = run_convert_in("", {photo, photo_out, "--quiet"}, env);
  const ToolRun with_depth = run_convert_in("", {photo, photo_out, "--depth-out", depth_out, "--force", "--quiet"}, env);
  const ToolRun failed = run_convert_in("", {bad, bad_out, "--quiet"}, env);
  ASSERT_EQ(video.status, 0) << video.err;
  ASSERT_EQ(still.status, 0) << still.err;
  ASSERT_EQ(with_depth.status, 0) << with_depth.err;
  EXPECT_EQ(failed.status, 1) << failed.err;
  for (const ToolRun *r : {&video, &still, &with_depth, &failed}) {
    EXPECT_NE(r->err.find("checking for leaks"), std::string::npos) << "the leaks tracer never checked";
    EXPECT_EQ(r->err.find("Leaks detected"), std::string::npos) << r->err;
    // A leaked object is logged as "object-alive, type-name=(string)Gst...";
    // the record's format string ("...(string)%s") is no leak.
    size_t at = 0;
    while ((at = r->err.find("object-alive, type-name=(string)", at)) != std::string::npos) {
      at += 32;
      EXPECT_EQ(r->err.compare(at, 2, "%s"), 0) << r->err.substr(at, 200);
    }
  }
}
