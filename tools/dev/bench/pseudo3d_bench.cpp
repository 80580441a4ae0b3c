// pseudo3d-bench: times every stage (convert, depth, filter, warp, pack,
// warp-pack) and the whole chain on the CPU and, when built with CUDA, on
// the GPU, plus a device-to-device copy that gives the card's achievable
// bandwidth. Writes one JSON line per measurement and prints a short table.
//
// Byte counts are the minimum a stage must move: every input read once,
// every output written once (W x H frame, F = the input frame's bytes,
// luma = W*H for YUV input, 4*W*H for packed RGB whose luma needs all of it):
//   convert  F + 4WH                 (frame -> RGBA)
//   depth    F + 4WH                 (float depth written)
//   filter   4WH/s^2 + luma + 4WH    (depth at the grid step s and guide read, depth written)
//   warp     F + 4WH + 8WH           (frame and depth read, 2W x H pair written)
//   pack     8WH + packed output     (pair read, layout's output written)
//   warp-pack F + 4WH + packed output (the warp writing the layout's output
//            itself, as pseudo3dwarp with a layout does: on the GPU fused
//            where WarpRendererGpu::render_packed can, else the pair then pack)
//   chain    depth + filter + warp-pack
//
// Scene mode (--scenes): instead of the stages on rotating inputs, the CPU
// chain (the GPU's with --device gpu) over generated sequences (still
// picture, screen content, the vtest.avi camera, pan, snow, cuts,
// letterbox; scenes.h) with the adaptive stages off and on, as the
// elements run them (scene_bench.h): ms a frame of each, the adaptive
// chain's cost relative to adaptive=false, whether its output is byte for
// byte the same (PSNR where a reuse tolerance lets it differ), the share
// of tiles that changed and the time per stage.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include <opencv2/core.hpp>

#include "build_version.h"
#include "bench_gpu.h"  // types only unless P3D_BENCH_GPU
#include "cli_args.h"
#include "pack.h"
#include "json_line.h"
#include "scene_bench.h"
#include "scenes.h"

namespace p3d::bench {
namespace {

constexpr int kFrames = 4;  // distinct inputs the timings rotate through
constexpr int kExitUsage = 64;
constexpr int kExitNoGpu = 2;

struct Options {
  bool want_cpu = true, want_gpu = true, device_given = false;
  std::vector<Size> sizes;
  PixelFormat format = PixelFormat::NV12;
  StageParams params;
  int iterations = 0;  // 0: the per-device defaults
  int gpu_warmup = 10;
  int cpu_warmup = 1;
  int cpu_threads = -1;  // -1: OpenCV's default
  size_t copy_bytes = size_t{1} << 30;
  std::string out_path = "bench-results.jsonl";
  std::string argv;
  SceneOptions scene;  // scene mode where scene.scenes is not empty
};

// ---- command line -----------------------------------------------------------

const std::map<std::string, PixelFormat> kFormats = {
    {"NV12", PixelFormat::NV12}, {"I420", PixelFormat::I420}, {"RGBA", PixelFormat::RGBA},
    {"BGRA", PixelFormat::BGRA}, {"RGBx", PixelFormat::RGBx}, {"BGRx", PixelFormat::BGRx},
    {"P010_10LE", PixelFormat::P010}, {"I420_10LE", PixelFormat::I420_10}, {"RGBA64_LE", PixelFormat::RGBA64}};

template <typename T>
std::string name_of(const std::map<std::string, T> &table, T value) {
  for (const auto &kv : table)
    if (kv.second == value) return kv.first;
  return "?";
}
template <typename E, std::size_t N>
std::string name_of(const p3d::EnumName<E> (&table)[N], E value) {
  return p3d::enum_nick(table, value);
}

const std::vector<Size> kDefaultSizes = {{1280, 720}, {1920, 1080}, {3840, 2160}, {7680, 4320}};
// Scene mode: the sizes the adaptive stages' goals are set at. Not 8K by
// default: a scene run holds every frame of a sequence in memory (1.5 GB
// for 30 frames of 8K I420).
const std::vector<Size> kDefaultSceneSizes = {{1920, 1080}, {3840, 2160}};

std::string scene_list() {
  std::string list;
  for (const std::string &k : scene_kinds()) list += (list.empty() ? "" : ", ") + k;
  return list;
}

void print_usage(std::ostream &os) {
  os << "Usage: pseudo3d-bench [options]\n"
        "  --device cpu|gpu        time only one device (default: both; GPU skipped if absent)\n"
        "  --size WxH              one frame size (repeatable or comma separated; default\n"
        "                          1280x720,1920x1080,3840x2160,7680x4320)\n"
        "  --format F              input format: NV12 (default), I420, RGBA, BGRA, RGBx, BGRx,\n"
        "                          P010_10LE, I420_10LE, RGBA64_LE (16-bit views; no scene mode)\n"
        "  --layout L              pack layout (default anaglyph): "
     << p3d::enum_nicks(kPackLayoutNames) << "\n"
     << "  --radius N              bilateral radius (default 5)\n"
        "  --filter-mode M         separable (default, as pseudo3dfilter) or exact\n"
        "  --filter-scale N        the filter's grid step: 0 automatic (default, as pseudo3dfilter:\n"
        "                          4 from 2160 rows up), 1 every pixel, up to 8\n"
        "  --max-disparity P       percent of width (default 3)\n"
        "  --fill F                "
     << p3d::enum_nicks(kHoleFillNames) << " (default background-smooth)\n"
     << "  --depth-handoff H       GPU depth between the stages: grid (default, as the elements on\n"
        "                          CUDA memory: block and cell values) or full (full-size maps)\n"
        "  --iterations N          timed iterations (default GPU 50; CPU 10, 5 from 4K up)\n"
        "  --warmup N              GPU warm-up iterations (default 10; CPU always 1)\n"
        "  --cpu-threads N         OpenCV worker threads for the CPU timings\n"
        "  --copy-mib N            size of the device-to-device copy (default 1024)\n"
        "  --quick                 smoke test: 3 iterations, 1280x720 and 1920x1080\n"
        "  --out FILE              JSON lines appended here (default bench-results.jsonl)\n"
        "Scene mode (the CPU chain, or the GPU's with --device gpu; --size (default\n"
        "1920x1080,3840x2160), --format, --layout, the stage options, --cpu-threads and --out apply,\n"
        "--iterations, --warmup and --copy-mib do not):\n"
        "  --scenes LIST           time the adaptive stages against adaptive=false over generated\n"
        "                          sequences, comma separated, or all: "
     << scene_list() << "\n"
     << "  --frames N              frames a sequence (default 30; the first is the warm-up)\n"
        "  --rounds N              runs of each sequence (default 1); each frame's time is its shortest,\n"
        "                          the work without what other load on the machine added\n"
        "  --tolerance LIST        reuse tolerances to run, comma separated (default 0)\n"
        "  --video FILE            the camera scene's video (default data/vtest.avi of the source tree)\n"
        "Exit status: 0 ok, 1 runtime/CUDA error (scene mode: also an adaptive output that differs\n"
        "at tolerance 0), 2 GPU requested but none usable, 64 bad usage.\n";
}

const p3d::tools::Cli kCli("pseudo3d-bench", print_usage, kExitUsage);
[[noreturn]] void usage_error(const std::string &msg) { kCli.fail(msg); }
int parse_int(const std::string &opt, const std::string &v, int lo, int hi) { return kCli.integer(opt, v, lo, hi); }

float parse_float(const std::string &opt, const std::string &v) {
  char *end = nullptr;
  const float f = std::strtof(v.c_str(), &end);
  if (v.empty() || *end != '\0' || !std::isfinite(f)) usage_error(opt + " wants a number, got '" + v + "'");
  return f;
}

std::vector<std::string> split_list(const std::string &v) {
  std::vector<std::string> items;
  std::stringstream ss(v);
  std::string item;
  while (std::getline(ss, item, ',')) items.push_back(item);
  return items;
}

void parse_sizes(const std::string &v, std::vector<Size> *sizes) {
  for (const std::string &item : split_list(v)) {
    const size_t x = item.find_first_of("xX");
    if (x == std::string::npos) usage_error("--size wants WxH, got '" + item + "'");
    sizes->push_back({parse_int("--size", item.substr(0, x), 1, 65536), parse_int("--size", item.substr(x + 1), 1, 65536)});
  }
}

void parse_scenes(const std::string &v, std::vector<std::string> *scenes) {
  for (const std::string &item : split_list(v)) {
    const std::vector<std::string> &kinds = scene_kinds();
    if (item == "all")
      scenes->insert(scenes->end(), kinds.begin(), kinds.end());
    else if (std::find(kinds.begin(), kinds.end(), item) != kinds.end())
      scenes->push_back(item);
    else
      usage_error("unknown scene '" + item + "' (" + scene_list() + ", all)");
  }
}

// Reuse tolerances: mean |difference| in 8-bit levels (change_map.h).
std::vector<float> parse_tolerances(const std::string &v) {
  std::vector<float> tolerances;
  for (const std::string &item : split_list(v)) {
    const float t = parse_float("--tolerance", item);
    if (t < 0.f || t > 255.f) usage_error("--tolerance wants levels in 0..255, got '" + item + "'");
    tolerances.push_back(t);
  }
  if (tolerances.empty()) usage_error("--tolerance wants at least one value");
  return tolerances;
}

template <typename T>
T parse_name(const std::string &opt, const std::string &v, const std::map<std::string, T> &table) {
  const auto it = table.find(v);
  if (it == table.end()) usage_error("unknown " + opt + " '" + v + "'");
  return it->second;
}
template <typename E, std::size_t N>
E parse_name(const std::string &opt, const std::string &v, const p3d::EnumName<E> (&table)[N]) {
  E value{};
  if (!p3d::enum_from_nick(table, v, &value))
    usage_error("unknown " + opt + " '" + v + "' (" + p3d::enum_nicks(table) + ")");
  return value;
}

Options parse_args(int argc, char **argv) {
  Options o;
  o.params.filter = default_filter_params();  // what pseudo3dfilter runs by default
  o.scene.video = P3D_BENCH_VIDEO;
  bool quick = false;
  kCli.parse(argc, argv, "--quick", &o.argv, [&]() { quick = true; }, [&](const std::string &a, const std::string &v) {
    if (a == "--device") {
      if (v != "cpu" && v != "gpu") usage_error("--device wants cpu or gpu");
      o.device_given = true;
      o.want_cpu = v == "cpu";
      o.want_gpu = v == "gpu";
    } else if (a == "--size") {
      parse_sizes(v, &o.sizes);
    } else if (a == "--format") {
      o.format = parse_name(a, v, kFormats);
    } else if (a == "--layout") {
      o.params.pack.layout = parse_name(a, v, kPackLayoutNames);
    } else if (a == "--radius") {
      o.params.filter.radius = parse_int(a, v, 0, kMaxBilateralRadius);
    } else if (a == "--filter-mode") {
      o.params.filter.mode = parse_name(a, v, kFilterModeNames);
    } else if (a == "--filter-scale") {
      o.params.filter.scale = parse_int(a, v, 0, kMaxBilateralScale);
    } else if (a == "--max-disparity") {
      o.params.warp.max_disparity = parse_float(a, v);
    } else if (a == "--fill") {
      o.params.warp.fill = parse_name(a, v, kHoleFillNames);
    } else if (a == "--depth-handoff") {
      if (v != "grid" && v != "full") usage_error("--depth-handoff wants grid or full");
      o.params.depth_grids = v == "grid";
    } else if (a == "--iterations") {
      o.iterations = parse_int(a, v, 1, 100000);
    } else if (a == "--warmup") {
      o.gpu_warmup = parse_int(a, v, 0, 100000);
    } else if (a == "--cpu-threads") {
      o.cpu_threads = parse_int(a, v, 1, 1024);
    } else if (a == "--copy-mib") {
      o.copy_bytes = static_cast<size_t>(parse_int(a, v, 1, 65536)) << 20;
    } else if (a == "--out") {
      o.out_path = v;
    } else if (a == "--scenes") {
      parse_scenes(v, &o.scene.scenes);
    } else if (a == "--frames") {
      o.scene.frames = parse_int(a, v, 2, 100000);
    } else if (a == "--rounds") {
      o.scene.rounds = parse_int(a, v, 1, 1000);
    } else if (a == "--tolerance") {
      o.scene.tolerances = parse_tolerances(v);
    } else if (a == "--video") {
      o.scene.video = v;
    } else {
      usage_error("unknown option " + a);
    }
  });
  if (quick) {
    if (o.iterations == 0) o.iterations = 3;
    if (o.sizes.empty()) o.sizes = {{1280, 720}, {1920, 1080}};
  }
  if (o.sizes.empty()) o.sizes = o.scene.scenes.empty() ? kDefaultSizes : kDefaultSceneSizes;
  return o;
}

int cpu_iterations(const Options &o, Size s) {
  if (o.iterations > 0) return o.iterations;
  return static_cast<long long>(s.width) * s.height > 1920LL * 1080 ? 5 : 10;
}

// ---- synthetic input ----------------------------------------------------------

std::vector<HostFrame> make_frames(PixelFormat format, Size s) {
  std::vector<HostFrame> frames;
  for (int k = 0; k < kFrames; ++k) frames.push_back(HostFrame::from_bgr(synthetic_bgr(s.width, s.height, k), format));
  return frames;
}

// ---- byte counts ----------------------------------------------------------------

double frame_bytes(PixelFormat f, int w, int h) {
  double total = 0;
  for (int i = 0; i < frame_plane_count(f); ++i) {
    int row = 0, rows = 0;
    frame_plane_size(f, w, h, i, &row, &rows);
    total += static_cast<double>(row) * rows;
  }
  return total;
}

// The filter's grid step at size s (the element's rule for scale 0).
int filter_step(const BilateralParams &filter, Size s) {
  return bilateral_effective_scale(bilateral_sanitize(filter), s.width, s.height);
}

// Bytes of one depth value a cell of 2^shift pixels, over the picture.
double grid_bytes(Size s, int shift) {
  return 4.0 * grid_cells(s.width, shift) * grid_cells(s.height, shift);
}

// gpu: the GPU's depth handoff (StageParams::depth_grids); the CPU stages
// hand full-size maps on.
double stage_bytes(const std::string &stage, PixelFormat f, Size s, const StageParams &p, bool gpu) {
  const bool grids = gpu && p.depth_grids;
  const double depth_map = grid_bytes(s, grids ? block_grid_shift(p.depth, s.width, s.height) : 0);
  const double filtered_map =
      grid_bytes(s, grids ? bilateral_grid_shift(bilateral_sanitize(p.filter), s.width, s.height) : 0);
  const PackParams &pack = p.pack;
  const double wh = static_cast<double>(s.width) * s.height;
  const double frame = frame_bytes(f, s.width, s.height);
  const double px = packed_pixel_bytes(stereo_format(f));  // a pixel of the views (8 bytes for deep input)
  const double luma = is_packed_rgb(f) ? packed_pixel_bytes(f) * wh : sample_bytes(f) * wh;
  int pw = 0, ph = 0;
  pack_size(pack.layout, s.width, s.height, &pw, &ph);
  const double packed = px * pw * ph;
  if (stage == "convert") return frame + px * wh;
  if (stage == "depth") return frame + depth_map;
  if (stage == "filter") {  // one depth a cell, from the block grid where it is coarser
    const int step = filter_step(p.filter, s);
    return std::min(4 * wh / (step * step), depth_map) + luma + filtered_map;
  }
  if (stage == "warp") return frame + filtered_map + 2 * px * wh;
  if (stage == "pack") return 2 * px * wh + packed;
  if (stage == "warp-pack") return frame + filtered_map + packed;  // no pair between them
  if (stage == "chain") {
    double sum = 0;
    for (const char *st : {"depth", "filter", "warp-pack"}) sum += stage_bytes(st, f, s, p, gpu);
    return sum;
  }
  return 0;
}

// ---- statistics and output --------------------------------------------------------

struct Stats {
  double median_ms = 0, min_ms = 0;
};

Stats stats_of(std::vector<double> ms) {
  Stats st;
  if (ms.empty()) return st;
  std::sort(ms.begin(), ms.end());
  const size_t n = ms.size();
  st.median_ms = n % 2 ? ms[n / 2] : 0.5 * (ms[n / 2 - 1] + ms[n / 2]);
  st.min_ms = ms.front();
  return st;
}

using p3d::tools::json_escape;
using p3d::tools::JsonLine;

struct Measurement {
  std::string stage, device, gpu_name;
  Size size{0, 0};
  int iterations = 0;
  Stats st;
  double bytes = 0;
  double share = -1;  // < 0: not applicable (CPU lines)
  double gbps() const { return st.median_ms > 0 ? bytes / (st.median_ms * 1e6) : 0; }
  double fps() const { return st.median_ms > 0 ? 1000.0 / st.median_ms : 0; }
};

class Reporter {
 public:
  Reporter(const Options &o, std::ofstream &out) : o_(o), out_(out) {}

  void header(const std::string &run_id, const std::string &date, const std::string &git) {
    run_id_ = run_id;
    JsonLine j;
    j.str("run", run_id).str("date", date);
    if (git.empty())
      j.raw("git", "null");
    else
      j.str("git", git);
    j.str("args", o_.argv).str("format", name_of(kFormats, o_.format));
    out_ << j.text() << "\n" << std::flush;
  }

  void table_header() {
    std::printf("%-8s %-9s %-6s %10s %10s %9s %8s %6s\n", "stage", "size", "device", "median ms", "min ms", "fps",
                "GB/s", "share");
    std::fflush(stdout);
  }

  void emit(const Measurement &m) {
    JsonLine j;
    j.str("run", run_id_).str("stage", m.stage).integer("width", m.size.width).integer("height", m.size.height);
    j.str("device", m.device).str("gpu_name", m.gpu_name);
    if (m.device == "cpu") j.integer("cpu_threads", cv::getNumThreads());
    j.str("format", name_of(kFormats, o_.format)).str("layout", name_of(kPackLayoutNames, o_.params.pack.layout));
    j.str("filter_mode", name_of(kFilterModeNames, o_.params.filter.mode)).str("fill", name_of(kHoleFillNames, o_.params.warp.fill));
    j.integer("filter_scale", filter_step(o_.params.filter, m.size));
    if (m.device == "gpu") j.str("depth_handoff", o_.params.depth_grids ? "grid" : "full");
    j.integer("iterations", m.iterations);
    j.num("median_ms", m.st.median_ms).num("min_ms", m.st.min_ms).num("fps", m.fps());
    j.integer("bytes", std::llround(m.bytes)).num("gbps", m.gbps());
    if (m.share >= 0) j.num("bandwidth_share", m.share);
    out_ << j.text() << "\n" << std::flush;

    char size[32], share[16] = "-";
    std::snprintf(size, sizeof size, "%dx%d", m.size.width, m.size.height);
    if (m.share >= 0) std::snprintf(share, sizeof share, "%.2f", m.share);
    std::printf("%-8s %-9s %-6s %10.4f %10.4f %9.1f %8.1f %6s\n", m.stage.c_str(), size, m.device.c_str(),
                m.st.median_ms, m.st.min_ms, m.fps(), m.gbps(), share);
    std::fflush(stdout);
  }

 private:
  const Options &o_;
  std::ofstream &out_;
  std::string run_id_;
};

// ---- CPU timings ----------------------------------------------------------------

void convert_cpu(const FrameView &in, const YuvToRgb &m, const FrameView &out) {
  cv::parallel_for_(cv::Range(0, in.height), [&](const cv::Range &rows) {
    for (int y = rows.start; y < rows.end; ++y)
      for (int x = 0; x < in.width; ++x) {
        if (is_deep(in.format))
          store_rgba16(out, x, y, load_rgba16(in, x, y, m));
        else
          store_rgba(out, x, y, load_rgba(in, x, y, m));
      }
  });
}

// The CPU counterpart of the GPU's SizeBench: rotating inputs, per-frame
// stage inputs computed once, scratch outputs.
struct CpuSizeBench {
  std::vector<HostFrame> frames, stereo;
  std::vector<cv::Mat> depth, filtered;
  cv::Mat out_depth, out_filtered;
  HostFrame out_stereo, out_packed, out_rgba;
  DepthEstimatorCpu estimator;

  CpuSizeBench(const StageParams &p, std::vector<HostFrame> inputs) : frames(std::move(inputs)) {
    const int w = frames[0].width(), h = frames[0].height();
    const PixelFormat sf = stereo_format(frames[0].format());
    int pw = 0, ph = 0;
    pack_size(p.pack.layout, w, h, &pw, &ph);
    out_depth.create(h, w, CV_32FC1);
    out_filtered.create(h, w, CV_32FC1);
    out_stereo = HostFrame(sf, 2 * w, h);
    out_packed = HostFrame(sf, pw, ph);
    out_rgba = HostFrame(is_deep(sf) ? PixelFormat::RGBA64 : PixelFormat::RGBA, w, h);
    for (const HostFrame &f : frames) {
      depth.emplace_back(h, w, CV_32FC1);
      filtered.emplace_back(h, w, CV_32FC1);
      stereo.emplace_back(sf, 2 * w, h);
      estimator.estimate(p.depth, f.view(), depth_view_of(depth.back()));
      bilateral_filter_cpu(p.filter, f.view(), depth_view_of(std::as_const(depth.back())),
                           depth_view_of(filtered.back()));
      warp(p, f.view(), filtered.back(), stereo.back().view());
    }
  }

  WarpCpuScratch warp_scratch;  // as pseudo3dwarp keeps it
  void warp(const StageParams &p, const FrameView &f, const cv::Mat &depth, const FrameView &out) {
    if (warp_render_cpu(p.warp, f, p.yuv, depth_view_of(depth), out, warp_scratch) < 0)
      throw std::runtime_error("warp_render_cpu: frames do not fit");
  }

  void run_stage(const std::string &stage, const StageParams &p, int i) {
    const size_t k = static_cast<size_t>(i) % frames.size();
    const FrameView f = frames[k].view();
    if (stage == "convert") {
      convert_cpu(f, p.yuv, out_rgba.view());
    } else if (stage == "depth") {
      estimator.estimate(p.depth, f, depth_view_of(out_depth));
    } else if (stage == "filter") {
      bilateral_filter_cpu(p.filter, f, depth_view_of(std::as_const(depth[k])), depth_view_of(out_filtered));
    } else if (stage == "warp") {
      warp(p, f, filtered[k], out_stereo.view());
    } else if (stage == "pack") {
      pack_cpu(p.pack, stereo[k].view(), out_packed.view());
    } else if (stage == "warp-pack") {
      warp(p, f, filtered[k], out_stereo.view());
      pack_cpu(p.pack, out_stereo.view(), out_packed.view());
    } else {  // chain
      estimator.estimate(p.depth, f, depth_view_of(out_depth));
      bilateral_filter_cpu(p.filter, f, depth_view_of(std::as_const(out_depth)), depth_view_of(out_filtered));
      warp(p, f, out_filtered, out_stereo.view());
      pack_cpu(p.pack, out_stereo.view(), out_packed.view());
    }
  }
};

std::vector<double> time_cpu(const std::function<void(int)> &op, int warmup, int iterations) {
  using clock = std::chrono::steady_clock;
  for (int i = 0; i < warmup; ++i) op(i);
  std::vector<double> ms;
  for (int i = 0; i < iterations; ++i) {
    const auto t0 = clock::now();
    op(warmup + i);
    ms.push_back(std::chrono::duration<double, std::milli>(clock::now() - t0).count());
  }
  return ms;
}

void bench_cpu(const Options &o, Size s, std::vector<HostFrame> frames, Reporter &rep) {
  CpuSizeBench b(o.params, std::move(frames));
  const int iterations = cpu_iterations(o, s);
  for (const std::string &stage : stage_names()) {
    Measurement m;
    m.stage = stage;
    m.device = "cpu";
    m.size = s;
    m.iterations = iterations;
    m.st = stats_of(time_cpu([&](int i) { b.run_stage(stage, o.params, i); }, o.cpu_warmup, iterations));
    m.bytes = stage_bytes(stage, o.format, s, o.params, false);
    rep.emit(m);
  }
}

// ---- GPU timings -------------------------------------------------------------------

#ifdef P3D_BENCH_GPU
struct GpuContext {
  std::string name;
  double copy_gbps = 0;
};

[[noreturn]] void gpu_failure(const std::string &error) {
  std::cerr << "pseudo3d-bench: CUDA error: " << error << "\n";
  std::exit(1);
}

GpuContext bench_gpu_copy(const Options &o, Reporter &rep) {
  GpuContext g;
  g.name = gpu_name();
  const TimingPlan plan{o.gpu_warmup, o.iterations > 0 ? o.iterations : 50};
  std::vector<double> ms;
  std::string error;
  if (!gpu_time_copy(o.copy_bytes, plan, &ms, &error)) gpu_failure(error);
  Measurement m;
  m.stage = "d2d_copy";
  m.device = "gpu";
  m.gpu_name = g.name;
  m.iterations = plan.iterations;
  m.st = stats_of(ms);
  m.bytes = 2.0 * static_cast<double>(o.copy_bytes);  // read + write
  g.copy_gbps = m.gbps();
  m.share = 1.0;
  rep.emit(m);
  return g;
}

void bench_gpu(const Options &o, const GpuContext &g, Size s, const std::vector<HostFrame> &frames, Reporter &rep) {
  const TimingPlan plan{o.gpu_warmup, o.iterations > 0 ? o.iterations : 50};
  std::vector<StageTimes> times;
  std::string error;
  if (!gpu_time_stages(o.params, frames, plan, &times, &error)) gpu_failure(error);
  for (const StageTimes &t : times) {
    Measurement m;
    m.stage = t.stage;
    m.device = "gpu";
    m.gpu_name = g.name;
    m.size = s;
    m.iterations = plan.iterations;
    m.st = stats_of(t.ms);
    m.bytes = stage_bytes(t.stage, o.format, s, o.params, true);
    m.share = g.copy_gbps > 0 ? m.gbps() / g.copy_gbps : 0;
    rep.emit(m);
  }
}
#endif

// ---- run metadata ------------------------------------------------------------------

std::string utc_now(const char *fmt) {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, fmt, &tm);
  return buf;
}

// The commit the binary was built from (with -dirty), or "" when it was not
// built from a git checkout. Recorded at build time: on the GPU machine the
// checkout beside the binary need not be the code that was built.
std::string git_version() { return P3D_BUILD_GIT; }

// Decides which devices run; returns a process exit status, or -1 to go on.
int resolve_devices(Options &o) {
#ifdef P3D_BENCH_GPU
  const bool have_gpu = gpu_present();
  const char *why = "no usable CUDA device";
#else
  const bool have_gpu = false;
  const char *why = "this build has no CUDA support";
#endif
  if (!o.want_gpu || have_gpu) return -1;
  if (o.device_given) {
    std::cerr << "pseudo3d-bench: --device gpu requested but " << why << "\n";
    return kExitNoGpu;
  }
  std::cout << "GPU skipped: " << why << "; timing the CPU only\n";
  o.want_gpu = false;
  return -1;
}

int run(int argc, char **argv) {
  Options o = parse_args(argc, argv);
  const bool scene_mode = !o.scene.scenes.empty();
  // Scene mode runs one device: the CPU unless --device gpu.
  if (scene_mode) o.scene.gpu = o.device_given && o.want_gpu;
  if (scene_mode && !o.scene.gpu) o.want_gpu = false;
  if (is_deep(o.format)) {
    // The scene chains take 8-bit formats.
    if (scene_mode) {
      std::cerr << "pseudo3d-bench: --format " << name_of(kFormats, o.format)
                << " is timed outside scene mode only (the scene chains take 8-bit formats)\n";
      return kExitUsage;
    }
    o.params.yuv = yuv_to_rgb_params(0.299, 0.114, false, 10);  // HostFrame's 10-bit Y'CbCr
  }
  const int early = resolve_devices(o);
  if (early >= 0) return early;
  if (o.cpu_threads > 0) cv::setNumThreads(o.cpu_threads);

  std::ofstream out(o.out_path, std::ios::app);
  if (!out) {
    std::cerr << "pseudo3d-bench: cannot open " << o.out_path << " for appending\n";
    return 1;
  }
  Reporter rep(o, out);
  const std::string run_id = utc_now("%Y%m%dT%H%M%SZ") + "-" + std::to_string(getpid());
  const std::string date = utc_now("%Y-%m-%dT%H:%M:%SZ");
  rep.header(run_id, date, git_version());
  if (scene_mode) {
    const int status = run_scenes(o.scene, o.params, o.format, o.sizes, {run_id, date, git_version(),
                                  name_of(kFormats, o.format)}, out);
    std::cout << "results appended to " << o.out_path << "\n";
    return status;
  }
  rep.table_header();

#ifdef P3D_BENCH_GPU
  GpuContext gpu;
  if (o.want_gpu) gpu = bench_gpu_copy(o, rep);
#endif
  for (const Size s : o.sizes) {
    std::vector<HostFrame> frames = make_frames(o.format, s);
#ifdef P3D_BENCH_GPU
    if (o.want_gpu) bench_gpu(o, gpu, s, frames, rep);
#endif
    if (o.want_cpu) bench_cpu(o, s, std::move(frames), rep);
  }
  std::cout << "results appended to " << o.out_path << "\n";
  return 0;
}

}  // namespace
}  // namespace p3d::bench

int main(int argc, char **argv) {
  try {
    return p3d::bench::run(argc, argv);
  } catch (const std::exception &e) {
    std::cerr << "pseudo3d-bench: " << e.what() << "\n";
    return 1;
  }
}
