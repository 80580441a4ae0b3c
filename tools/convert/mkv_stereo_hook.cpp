#include "mkv_stereo_hook.h"

#include "mkv_stereo.h"

namespace p3d::convert {

namespace {

MkvStereoLayout mkv_layout(const std::string &layout) {
  if (layout == "side-by-side" || layout == "side-by-side-half") return MkvStereoLayout::SideBySide;
  if (layout == "top-bottom" || layout == "top-bottom-half") return MkvStereoLayout::TopBottom;
  if (layout == "row-interleaved") return MkvStereoLayout::RowInterleaved;
  if (layout == "column-interleaved") return MkvStereoLayout::ColumnInterleaved;
  if (layout == "checkerboard") return MkvStereoLayout::Checkerboard;
  return MkvStereoLayout::Mono;  // anaglyph, left, right
}

}  // namespace

bool set_mkv_container_stereo_mode(const std::string &path, const std::string &layout, bool right_first,
                                   std::string *error) {
  return mkv_set_stereo_mode(path, mkv_layout(layout), right_first, error);
}

}  // namespace p3d::convert
