// read_image_file() for the GPU suites: no codecs, only the .p3draw dumps
// that make_raw_data writes at build time are read (see test_data.h).
#include "test_data.h"

namespace p3d::test {
cv::Mat read_image_file(const std::string &) { return cv::Mat(); }
}  // namespace p3d::test
