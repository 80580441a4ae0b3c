#include "mkv_stereo_hook.h"

namespace p3d::convert {

bool set_mkv_container_stereo_mode(const std::string &path, const std::string &layout, bool right_first,
                                   std::string *error) {
  // See the header: the lead replaces this body with the call to
  // p3d::mkv_set_stereo_mode once tools/support/mkv_stereo.h is merged.
  (void)path;
  (void)layout;
  (void)right_first;
  (void)error;
  return true;
}

}  // namespace p3d::convert
