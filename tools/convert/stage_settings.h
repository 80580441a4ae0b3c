// The plugin properties the command line sets, checked against the plugin
// itself (so the converter never drifts from the elements' names, ranges and
// defaults) and applied either to the pseudo3dconvert bin (video) or to the
// stage element that owns each property (photos).
#pragma once

#include <gst/gst.h>

#include <string>

#include "options.h"

namespace p3d::convert {

// Loads the pseudo3d plugin (from the build folder when it is not
// installed); false with *error when it cannot be found.
bool ensure_plugin(std::string *error);

// Checks every value in o.stage_values against the property's pspec on
// pseudo3dconvert: enum nicks, numeric ranges. One-line *error naming the
// option and the accepted values.
bool check_stage_values(const Options &o, std::string *error);

// The layout in use: the one given, else side-by-side-half for video and
// side-by-side for photos (the plugin's own default is anaglyph).
std::string effective_layout(const Options &o);
bool right_view_first(const Options &o);  // --swap-eyes

// Sets the given values plus the layout on a pseudo3dconvert bin, or on a
// pseudo3dwarp that packs (the names it lacks are left out).
void apply_to_bin(const Options &o, GstElement *bin);
// Sets each value on the stage element of the matching factory
// (pseudo3ddepth, pseudo3dwarp, pseudo3dpack...) among `stages`;
// `layout` and `swap_eyes` override the command line's.
void apply_to_stages(const Options &o, GstElement *const *stages, int n_stages, const std::string &layout,
                     bool swap_eyes);

}  // namespace p3d::convert
