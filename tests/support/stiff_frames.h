// Stiff test frames shared by the CPU and GPU extreme-case suites: exact
// black/white patterns (1-pixel stripes, checkerboards), a constant colour
// and pure noise, in any supported format.
#pragma once

#include <cstdint>

#include "host_frame.h"

namespace p3d::test {

enum class Pattern { Black, White, Colour, VStripes, HStripes, Checker1, Checker8, Noise };
inline constexpr Pattern kAllPatterns[] = {Pattern::Black,    Pattern::White,    Pattern::Colour,   Pattern::VStripes,
                                           Pattern::HStripes, Pattern::Checker1, Pattern::Checker8, Pattern::Noise};

const char *pattern_name(Pattern p);
// Grey level (0 or 255) of pixel (x, y) of a black/white pattern.
int pattern_level(Pattern p, int x, int y);
// Black/white patterns: exact greys (R'=G'=B', alpha 255; or Y' 16/235 with
// neutral chroma, so a YUV checkerboard has the full contrast in Y' and none
// in chroma). Colour: a constant non-grey frame with no channel at 255 (so
// never the hole colour), built directly so 8K stays cheap. Noise: every
// byte random (alpha and chroma included). Rows carry 3 bytes of padding.
HostFrame make_frame(Pattern p, PixelFormat f, int w, int h, uint32_t seed = 1);

}  // namespace p3d::test
