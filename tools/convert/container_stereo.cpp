#include "container_stereo.h"

#include "mkv_stereo.h"
#include "mp4_stereo.h"

namespace p3d::convert {

bool set_mkv_container_stereo_mode(const std::string &path, const std::string &layout, bool right_first,
                                   std::string *error) {
  MkvStereoLayout mkv = MkvStereoLayout::Mono;
  mkv_stereo_layout_from_name(layout, &mkv);
  return mkv_set_stereo_mode(path, mkv, right_first, error);
}

namespace {

// The st3d mode of a layout; false where st3d has none.
bool mp4_stereo_mode(const std::string &layout, bool right_first, Mp4StereoMode *mode) {
  MkvStereoLayout arrangement = MkvStereoLayout::Mono;
  mkv_stereo_layout_from_name(layout, &arrangement);
  if (right_first) return false;
  if (arrangement == MkvStereoLayout::SideBySide) *mode = Mp4StereoMode::LeftRight;
  else if (arrangement == MkvStereoLayout::TopBottom) *mode = Mp4StereoMode::TopBottom;
  else return false;
  return true;
}

}  // namespace

bool mp4_stereo_box_says(const std::string &layout, bool right_first) {
  Mp4StereoMode mode;
  return mp4_stereo_mode(layout, right_first, &mode);
}

bool set_mp4_stereo_box(const std::string &path, const std::string &layout, bool right_first, std::string *error) {
  Mp4StereoMode mode;
  return !mp4_stereo_mode(layout, right_first, &mode) || mp4_set_stereo_box(path, mode, error);
}

}  // namespace p3d::convert
