// Properties changed while frames flow: every property documented as
// changeable while playing, set from a second thread hundreds of times, with
// no error and every frame consistent with its caps; geometry-changing
// properties (pack's layout, swap-eyes and input layout, depth's method)
// checked frame by frame against the reference for the caps each frame came
// with; a caps query answered with one layout even when it changes halfway;
// READY-only properties refused while playing; caps renegotiation mid
// stream (size and format).
#include <gst/check/gstharness.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "depth_estimate.h"
#include "element_helpers.h"
#include "pack.h"
#include "processing_latency.h"
#include "test_data.h"

using namespace p3d;
using namespace p3d::test;

namespace {

// A second thread that sets properties until stopped.
class PropertyChanger {
 public:
  template <typename F>
  explicit PropertyChanger(F &&change) : thread_([this, change] {
      std::mt19937 rng(12345);
      while (!stop_.load()) {
        change(rng);
        ++changes_;
        std::this_thread::sleep_for(std::chrono::microseconds(150));
      }
    }) {}
  ~PropertyChanger() { finish(); }
  int finish() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    return changes_;
  }
  int changes() const { return changes_; }

 private:
  std::atomic<bool> stop_{false};
  std::atomic<int> changes_{0};
  std::thread thread_;
};

// A random valid value of a property (extremes often).
void set_random(GObject *obj, GParamSpec *p, std::mt19937 &rng) {
  GValue v = G_VALUE_INIT;
  g_value_init(&v, p->value_type);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double t = u(rng) < 0.2 ? 0.0 : (u(rng) < 0.25 ? 1.0 : u(rng));
  if (G_IS_PARAM_SPEC_ENUM(p)) {
    GEnumClass *e = G_PARAM_SPEC_ENUM(p)->enum_class;
    g_value_set_enum(&v, e->values[rng() % e->n_values].value);
  } else if (G_IS_PARAM_SPEC_INT(p)) {
    const auto *i = G_PARAM_SPEC_INT(p);
    g_value_set_int(&v, i->minimum + static_cast<int>(t * (static_cast<double>(i->maximum) - i->minimum)));
  } else if (G_IS_PARAM_SPEC_FLOAT(p)) {
    const auto *f = G_PARAM_SPEC_FLOAT(p);
    g_value_set_float(&v, static_cast<float>(f->minimum + t * (static_cast<double>(f->maximum) - f->minimum)));
  } else if (G_IS_PARAM_SPEC_BOOLEAN(p)) {
    g_value_set_boolean(&v, rng() % 2);
  }
  g_object_set_property(obj, p->name, &v);
  g_value_unset(&v);
}

// The element's properties documented as changeable while playing.
std::vector<GParamSpec *> live_properties(GstElement *e) {
  guint n = 0;
  GParamSpec **specs = g_object_class_list_properties(G_OBJECT_GET_CLASS(e), &n);
  std::vector<GParamSpec *> live;
  for (guint i = 0; i < n; ++i)
    if ((specs[i]->flags & GST_PARAM_MUTABLE_PLAYING) && (specs[i]->flags & G_PARAM_WRITABLE)) live.push_back(specs[i]);
  g_free(specs);
  return live;
}

GstElement *find(GstHarness *h, const char *factory) {
  if (g_str_equal(GST_OBJECT_NAME(gst_element_get_factory(h->element)), factory))
    return GST_ELEMENT(gst_object_ref(h->element));
  GstIterator *it = gst_bin_iterate_recurse(GST_BIN(h->element));
  GValue v = G_VALUE_INIT;
  GstElement *found = nullptr;
  while (!found && gst_iterator_next(it, &v) == GST_ITERATOR_OK) {
    GstElement *e = GST_ELEMENT(g_value_get_object(&v));
    if (g_str_equal(GST_OBJECT_NAME(gst_element_get_factory(e)), factory)) found = GST_ELEMENT(gst_object_ref(e));
    g_value_reset(&v);
  }
  g_value_unset(&v);
  gst_iterator_free(it);
  return found;
}

// The frames a harness's output buffer belongs to: size and format from the caps.
GstVideoInfo output_info(GstHarness *h) {
  GstVideoInfo info;
  gst_video_info_init(&info);
  GstCaps *caps = gst_pad_get_current_caps(h->sinkpad);
  if (caps) gst_video_info_from_caps(&info, caps);
  if (caps) gst_caps_unref(caps);
  return info;
}

HostFrame textured(PixelFormat f, int w, int h, uint32_t seed) {
  cv::Mat bgr(h, w, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(bgr, cv::RNG::UNIFORM, 0, 255);
  bgr(cv::Rect(0, 0, w, h / 2)).setTo(cv::Scalar(30, 160, 220));
  return HostFrame::from_bgr(bgr, f);
}

}  // namespace

// Every live property of every element, changed from a second thread while
// frames are pushed through the whole chain: every frame comes out, sized as
// its caps say, and nothing posts an error or a warning.
TEST(LiveProperties, EveryLivePropertyFromASecondThread) {
  const char *chains[] = {"pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp ! pseudo3dpack",
                          "pseudo3dconvert processing=cpu"};
  const char *factories[][4] = {{"pseudo3ddepth", "pseudo3dfilter", "pseudo3dwarp", "pseudo3dpack"},
                                {"pseudo3dconvert", nullptr, nullptr, nullptr}};
  for (int c = 0; c < 2; ++c) {
    GstHarness *h = gst_harness_new_parse(chains[c]);
    BusMessages bus(h->element);
    gst_harness_set_src_caps_str(h, raw_caps(PixelFormat::I420, 64, 48).c_str());
    std::vector<std::pair<GstElement *, GParamSpec *>> targets;
    for (const char *f : factories[c]) {
      if (!f) continue;
      GstElement *e = find(h, f);
      ASSERT_NE(e, nullptr) << f;
      for (GParamSpec *p : live_properties(e)) {
        // The warp's own layout makes it pack its pair: a mono or one-view
        // frame, which the pseudo3dpack after it rightly refuses (the bin
        // has no pack after its warp, and takes layout itself).
        if (c == 0 && g_str_equal(f, "pseudo3dwarp") && g_str_equal(p->name, "layout")) continue;
        targets.emplace_back(e, p);
      }
    }
    ASSERT_GT(targets.size(), 10u);
    std::vector<HostFrame> frames;
    for (uint32_t s = 0; s < 4; ++s) frames.push_back(textured(PixelFormat::I420, 64, 48, s));
    int pushed = 0;
    {
      PropertyChanger changer([&](std::mt19937 &rng) {
        auto &t = targets[rng() % targets.size()];
        set_random(G_OBJECT(t.first), t.second, rng);
      });
      for (; pushed < 400 || changer.changes() < 300; ++pushed) {
        GstBuffer *out = gst_harness_push_and_pull(h, buffer_from_frame(frames[pushed % frames.size()]));
        if (!out) {
          std::string errors;
          for (const std::string &e : bus.take(GST_MESSAGE_ERROR)) errors += e + "\n";
          for (const std::string &w : bus.take(GST_MESSAGE_WARNING)) errors += "warning: " + w + "\n";
          FAIL() << chains[c] << ": no output for frame " << pushed << "; errors:\n" << errors;
        }
        const GstVideoInfo info = output_info(h);
        EXPECT_GE(gst_buffer_get_size(out), GST_VIDEO_INFO_SIZE(&info)) << "frame " << pushed;
        EXPECT_GT(GST_VIDEO_INFO_WIDTH(&info), 0);
        gst_buffer_unref(out);
        if (HasFailure()) break;
      }
      const int changes = changer.finish();
      EXPECT_GE(changes, 200) << "the second thread should have made hundreds of changes";
    }
    EXPECT_EQ(bus.take(GST_MESSAGE_ERROR), std::vector<std::string>{}) << chains[c];
    EXPECT_EQ(bus.take(GST_MESSAGE_WARNING), std::vector<std::string>{}) << chains[c];
    std::vector<GstElement *> unique;
    for (auto &t : targets)
      if (std::find(unique.begin(), unique.end(), t.first) == unique.end()) unique.push_back(t.first);
    for (GstElement *e : unique) gst_object_unref(e);
    gst_harness_teardown(h);
  }
}

// pseudo3dpack while layout, swap-eyes and input-layout change from another
// thread: each frame is exactly the conversion its own caps describe.
TEST(LiveProperties, PackFramesMatchTheirCaps) {
  const int w = 12, h = 8;
  HostFrame pair(PixelFormat::RGBA, 2 * w, h);
  pair.fill_random(77);
  GstHarness *hx = gst_harness_new_parse("pseudo3dpack glasses=green-magenta anaglyph-method=color");
  GstElement *pack = find(hx, "pseudo3dpack");
  BusMessages bus(hx->element);
  gst_harness_set_src_caps_str(hx, raw_caps(PixelFormat::RGBA, 2 * w, h, ",multiview-mode=side-by-side").c_str());
  GEnumClass *layouts = G_ENUM_CLASS(g_type_class_ref(g_type_from_name("GstPseudo3DLayout")));
  int checked = 0;
  {
    PropertyChanger changer([&](std::mt19937 &rng) {
      switch (rng() % 3) {
        case 0: g_object_set(pack, "layout", layouts->values[rng() % layouts->n_values].value, NULL); break;
        case 1: g_object_set(pack, "swap-eyes", (gboolean)(rng() % 2), NULL); break;
        default: gst_util_set_object_arg(G_OBJECT(pack), "input-layout", rng() % 2 ? "from-caps" : "side-by-side");
      }
    });
    for (int i = 0; i < 300 || changer.changes() < 300; ++i) {
      GstBuffer *out = gst_harness_push_and_pull(hx, buffer_from_frame(pair));
      ASSERT_NE(out, nullptr) << "frame " << i;
      GstCaps *caps = gst_pad_get_current_caps(hx->sinkpad);
      GstVideoInfo info;
      ASSERT_TRUE(gst_video_info_from_caps(&info, caps));
      // What the caps say the frame is.
      PackParams p;
      p.glasses = AnaglyphGlasses::GreenMagenta;
      p.method = AnaglyphMethod::Color;
      const GstVideoMultiviewMode mode = GST_VIDEO_INFO_MULTIVIEW_MODE(&info);
      const guint flags = GST_VIDEO_INFO_MULTIVIEW_FLAGS(&info);
      const bool half = flags & GST_VIDEO_MULTIVIEW_FLAGS_HALF_ASPECT;
      p.swap_eyes = flags & GST_VIDEO_MULTIVIEW_FLAGS_RIGHT_VIEW_FIRST;
      bool known = true;
      switch (mode) {
        case GST_VIDEO_MULTIVIEW_MODE_MONO: p.layout = PackLayout::Anaglyph; break;
        case GST_VIDEO_MULTIVIEW_MODE_LEFT: p.layout = PackLayout::Left; break;
        case GST_VIDEO_MULTIVIEW_MODE_RIGHT: p.layout = PackLayout::Right; break;
        case GST_VIDEO_MULTIVIEW_MODE_SIDE_BY_SIDE:
          p.layout = half ? PackLayout::SideBySideHalf : PackLayout::SideBySide;
          break;
        case GST_VIDEO_MULTIVIEW_MODE_TOP_BOTTOM: p.layout = half ? PackLayout::TopBottomHalf : PackLayout::TopBottom; break;
        case GST_VIDEO_MULTIVIEW_MODE_ROW_INTERLEAVED: p.layout = PackLayout::RowInterleaved; break;
        case GST_VIDEO_MULTIVIEW_MODE_COLUMN_INTERLEAVED: p.layout = PackLayout::ColumnInterleaved; break;
        case GST_VIDEO_MULTIVIEW_MODE_CHECKERBOARD: p.layout = PackLayout::Checkerboard; break;
        default: known = false;
      }
      ASSERT_TRUE(known) << "frame " << i << " mode " << mode;
      // An anaglyph's swap-eyes is not in the caps: both are possible, one must match.
      int ow = 0, oh = 0;
      pack_size(p.layout, w, h, &ow, &oh);
      ASSERT_EQ(GST_VIDEO_INFO_WIDTH(&info), ow) << "frame " << i;
      ASSERT_EQ(GST_VIDEO_INFO_HEIGHT(&info), oh) << "frame " << i;
      const cv::Mat got = buffer_to_bgra(out, caps);
      bool match = false;
      for (bool swap : {p.swap_eyes, !p.swap_eyes}) {
        if (swap != p.swap_eyes && p.layout != PackLayout::Anaglyph) continue;
        PackParams q = p;
        q.swap_eyes = swap;
        HostFrame want(PixelFormat::RGBA, ow, oh);
        pack_cpu(q, pair.view(), want.view());
        match = match || cv::norm(got, want.to_bgra(), cv::NORM_INF) == 0;
      }
      EXPECT_TRUE(match) << "frame " << i << " is not the conversion its caps describe";
      ++checked;
      gst_caps_unref(caps);
      gst_buffer_unref(out);
      if (HasFailure()) break;
    }
    EXPECT_GE(changer.finish(), 300);
  }
  EXPECT_GE(checked, 300);
  EXPECT_EQ(bus.take(GST_MESSAGE_ERROR), std::vector<std::string>{});
  g_type_class_unref(layouts);
  gst_object_unref(pack);
  gst_harness_teardown(hx);
}

// A caps query is one negotiation: pseudo3dpack transforms the filter
// towards its source, asks downstream, and transforms the answer back. The
// layout changes (from another thread in real use; here from a probe, each
// time downstream has answered) between the two transforms: both must still use
// one layout, or the answer is empty and upstream (pseudo3dwarp in a chain
// whose layout changes while playing) fails to negotiate, as it did under
// AddressSanitizer's timing.
TEST(LiveProperties, CapsQueryUsesOneLayoutThroughout) {
  const int w = 12, h = 8;
  GstHarness *hx = gst_harness_new_parse("pseudo3dpack layout=left");
  GstElement *pack = find(hx, "pseudo3dpack");
  GstPad *src = gst_element_get_static_pad(pack, "src");
  struct Flip {
    GstElement *pack;
    int flips = 0;
  } flip{pack};
  gst_pad_add_probe(
      src, static_cast<GstPadProbeType>(GST_PAD_PROBE_TYPE_QUERY_DOWNSTREAM | GST_PAD_PROBE_TYPE_PULL),
      [](GstPad *, GstPadProbeInfo *info, gpointer data) {
        auto *f = static_cast<Flip *>(data);
        if (GST_QUERY_TYPE(GST_PAD_PROBE_INFO_QUERY(info)) == GST_QUERY_CAPS)
          gst_util_set_object_arg(G_OBJECT(f->pack), "layout", f->flips++ % 2 ? "left" : "side-by-side");
        return GST_PAD_PROBE_OK;
      },
      &flip, nullptr);
  GstCaps *filter = gst_caps_from_string(raw_caps(PixelFormat::RGBA, 2 * w, h, ",multiview-mode=side-by-side").c_str());
  for (int i = 0; i < 4; ++i) {
    GstCaps *caps = gst_pad_peer_query_caps(hx->srcpad, filter);
    ASSERT_NE(caps, nullptr);
    EXPECT_FALSE(gst_caps_is_empty(caps)) << "query " << i << ": the two transforms used different layouts";
    EXPECT_TRUE(gst_caps_can_intersect(caps, filter)) << "query " << i << ": " << gst_caps_to_string(caps);
    gst_caps_unref(caps);
  }
  EXPECT_EQ(flip.flips, 4) << "downstream answered once per query, and the layout changed each time";
  gst_caps_unref(filter);
  gst_object_unref(src);
  gst_object_unref(pack);
  gst_harness_teardown(hx);
}

// pseudo3ddepth while method switches between edges and rgbd: an rgbd frame
// is the colour half with the grey half as depth, an edges frame is the
// whole input with depth of its size; never anything in between.
TEST(LiveProperties, DepthMethodFramesMatchTheirCaps) {
  const int w = 16, h = 8;
  for (PixelFormat fmt : {PixelFormat::RGBA, PixelFormat::I420}) {
    cv::Mat bgr(h, 2 * w, CV_8UC3);
    cv::randu(bgr, 0, 256);
    const HostFrame rgbd = HostFrame::from_bgr(bgr, fmt);
    GstHarness *hx = gst_harness_new_parse("pseudo3ddepth");
    GstElement *depth_el = find(hx, "pseudo3ddepth");
    BusMessages bus(hx->element);
    gst_harness_set_src_caps_str(hx, raw_caps(fmt, 2 * w, h).c_str());
    int seen_rgbd = 0, seen_edges = 0;
    {
      PropertyChanger changer([&](std::mt19937 &rng) {
        gst_util_set_object_arg(G_OBJECT(depth_el), "method", rng() % 2 ? "rgbd" : "edges");
      });
      for (int i = 0; i < 300 || changer.changes() < 300; ++i) {
        GstBuffer *out = gst_harness_push_and_pull(hx, buffer_from_frame(rgbd));
        ASSERT_NE(out, nullptr);
        GstCaps *caps = gst_pad_get_current_caps(hx->sinkpad);
        const cv::Mat frame = buffer_to_bgra(out, caps), depth = buffer_depth(out);
        const cv::Mat input = rgbd.to_bgra(yuv_to_rgb_params(0.299, 0.114, false));
        if (frame.cols == w) {
          ++seen_rgbd;
          EXPECT_EQ(cv::norm(frame, input(cv::Rect(0, 0, w, h)), cv::NORM_INF), 0) << "frame " << i;
          ASSERT_EQ(depth.size(), cv::Size(w, h));
          HostFrame grey(fmt, w, h);
          cv::Mat want(h, w, CV_32FC1);
          FrameView half = rgbd.view();
          half.width = w;
          if (is_packed_rgb(fmt)) {
            half.plane[0] += 4 * w;
          } else {
            half.plane[0] += w;
            half.plane[1] += w / 2;
            half.plane[2] += w / 2;
          }
          depth_from_grey_cpu(half, yuv_to_rgb_params(0.299, 0.114, false), depth_view_of(want));
          EXPECT_EQ(cv::norm(depth, want, cv::NORM_INF), 0) << "frame " << i;
        } else {
          ++seen_edges;
          EXPECT_EQ(frame.cols, 2 * w) << "frame " << i;
          EXPECT_EQ(cv::norm(frame, input, cv::NORM_INF), 0) << "frame " << i;
          EXPECT_EQ(depth.size(), cv::Size(2 * w, h)) << "frame " << i;
        }
        gst_caps_unref(caps);
        gst_buffer_unref(out);
        if (HasFailure()) break;
      }
    }
    EXPECT_GT(seen_rgbd, 10);
    EXPECT_GT(seen_edges, 10);
    EXPECT_EQ(bus.take(GST_MESSAGE_ERROR), std::vector<std::string>{});
    gst_object_unref(depth_el);
    gst_harness_teardown(hx);
  }
}

// A live value the running stream cannot take is refused, not fatal:
// method=rgbd on a 321-wide I420 stream (no colour half of that width) and
// input-layout=top-bottom on a pair of odd height. Frames keep coming, the
// same as before the set, one warning says why, the property reads back
// the value in force, and a value that fits is still taken afterwards.
struct LiveRefusal {
  const char *launch, *caps;
  int width, height;
  const char *property, *refused, *kept, *reason;
  const char *later;  // a value that fits, set after the refusal
};

TEST(LiveProperties, ValueTheStreamCannotTakeIsRefusedWithAWarning) {
  const LiveRefusal cases[] = {
      {"pseudo3ddepth", "", 321, 8, "method", "rgbd", "edges", "twice as wide", nullptr},
      {"pseudo3dpack layout=side-by-side-half", ",multiview-mode=side-by-side", 24, 7, "input-layout", "top-bottom",
       "from-caps", "even height", "side-by-side"},
  };
  for (const LiveRefusal &c : cases) {
    SCOPED_TRACE(c.launch);
    const PixelFormat fmt = std::string(c.property) == "method" ? PixelFormat::I420 : PixelFormat::RGBA;
    HostFrame input(fmt, c.width, c.height);
    input.fill_random(9);
    GstHarness *hx = gst_harness_new_parse(c.launch);
    const std::string factory = std::string(c.launch).substr(0, std::string(c.launch).find(' '));
    GstElement *el = find(hx, factory.c_str());
    BusMessages bus(hx->element);
    gst_harness_set_src_caps_str(hx, raw_caps(fmt, c.width, c.height, c.caps).c_str());
    auto push_pull = [&](std::string *caps_out) {
      GstBuffer *out = gst_harness_push_and_pull(hx, buffer_from_frame(input));
      if (!out) return cv::Mat();
      GstCaps *caps = gst_pad_get_current_caps(hx->sinkpad);
      *caps_out = current_caps(hx->sinkpad);
      cv::Mat m = buffer_to_bgra(out, caps).clone();
      gst_caps_unref(caps);
      gst_buffer_unref(out);
      return m;
    };
    std::string caps_before, caps_after;
    const cv::Mat before = push_pull(&caps_before);
    ASSERT_FALSE(before.empty());
    gst_util_set_object_arg(G_OBJECT(el), c.property, c.refused);
    for (int i = 0; i < 3; ++i) {
      const cv::Mat after = push_pull(&caps_after);
      ASSERT_FALSE(after.empty()) << "frame " << i << " after the set did not come out";
      EXPECT_EQ(caps_after, caps_before);
      EXPECT_EQ(cv::norm(after, before, cv::NORM_INF), 0) << "frame " << i;
    }
    EXPECT_EQ(bus.take(GST_MESSAGE_ERROR), std::vector<std::string>{});
    const std::vector<std::string> warnings = bus.take(GST_MESSAGE_WARNING);
    ASSERT_EQ(warnings.size(), 1u) << "one warning, not one a frame";
    EXPECT_NE(warnings[0].find(c.reason), std::string::npos) << warnings[0];
    EXPECT_NE(warnings[0].find("refused"), std::string::npos) << warnings[0];
    GValue v = G_VALUE_INIT;
    g_value_init(&v, G_PARAM_SPEC_VALUE_TYPE(g_object_class_find_property(G_OBJECT_GET_CLASS(el), c.property)));
    g_object_get_property(G_OBJECT(el), c.property, &v);
    EXPECT_STREQ(g_enum_get_value(G_ENUM_CLASS(g_type_class_peek(G_VALUE_TYPE(&v))), g_value_get_enum(&v))->value_nick,
                 c.kept);
    g_value_unset(&v);
    if (c.later) {
      gst_util_set_object_arg(G_OBJECT(el), c.property, c.later);
      ASSERT_FALSE(push_pull(&caps_after).empty());
      EXPECT_TRUE(bus.take(GST_MESSAGE_WARNING).empty());
      EXPECT_EQ(bus.take(GST_MESSAGE_ERROR), std::vector<std::string>{});
    }
    gst_object_unref(el);
    gst_harness_teardown(hx);
  }
}

// A layout change racing a flushing seek: the renegotiation before the next
// buffer meets the flush (here made certain: the flush starts while the
// element asks downstream for its caps, so the new caps then cannot leave
// the flushing source pad). That is the seek's doing, not a failure: no "not
// negotiated" warning reaches the application, and after the flush the
// change is negotiated and applied.
TEST(LiveProperties, LayoutChangeRacingAFlushPostsNoWarning) {
  const int w = 12, h = 8;
  struct Case {
    const char *launch, *factory, *caps;
    int width;  // of the input frame
  };
  for (const Case &c : {Case{"pseudo3dpack layout=side-by-side", "pseudo3dpack", ",multiview-mode=side-by-side", 2 * w},
                        Case{"pseudo3ddepth ! pseudo3dwarp", "pseudo3dwarp", "", w}}) {
    SCOPED_TRACE(c.factory);
    HostFrame pair(PixelFormat::RGBA, c.width, h);
    pair.fill_random(21);
    GstHarness *hx = gst_harness_new_parse(c.launch);
    GstElement *el = find(hx, c.factory);
    BusMessages bus(hx->element);
    gst_harness_set_src_caps_str(hx, raw_caps(PixelFormat::RGBA, c.width, h, c.caps).c_str());
    GstBuffer *first = gst_harness_push_and_pull(hx, buffer_from_frame(pair));
    ASSERT_NE(first, nullptr);
    gst_buffer_unref(first);

    // GstBaseTransform asks the peer pad itself for its caps: the probe sits there.
    GstPad *src = gst_element_get_static_pad(el, "src"), *sink = gst_element_get_static_pad(el, "sink");
    GstPad *peer = gst_pad_get_peer(src);
    struct Race {
      GstPad *sink;
      bool flushed = false;
    } race{sink};
    const gulong probe = gst_pad_add_probe(
        peer, static_cast<GstPadProbeType>(GST_PAD_PROBE_TYPE_QUERY_DOWNSTREAM | GST_PAD_PROBE_TYPE_PUSH),
        [](GstPad *, GstPadProbeInfo *info, gpointer data) {
          auto *r = static_cast<Race *>(data);
          if (GST_QUERY_TYPE(GST_PAD_PROBE_INFO_QUERY(info)) == GST_QUERY_CAPS && !r->flushed) {
            r->flushed = true;
            gst_pad_send_event(r->sink, gst_event_new_flush_start());
          }
          return GST_PAD_PROBE_OK;
        },
        &race, nullptr);
    g_object_set(el, "layout", PackLayout::TopBottom, NULL);
    EXPECT_NE(gst_harness_push(hx, buffer_from_frame(pair)), GST_FLOW_OK) << "the buffer meets the flush";
    EXPECT_TRUE(race.flushed);
    gst_pad_remove_probe(peer, probe);
    gst_harness_push_event(hx, gst_event_new_flush_stop(TRUE));
    GstSegment segment;
    gst_segment_init(&segment, GST_FORMAT_TIME);
    gst_harness_push_event(hx, gst_event_new_segment(&segment));

    GstBuffer *out = gst_harness_push_and_pull(hx, buffer_from_frame(pair));
    ASSERT_NE(out, nullptr);
    gst_buffer_unref(out);
    GstCaps *caps = gst_pad_get_current_caps(hx->sinkpad);
    GstVideoInfo info;
    ASSERT_TRUE(gst_video_info_from_caps(&info, caps));
    EXPECT_EQ(GST_VIDEO_INFO_MULTIVIEW_MODE(&info), GST_VIDEO_MULTIVIEW_MODE_TOP_BOTTOM) << "the change applies after";
    gst_caps_unref(caps);
    EXPECT_EQ(bus.take(GST_MESSAGE_WARNING), std::vector<std::string>{});
    EXPECT_EQ(bus.take(GST_MESSAGE_ERROR), std::vector<std::string>{});
    gst_object_unref(peer);
    gst_object_unref(src);
    gst_object_unref(sink);
    gst_object_unref(el);
    gst_harness_teardown(hx);
  }
}

// processing and cuda-device-id may only change in NULL or READY: while
// playing the change is refused with a warning, and the value stays.
TEST(LiveProperties, ReadyOnlyPropertiesAreRefusedWhilePlaying) {
  for (const char *factory : {"pseudo3dwarp", "pseudo3dconvert"}) {
    GstHarness *h = gst_harness_new(factory);
    BusMessages bus(h->element);
    ASSERT_EQ(GST_STATE(h->element), GST_STATE_PLAYING);
    gst_util_set_object_arg(G_OBJECT(h->element), "processing", "gpu");
    g_object_set(h->element, "cuda-device-id", 3, NULL);
    gint device = 0;
    GValue v = G_VALUE_INIT;
    g_value_init(&v, g_type_from_name("GstPseudo3DProcessing"));
    g_object_get_property(G_OBJECT(h->element), "processing", &v);
    EXPECT_EQ(g_value_get_enum(&v), 0) << factory << ": processing stays auto";
    g_value_unset(&v);
    g_object_get(h->element, "cuda-device-id", &device, NULL);
    EXPECT_EQ(device, -1) << factory;
    const std::vector<std::string> warnings = bus.take(GST_MESSAGE_WARNING);
    ASSERT_EQ(warnings.size(), 2u) << factory;
    EXPECT_NE(warnings[0].find("'processing' cannot be changed"), std::string::npos) << warnings[0];
    // In READY the same change is taken.
    gst_element_set_state(h->element, GST_STATE_READY);
    g_object_set(h->element, "cuda-device-id", 3, NULL);
    g_object_get(h->element, "cuda-device-id", &device, NULL);
    EXPECT_EQ(device, 3) << factory;
    gst_harness_teardown(h);
  }
}

// New caps mid-stream (another size, another format): the first frame after
// each change is what a fresh element gives for it (the history does not
// carry over), and the output caps follow.
TEST(Renegotiation, SizeAndFormatMidStream) {
  const char *chain = "pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp ! pseudo3dpack layout=side-by-side-half";
  struct Step {
    PixelFormat f;
    int w, h;
  };
  const Step steps[] = {{PixelFormat::RGBA, 64, 48}, {PixelFormat::NV12, 80, 40}, {PixelFormat::NV12, 64, 48},
                        {PixelFormat::BGRx, 64, 48}};
  GstHarness *h = gst_harness_new_parse(chain);
  for (const Step &s : steps) {
    gst_harness_set_src_caps_str(h, raw_caps(s.f, s.w, s.h).c_str());
    const HostFrame a = textured(s.f, s.w, s.h, 1), b = textured(s.f, s.w, s.h, 2);
    GstBuffer *first = gst_harness_push_and_pull(h, buffer_from_frame(a));
    GstBuffer *second = gst_harness_push_and_pull(h, buffer_from_frame(b));
    ASSERT_NE(first, nullptr);
    ASSERT_NE(second, nullptr);
    const GstVideoInfo info = output_info(h);
    EXPECT_EQ(GST_VIDEO_INFO_WIDTH(&info), s.w);
    EXPECT_EQ(GST_VIDEO_INFO_HEIGHT(&info), s.h);
    GstCaps *caps = gst_pad_get_current_caps(h->sinkpad);
    const cv::Mat got = buffer_to_bgra(first, caps);
    // A fresh chain given the same first frame.
    GstHarness *fresh = gst_harness_new_parse(chain);
    gst_harness_set_src_caps_str(fresh, raw_caps(s.f, s.w, s.h).c_str());
    GstBuffer *want_buf = gst_harness_push_and_pull(fresh, buffer_from_frame(a));
    ASSERT_NE(want_buf, nullptr);
    EXPECT_EQ(cv::norm(got, buffer_to_bgra(want_buf, caps), cv::NORM_INF), 0) << format_name(s.f) << " " << s.w;
    gst_buffer_unref(want_buf);
    gst_harness_teardown(fresh);
    gst_caps_unref(caps);
    gst_buffer_unref(first);
    gst_buffer_unref(second);
  }
  gst_harness_teardown(h);
}

// The rule of gst/processing_latency.h: nothing before a measured frame, the
// first frame after a start not counted, then the second longest of the
// window plus an eighth, rounded up to a millisecond, growing as soon as a
// frame time exceeds what is reported and shrinking only when the windows
// of kShrinkAfter frames in a row ask for under half of it.
TEST(ProcessingLatency, ReportsTheSecondLongestFrameGrowingAtOnceShrinkingRarely) {
  constexpr uint64_t ms = 1000000;
  p3d::gst::ProcessingLatency l;
  EXPECT_FALSE(l.observe(90 * ms));  // warm-up: allocations
  EXPECT_EQ(l.reported(), 0u);
  EXPECT_TRUE(l.observe(8 * ms));  // one frame: it alone
  EXPECT_EQ(l.reported(), 9 * ms);  // 8 + 1 = 9
  EXPECT_FALSE(l.observe(40 * ms));  // a spike: the second longest is 8
  EXPECT_EQ(l.reported(), 9 * ms);
  EXPECT_FALSE(l.observe(9 * ms));  // within what is reported
  EXPECT_TRUE(l.observe(16 * ms));  // second longest 16: 18 ms
  EXPECT_EQ(l.reported(), 18 * ms);
  constexpr int window = p3d::gst::ProcessingLatency::kWindow;
  for (int i = 0; i < 2 * window; ++i) EXPECT_FALSE(l.observe(11 * ms));  // 13 ms: not under half of 18
  EXPECT_EQ(l.reported(), 18 * ms);
  // From the 15th frame of 2 ms the window (one 11 ms frame left, the
  // second longest 2 ms) asks for 3 ms; kShrinkAfter such frames lower it.
  constexpr int shrink_after = p3d::gst::ProcessingLatency::kShrinkAfter;
  int changes = 0;
  for (int i = 0; i < window - 3 + shrink_after; ++i) changes += l.observe(2 * ms);
  EXPECT_EQ(changes, 0);
  EXPECT_TRUE(l.observe(2 * ms));
  EXPECT_EQ(l.reported(), 3 * ms);
  for (int i = 0; i < 2 * window; ++i) EXPECT_FALSE(l.observe(2 * ms));
  l.restart();  // new caps: warm-up again, the report stays
  EXPECT_FALSE(l.observe(100 * ms));
  EXPECT_EQ(l.reported(), 3 * ms);
  l.set_live(true);
  EXPECT_TRUE(l.live());
  l.reset();  // stopped
  EXPECT_EQ(l.reported(), 0u);
  EXPECT_FALSE(l.live());
  EXPECT_FALSE(l.observe(5 * ms));
  EXPECT_TRUE(l.observe(5 * ms - 1));
  EXPECT_EQ(l.reported(), 6 * ms);  // 5 ms - 1 ns plus an eighth, rounded up
}

// After kShrinkAfter frames whose windows ask for under half, the report
// comes down, once; a change now and then (a slide) keeps it; a report of
// 2 ms does not drop to 1 and back on frames near 1 ms.
TEST(ProcessingLatency, ShrinksOnceAfterAPeriodOfShortFrames) {
  constexpr uint64_t ms = 1000000;
  constexpr int window = p3d::gst::ProcessingLatency::kWindow;
  constexpr int shrink_after = p3d::gst::ProcessingLatency::kShrinkAfter;
  static_assert(shrink_after > 50 - window, "a slide every 50 frames leaves no long enough calm");
  p3d::gst::ProcessingLatency l;
  EXPECT_FALSE(l.observe(60 * ms));  // warm-up
  EXPECT_TRUE(l.observe(20 * ms));  // 23 ms
  EXPECT_EQ(l.reported(), 23 * ms);
  int changes = 0;
  for (int slide = 0; slide < 4; ++slide) {  // two slow frames every 50: never a long enough calm
    changes += l.observe(20 * ms);
    changes += l.observe(20 * ms);
    for (int i = 0; i < 48; ++i) changes += l.observe(1 * ms + 500000);
  }
  EXPECT_EQ(changes, 0);
  EXPECT_EQ(l.reported(), 23 * ms);
  // A calm of kShrinkAfter frames (the windows' second longest 1.5 ms plus
  // an eighth: 2 ms) lowers it, once.
  for (int i = 0; i < shrink_after; ++i) changes += l.observe(1 * ms + 500000);
  EXPECT_EQ(changes, 1);
  EXPECT_EQ(l.reported(), 2 * ms);
  changes = 0;
  for (int i = 0; i < 4 * window; ++i) changes += l.observe(i % 2 ? 700000 : 800000);  // 0.9 ms: 1 ms
  EXPECT_EQ(changes, 0);  // 1 ms would be half of 2, not under it
  EXPECT_EQ(l.reported(), 2 * ms);
}

// Plays `launch` to its end (an error fails the test and ends the wait)
// and returns the pipeline, still playing, for queries (null: it did not
// start); posted receives the names of the elements that posted LATENCY
// messages meanwhile.
GstElement *play_to_eos(const char *launch, std::vector<std::string> *posted) {
  GstElement *pipeline = gst_parse_launch(launch, nullptr);
  if (!pipeline || gst_element_set_state(pipeline, GST_STATE_PLAYING) == GST_STATE_CHANGE_FAILURE) {
    ADD_FAILURE() << "could not play " << launch;
    if (pipeline) gst_object_unref(pipeline);
    return nullptr;
  }
  GstBus *bus = gst_element_get_bus(pipeline);
  bool eos = false;
  while (GstMessage *m = gst_bus_timed_pop_filtered(
             bus, 60 * GST_SECOND, (GstMessageType)(GST_MESSAGE_EOS | GST_MESSAGE_ERROR | GST_MESSAGE_LATENCY))) {
    const GstMessageType type = GST_MESSAGE_TYPE(m);
    if (type == GST_MESSAGE_LATENCY) posted->emplace_back(GST_OBJECT_NAME(GST_MESSAGE_SRC(m)));
    if (type == GST_MESSAGE_ERROR) ADD_FAILURE() << message_text(m);
    eos = type == GST_MESSAGE_EOS;
    gst_message_unref(m);
    if (type != GST_MESSAGE_LATENCY) break;
  }
  EXPECT_TRUE(eos) << launch;
  gst_object_unref(bus);
  return pipeline;
}

// Not live: the stages post no LATENCY message (it would only make the
// application recalculate a latency nothing waits for).
TEST(ProcessingLatency, StagesPostNoMessageWhenNotLive) {
  std::vector<std::string> posted;
  GstElement *pipeline = play_to_eos(
      "videotestsrc pattern=snow num-buffers=20 ! video/x-raw,format=I420,width=320,height=240,framerate=30/1 ! "
      "pseudo3dconvert processing=cpu ! fakesink sync=true",
      &posted);
  ASSERT_NE(pipeline, nullptr);
  for (const char *stage : {"depth", "filter", "warp"})
    EXPECT_EQ(std::find(posted.begin(), posted.end(), stage), posted.end()) << stage << " posted a LATENCY message";
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(pipeline);
}

// A live pipeline: every stage of pseudo3dconvert posts a LATENCY message
// once it has measured its frames, and the latency downstream of the
// converter exceeds upstream's by what the stages report (at least a
// millisecond each), so that a sink with sync=true waits for the frames
// instead of finding them late.
TEST(ProcessingLatency, LiveStagesAddTheirTimeToTheLatencyQuery) {
  std::vector<std::string> posted;
  GstElement *pipeline = play_to_eos(
      "videotestsrc is-live=true pattern=snow num-buffers=20 ! video/x-raw,format=I420,width=320,height=240,"
      "framerate=30/1 ! pseudo3dconvert name=c processing=cpu ! fakesink name=s sync=true",
      &posted);
  ASSERT_NE(pipeline, nullptr);
  // The minimum latency at a pad's peer (upstream of the pad).
  gboolean live = FALSE;
  auto min_latency = [&](const char *element, const char *pad_name) {
    GstElement *e = gst_bin_get_by_name(GST_BIN(pipeline), element);
    GstPad *pad = gst_element_get_static_pad(e, pad_name);
    GstQuery *q = gst_query_new_latency();
    GstClockTime min = GST_CLOCK_TIME_NONE;
    if (gst_pad_peer_query(pad, q)) gst_query_parse_latency(q, &live, &min, nullptr);
    gst_query_unref(q);
    gst_object_unref(pad);
    gst_object_unref(e);
    return min;
  };
  const GstClockTime upstream = min_latency("c", "sink"), downstream = min_latency("s", "sink");
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(pipeline);
  EXPECT_TRUE(live);
  for (const char *stage : {"depth", "filter", "warp"})
    EXPECT_NE(std::find(posted.begin(), posted.end(), stage), posted.end()) << stage << " posted no LATENCY message";
  ASSERT_TRUE(GST_CLOCK_TIME_IS_VALID(upstream) && GST_CLOCK_TIME_IS_VALID(downstream));
  EXPECT_GE(downstream, upstream + 3 * GST_MSECOND) << "upstream " << upstream << " downstream " << downstream;
}
