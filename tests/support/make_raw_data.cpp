// Build-time helper: decodes the test images (OpenCV) into .p3draw dumps
// for the GPU suites; for a video (.avi), its first kVideoFrames frames as
// "<name>.frame-NNN.p3draw". A missing input is skipped (the test then
// reports it).
//   make_raw_data OUTDIR IMAGE|VIDEO...
#include <cstdio>
#include <string>

#include <glib/gstdio.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "test_data.h"

int main(int argc, char **argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: make_raw_data OUTDIR IMAGE...\n");
    return 2;
  }
  const std::string out = argv[1];
  g_mkdir_with_parents(out.c_str(), 0755);
  constexpr int kVideoFrames = 12;  // a short sequence: the payload carried to a GPU machine stays small
  for (int i = 2; i < argc; ++i) {
    const std::string in = argv[i];
    const std::string name = in.substr(in.find_last_of('/') + 1);
    if (in.size() > 4 && in.compare(in.size() - 4, 4, ".avi") == 0) {
      cv::VideoCapture video(in);
      cv::Mat frame;
      for (int k = 0; k < kVideoFrames && video.read(frame); ++k) {
        char suffix[32];
        std::snprintf(suffix, sizeof suffix, ".frame-%03d.p3draw", k);
        if (!p3d::test::write_raw_image(out + "/" + name + suffix, frame)) return 1;
      }
      continue;
    }
    const cv::Mat m = cv::imread(in, cv::IMREAD_UNCHANGED);
    if (m.empty()) {
      std::fprintf(stderr, "make_raw_data: skipping %s (not readable)\n", in.c_str());
      continue;
    }
    if (!p3d::test::write_raw_image(out + "/" + name + ".p3draw", m)) return 1;
  }
  return 0;
}
