// The names tables of the public enums (common/enum_name.h): every value
// has one nick that leads back to it, no nick is shared within a table,
// and values outside a table are refused by the range checks that read it.
#include <gtest/gtest.h>

#include <iterator>
#include <set>
#include <string>

#include "bilateral.h"
#include "depth_estimate.h"
#include "depth_grey.h"
#include "pack.h"
#include "warp.h"

using namespace p3d;

namespace {

template <typename E, std::size_t N>
void expect_round_trip(const EnumName<E> (&table)[N], const char *what) {
  std::set<std::string> nicks;
  for (const EnumName<E> &e : table) {
    EXPECT_TRUE(nicks.insert(e.nick).second) << what << ": nick " << e.nick << " twice";
    EXPECT_STREQ(enum_nick(table, e.value), e.nick) << what;
    E back{};
    ASSERT_TRUE(enum_from_nick(table, e.nick, &back)) << what << ": " << e.nick;
    EXPECT_EQ(back, e.value) << what << ": " << e.nick;
    EXPECT_TRUE(enum_valid(table, e.value)) << what;
    EXPECT_GT(std::string(e.description).size(), 3u) << what << ": " << e.nick;
  }
  E none{};
  EXPECT_FALSE(enum_from_nick(table, "no-such-name", &none)) << what;
  EXPECT_FALSE(enum_valid(table, static_cast<E>(N))) << what;
  EXPECT_FALSE(enum_valid(table, static_cast<E>(-1))) << what;
  EXPECT_STREQ(enum_nick(table, static_cast<E>(N)), "?") << what;
  EXPECT_EQ(enum_nicks(table, "|").find("||"), std::string::npos) << what;
}

}  // namespace

TEST(EnumNames, EveryTableRoundTrips) {
  expect_round_trip(kHypothesisNames, "hypothesis");
  expect_round_trip(kFilterModeNames, "filter mode");
  expect_round_trip(kDepthConventionNames, "depth convention");
  expect_round_trip(kStereoViewNames, "view");
  expect_round_trip(kHoleFillNames, "fill");
  expect_round_trip(kPackLayoutNames, "layout");
  expect_round_trip(kGlassesNames, "glasses");
  expect_round_trip(kAnaglyphMethodNames, "anaglyph method");
  expect_round_trip(kStereoInputNames, "input layout");
}

// pack_args_valid reads the tables: one value past each is refused.
TEST(EnumNames, PackArgumentsOutsideTheTablesAreRefused) {
  // A 16 x 4 side-by-side pair (views of 8 x 4) packed side by side again.
  alignas(4) uint8_t in_pixels[16 * 4 * 4] = {}, out_pixels[16 * 4 * 4] = {};
  FrameView in, out;
  in.format = out.format = PixelFormat::RGBA;
  in.width = out.width = 16;
  in.height = out.height = 4;
  in.plane[0] = in_pixels;
  out.plane[0] = out_pixels;
  in.stride[0] = out.stride[0] = 16 * 4;
  PackParams p;
  p.layout = PackLayout::SideBySide;
  p.input = StereoInput::SideBySide;
  ASSERT_TRUE(pack_args_valid(p, in, out));
  for (int which = 0; which < 4; ++which) {
    PackParams q = p;
    if (which == 0) q.layout = static_cast<PackLayout>(std::size(kPackLayoutNames));
    if (which == 1) q.glasses = static_cast<AnaglyphGlasses>(std::size(kGlassesNames));
    if (which == 2) q.method = static_cast<AnaglyphMethod>(std::size(kAnaglyphMethodNames));
    if (which == 3) q.input = static_cast<StereoInput>(std::size(kStereoInputNames));
    EXPECT_FALSE(pack_args_valid(q, in, out)) << which;
  }
}
