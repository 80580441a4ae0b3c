// read_image_file() through OpenCV's codecs (CPU suites).
#include <opencv2/imgcodecs.hpp>

#include "test_data.h"

namespace p3d::test {
cv::Mat read_image_file(const std::string &path) { return cv::imread(path, cv::IMREAD_UNCHANGED); }
}  // namespace p3d::test
