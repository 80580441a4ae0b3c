// pseudo3d-bench's scene mode (scene_bench.h).
#include "scene_bench.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <limits>
#include <numeric>

#include <opencv2/imgproc.hpp>

#include "enum_name.h"
#include "json_line.h"
#include "metrics.h"
#include "scene_chain.h"
#ifdef P3D_BENCH_GPU
#include <stdexcept>

#include "scene_chain_gpu.h"
#endif

namespace p3d::bench {

namespace {

// Per-frame times of one chain over the timed frames. Over several rounds
// each frame's stage keeps its shortest time: the work is the same every
// round, and what a shared machine's other load does can only add to it.
struct Series {
  std::vector<StageMs> frames;
  void keep_shortest(const std::vector<StageMs> &round) {
    if (frames.empty()) {
      frames = round;
      return;
    }
    for (size_t k = 0; k < frames.size() && k < round.size(); ++k)
      for (double StageMs::*stage : {&StageMs::depth, &StageMs::filter, &StageMs::warp})
        frames[k].*stage = std::min(frames[k].*stage, round[k].*stage);
  }
  std::vector<double> totals() const {
    std::vector<double> t;
    for (const StageMs &ms : frames) t.push_back(ms.total());
    return t;
  }
  double mean() const {
    const std::vector<double> t = totals();
    return t.empty() ? 0 : std::accumulate(t.begin(), t.end(), 0.0) / t.size();
  }
  double median() const {
    std::vector<double> t = totals();
    if (t.empty()) return 0;
    std::sort(t.begin(), t.end());
    const size_t n = t.size();
    return n % 2 ? t[n / 2] : 0.5 * (t[n / 2 - 1] + t[n / 2]);
  }
  double stage_mean(double StageMs::*stage) const {
    double sum = 0;
    for (const StageMs &ms : frames) sum += ms.*stage;
    return frames.empty() ? 0 : sum / frames.size();
  }
};

struct SceneResult {
  std::string scene, note;
  Size size{0, 0};
  float tolerance = 0;
  int frames = 0, rounds = 1;
  Series off, on;
  AdaptiveChain::Shares changed;  // means over the timed frames
  bool compared = true;  // false: the on chain is meant to differ (measure_crop)
  bool gpu = false;      // the GPU chains (they count the warp's rows, not the spans and tiles)
  int identical_frames = 0;
  int first_mismatch = -1;  // frame number, -1: none
  std::string mismatch_at;
  double psnr_mean = std::numeric_limits<double>::quiet_NaN();  // over the frames that differ
  double psnr_min = std::numeric_limits<double>::infinity();
  double ratio() const { return off.mean() > 0 ? 100.0 * on.mean() / off.mean() : 0; }
  bool identical() const { return first_mismatch < 0; }
};

// One round: a new chain of each kind over the sequence (make_off() and
// make_on() build them), frame by frame in turn, which of them first
// alternating. Both then meet the same load of a shared machine (in turn a
// frame apart, not a sequence apart) and, on average, the same state of
// its caches. Frame 0 is the warm-up: each chain's first frame (whole, and
// the one that maps its buffers), untimed; frames 1..n-1 are timed, every
// one a change from the frame before as a stream meets it. after(off, on,
// k) sees each frame's outputs.
template <class MakeOff, class MakeOn, class After>
void run_round(const std::vector<FrameView> &frames, SceneResult *r, MakeOff make_off, MakeOn make_on, After after) {
  auto off_chain = make_off();
  auto on_chain = make_on();
  std::vector<StageMs> off, on;
  for (size_t k = 0; k < frames.size(); ++k) {
    const FrameView f = frames[k];
    StageMs off_ms, on_ms;
    if (k % 2) {
      off_chain.frame(f, &off_ms);
      on_chain.frame(f, &on_ms);
    } else {
      on_chain.frame(f, &on_ms);
      off_chain.frame(f, &off_ms);
    }
    if (k > 0) {
      off.push_back(off_ms);
      on.push_back(on_ms);
    }
    after(off_chain, on_chain, k);
  }
  r->off.keep_shortest(off);
  r->on.keep_shortest(on);
}

// Where two frames of one geometry first differ ("" where they do not):
// the plane, the row and the byte in the row.
std::string first_difference(const HostFrame &a, const HostFrame &b) {
  const FrameView va = a.view(), vb = b.view();
  for (int i = 0; i < frame_plane_count(va.format); ++i) {
    int row_bytes = 0, rows = 0;
    frame_plane_size(va.format, va.width, va.height, i, &row_bytes, &rows);
    for (int y = 0; y < rows; ++y) {
      const uint8_t *ra = va.plane[i] + static_cast<size_t>(y) * va.stride[i];
      const uint8_t *rb = vb.plane[i] + static_cast<size_t>(y) * vb.stride[i];
      if (std::memcmp(ra, rb, row_bytes) == 0) continue;
      const int x = static_cast<int>(std::mismatch(ra, ra + row_bytes, rb).first - ra);
      return "plane " + std::to_string(i) + " row " + std::to_string(y) + " byte " + std::to_string(x);
    }
  }
  return "";
}

// PSNR over the colour channels (alpha left out).
double frame_psnr(const HostFrame &a, const HostFrame &b) {
  cv::Mat ca, cb;
  cv::cvtColor(a.to_bgra(), ca, cv::COLOR_BGRA2BGR);
  cv::cvtColor(b.to_bgra(), cb, cv::COLOR_BGRA2BGR);
  return psnr(ca, cb);
}

std::vector<FrameView> views_of(const std::vector<HostFrame> &frames) {
  std::vector<FrameView> v;
  for (const HostFrame &f : frames) v.push_back(f.view());
  return v;
}

// The chains' shares of changed tiles and spans (AdaptiveChain::shares);
// the GPU chain reports its warp's rows, and its input share is
// FrameHistory's.
void add_shares(SceneResult *r, const AdaptiveChain &adaptive) {
  const AdaptiveChain::Shares &s = adaptive.shares();
  r->changed.input += s.input;
  r->changed.filter += s.filter;
  r->changed.warp += s.warp;
  r->changed.warp_spans += s.warp_spans;
}
#ifdef P3D_BENCH_GPU
void add_shares(SceneResult *r, const GpuSceneChain &adaptive) { r->changed.warp_rows += adaptive.warp_rows_share(); }
#endif

// Both chains over one sequence (`frames`, their views in the chains'
// memory), `rounds` times; in the first round each adaptive output is
// compared with the full chain's (every round computes the same bytes).
template <class MakeFull, class MakeAdaptive>
SceneResult measure(const std::vector<HostFrame> &frames, const std::vector<FrameView> &views, float tolerance,
                    int rounds, MakeFull make_full, MakeAdaptive make_adaptive) {
  SceneResult r;
  r.tolerance = tolerance;
  r.frames = static_cast<int>(frames.size());
  r.rounds = rounds;
  double psnr_sum = 0;
  int differing = 0;
  run_round(views, &r, make_full, make_adaptive, [&](const auto &full, const auto &adaptive, size_t k) {
    if (k > 0) add_shares(&r, adaptive);
    const std::string where = first_difference(full.output(), adaptive.output());
    if (where.empty()) {
      ++r.identical_frames;
      return;
    }
    if (r.first_mismatch < 0) {
      r.first_mismatch = static_cast<int>(k);
      r.mismatch_at = where;
    }
    const double db = frame_psnr(full.output(), adaptive.output());
    psnr_sum += db;
    ++differing;
    r.psnr_min = std::min(r.psnr_min, db);
  });
  for (int i = 1; i < rounds; ++i)
    run_round(views, &r, make_full, make_adaptive, [](const auto &, const auto &, size_t) {});
  if (differing > 0) r.psnr_mean = psnr_sum / differing;
  const double timed = std::max(1, r.frames - 1);
  for (double *share :
       {&r.changed.input, &r.changed.filter, &r.changed.warp, &r.changed.warp_spans, &r.changed.warp_rows})
    *share /= timed;
  return r;
}

#ifdef P3D_BENCH_GPU
// The frames uploaded into *device, and their views there.
std::vector<FrameView> device_views(const std::vector<HostFrame> &frames, std::vector<DevFrame> *device) {
  device->resize(frames.size());
  std::vector<FrameView> views;
  for (size_t k = 0; k < frames.size(); ++k) {
    const CudaStatus st = (*device)[k].upload(frames[k]);
    if (!st.ok()) throw std::runtime_error(st.message());
    views.push_back((*device)[k].view);
  }
  return views;
}

// The share of the input's tiles that differ from the frame before, over
// the timed frames (FrameHistory at the tolerance).
double input_share(const std::vector<HostFrame> &frames, float tolerance) {
  FrameHistory h;
  double sum = 0;
  for (size_t k = 0; k < frames.size(); ++k) {
    const double f = h.compare(frames[k].view(), tolerance).fraction();
    if (k > 0) sum += f;
  }
  return frames.size() > 1 ? sum / static_cast<double>(frames.size() - 1) : 0;
}
#endif

// The CPU chains (both with crop-bars=auto, as the elements default: no
// scene but the letterbox has bars, and the counts are the cost both pay)
// or the GPU chains.
SceneResult measure(const StageParams &p, const std::vector<HostFrame> &frames, float tolerance, int rounds,
                    bool gpu) {
  const int w = frames[0].width(), h = frames[0].height();
  const PixelFormat format = frames[0].format();
#ifdef P3D_BENCH_GPU
  if (gpu) {
    std::vector<DevFrame> device;
    const std::vector<FrameView> views = device_views(frames, &device);
    SceneResult r = measure(
        frames, views, tolerance, rounds, [&] { return GpuSceneChain(p, w, h, format, false, 0.f); },
        [&] { return GpuSceneChain(p, w, h, format, true, tolerance); });
    r.changed.input = input_share(frames, tolerance);
    r.gpu = true;
    return r;
  }
#else
  (void)gpu;
#endif
  return measure(
      frames, views_of(frames), tolerance, rounds, [&] { return FullChain(p, w, h, format, true); },
      [&] { return AdaptiveChain(p, w, h, format, tolerance); });
}

// The letterbox scene: crop-bars=auto ("on") against off, both with
// adaptive=false; the outputs differ by design (the bars are left out of
// the 3D), so they are not compared.
SceneResult measure_crop(const StageParams &p, const std::vector<HostFrame> &frames, int rounds, bool gpu) {
  SceneResult r;
  r.frames = static_cast<int>(frames.size());
  r.rounds = rounds;
  r.compared = false;
  const int w = frames[0].width(), h = frames[0].height();
  const PixelFormat format = frames[0].format();
#ifdef P3D_BENCH_GPU
  if (gpu) {
    std::vector<DevFrame> device;
    const std::vector<FrameView> views = device_views(frames, &device);
    for (int i = 0; i < rounds; ++i)
      run_round(views, &r, [&] { return GpuSceneChain(p, w, h, format, false, 0.f, false); },
                [&] { return GpuSceneChain(p, w, h, format, false, 0.f, true); },
                [](const GpuSceneChain &, const GpuSceneChain &, size_t) {});
    r.gpu = true;
    return r;
  }
#else
  (void)gpu;
#endif
  for (int i = 0; i < rounds; ++i)
    run_round(views_of(frames), &r, [&] { return FullChain(p, w, h, format, false); },
              [&] { return FullChain(p, w, h, format, true); }, [](const FullChain &, const FullChain &, size_t) {});
  return r;
}

// ---- output ---------------------------------------------------------------------------

void print_header() {
  std::printf("%-9s %-9s %4s %7s %6s %7s %8s %7s %8s %7s %5s %13s  %-20s %-20s\n", "scene", "size", "tol", "changed",
              "spans", "off med", "off mean", "on med", "on mean", "on/off", "same", "PSNR mean/min",
              "off ms depth/filt/warp", "on ms depth/filt/warp");
  std::fflush(stdout);
}

std::string stages_text(const Series &s) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.1f/%.1f/%.1f", s.stage_mean(&StageMs::depth), s.stage_mean(&StageMs::filter),
                s.stage_mean(&StageMs::warp));
  return buf;
}

void print_row(const SceneResult &r) {
  char size[32], psnr_text[32] = "-";
  std::snprintf(size, sizeof size, "%dx%d", r.size.width, r.size.height);
  if (!r.identical()) std::snprintf(psnr_text, sizeof psnr_text, "%.1f/%.1f", r.psnr_mean, r.psnr_min);
  std::printf("%-9s %-9s %4g %6.1f%% %5.1f%% %7.1f %8.1f %7.1f %8.1f %6.1f%% %5s %13s  %-20s %-20s\n", r.scene.c_str(),
              size, r.tolerance, 100.0 * r.changed.input, 100.0 * (r.gpu ? r.changed.warp_rows : r.changed.warp_spans),
              r.off.median(), r.off.mean(),
              r.on.median(), r.on.mean(), r.ratio(),
              !r.compared ? "n/a" : r.identical() ? "yes" : "no", psnr_text, stages_text(r.off).c_str(),
              stages_text(r.on).c_str());
  if (!r.identical())
    std::printf("  first difference: frame %d, %s (%d of %d frames identical)\n", r.first_mismatch,
                r.mismatch_at.c_str(), r.identical_frames, r.frames);
  if (!r.note.empty()) std::printf("  note: %s\n", r.note.c_str());
  std::fflush(stdout);
}

void emit(const SceneResult &r, const StageParams &p, const SceneRunInfo &info, std::ostream &out) {
  using tools::JsonLine;
  JsonLine j;
  j.str("run", info.run_id).str("kind", "scene").str("date", info.date);
  if (info.git.empty())
    j.raw("git", "null");
  else
    j.str("git", info.git);
  j.str("scene", r.scene).integer("width", r.size.width).integer("height", r.size.height);
  if (r.gpu) {
#ifdef P3D_BENCH_GPU
    j.str("device", "gpu").str("gpu_name", gpu_name());
#endif
  } else {
    j.str("device", "cpu").integer("cpu_threads", cv::getNumThreads());
  }
  j.str("format", info.format).str("layout", enum_nick(kPackLayoutNames, p.pack.layout));
  j.str("filter_mode", enum_nick(kFilterModeNames, p.filter.mode)).str("fill", enum_nick(kHoleFillNames, p.warp.fill));
  j.integer("filter_scale", bilateral_effective_scale(bilateral_sanitize(p.filter), r.size.width, r.size.height));
  j.num("tolerance", r.tolerance).integer("frames", r.frames).integer("timed_frames", r.frames - 1);
  j.integer("rounds", r.rounds);
  j.num("changed_tiles", r.changed.input).num("filter_tiles", r.changed.filter).num("warp_tiles", r.changed.warp);
  j.num("warp_spans", r.changed.warp_spans);
  if (r.gpu && r.compared) j.num("warp_rows", r.changed.warp_rows);
  j.num("off_median_ms", r.off.median()).num("off_mean_ms", r.off.mean());
  j.num("on_median_ms", r.on.median()).num("on_mean_ms", r.on.mean()).num("ratio_pct", r.ratio());
  j.str("on", r.compared ? "adaptive=true" : "crop-bars=auto");
  j.str("off", r.compared ? "adaptive=false" : "crop-bars=off");
  j.raw("identical", !r.compared ? "null" : r.identical() ? "true" : "false");
  j.integer("identical_frames", r.identical_frames);
  if (r.identical() || !r.compared)
    j.raw("first_mismatch_frame", "null");
  else
    j.integer("first_mismatch_frame", r.first_mismatch).str("first_mismatch_at", r.mismatch_at);
  j.num("psnr_mean_db", r.psnr_mean).num("psnr_min_db", r.psnr_min);  // identical: null, +inf -> null
  j.num("off_depth_ms", r.off.stage_mean(&StageMs::depth)).num("off_filter_ms", r.off.stage_mean(&StageMs::filter));
  j.num("off_warp_ms", r.off.stage_mean(&StageMs::warp));
  j.num("on_depth_ms", r.on.stage_mean(&StageMs::depth)).num("on_filter_ms", r.on.stage_mean(&StageMs::filter));
  j.num("on_warp_ms", r.on.stage_mean(&StageMs::warp));
  if (!r.note.empty()) j.str("note", r.note);
  out << j.text() << "\n" << std::flush;
}

}  // namespace

int run_scenes(const SceneOptions &o, const StageParams &p, PixelFormat format, const std::vector<Size> &sizes,
               const SceneRunInfo &info, std::ostream &out) {
  std::printf("scene mode: the %s chain (depth, filter, warp + pack), adaptive off and on in turn frame by frame;\n"
              "%d frames a sequence, the first the warm-up; ms a frame, the shortest of %d round(s).\n"
              "changed: input tiles that differ from the frame before; spans: source pixels in the columns of\n"
              "each row the warp is given as changed (GPU: rows, the share of the rows the warp renders);\n"
              "on/off: mean on / mean off; same: every output byte equal to adaptive=false's\n"
              "letterbox: on is crop-bars=auto, off crop-bars=off, both adaptive=false (changed: n/a)\n",
              o.gpu ? "GPU" : "CPU", o.frames, o.rounds);
  print_header();
  bool mismatch_at_zero = false;
  for (const Size s : sizes) {
    for (const std::string &scene : o.scenes) {
      std::vector<HostFrame> frames;
      std::string why, note;
      if (!make_scene(scene, s, o.frames, format, o.video, &frames, &why, &note)) {
        std::printf("%-7s %dx%d skipped: %s\n", scene.c_str(), s.width, s.height, why.c_str());
        continue;
      }
      for (const float tolerance : o.tolerances) {
        SceneResult r = scene == "letterbox" ? measure_crop(p, frames, o.rounds, o.gpu)
                                             : measure(p, frames, tolerance, o.rounds, o.gpu);
        r.scene = scene;
        r.size = s;
        r.note = note;
        print_row(r);
        emit(r, p, info, out);
        if (tolerance == 0.f && r.compared && !r.identical()) mismatch_at_zero = true;
        if (!r.compared) break;  // no tolerance in it: one row
      }
    }
  }
  if (mismatch_at_zero) std::cerr << "pseudo3d-bench: an adaptive output differs from adaptive=false at tolerance 0\n";
  return mismatch_at_zero ? 1 : 0;
}

}  // namespace p3d::bench
