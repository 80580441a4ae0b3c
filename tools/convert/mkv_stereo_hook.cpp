#include "mkv_stereo_hook.h"

#include "mkv_stereo.h"

namespace p3d::convert {

bool set_mkv_container_stereo_mode(const std::string &path, const std::string &layout, bool right_first,
                                   std::string *error) {
  MkvStereoLayout mkv = MkvStereoLayout::Mono;
  mkv_stereo_layout_from_name(layout, &mkv);
  return mkv_set_stereo_mode(path, mkv, right_first, error);
}

}  // namespace p3d::convert
