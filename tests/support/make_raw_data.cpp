// Build-time helper: decodes the test images (OpenCV) into .p3draw dumps
// for the GPU suites. A missing input is skipped (the test then reports it).
//   make_raw_data OUTDIR IMAGE...
#include <cstdio>
#include <string>

#include <glib/gstdio.h>
#include <opencv2/imgcodecs.hpp>

#include "test_data.h"

int main(int argc, char **argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: make_raw_data OUTDIR IMAGE...\n");
    return 2;
  }
  const std::string out = argv[1];
  g_mkdir_with_parents(out.c_str(), 0755);
  for (int i = 2; i < argc; ++i) {
    const std::string in = argv[i];
    const cv::Mat m = cv::imread(in, cv::IMREAD_UNCHANGED);
    if (m.empty()) {
      std::fprintf(stderr, "make_raw_data: skipping %s (not readable)\n", in.c_str());
      continue;
    }
    const std::string name = in.substr(in.find_last_of('/') + 1);
    if (!p3d::test::write_raw_image(out + "/" + name + ".p3draw", m)) return 1;
  }
  return 0;
}
