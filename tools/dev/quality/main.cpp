// pseudo3d-quality: error against run time on real data, with the CPU
// reference code (common/). Writes one JSON line per measurement (the first
// line describes the run); scripts/quality-report.sh turns them into
// docs/quality.md and docs/img/quality-vs-time.png. The studies live one per
// file (quality.h lists them); this file reads the command line and runs
// them. Times are medians of --runs runs on this machine's CPU
// (cv::getNumThreads() worker threads, recorded in the run line).
#include <cstdlib>
#include <iostream>
#include <sstream>

#include "cli_args.h"
#include "quality.h"

namespace p3d::quality {
namespace {

constexpr int kExitUsage = 64;
const std::set<std::string> kParts = {"synthesis", "peers", "filter", "depth", "scale", "flicker"};

void print_usage(std::ostream &os) {
  os << "Usage: pseudo3d-quality [options]\n"
        "  --data DIR      aloeL.jpg, aloeR.jpg, aloeGT.png, vtest.avi (default data)\n"
        "  --out FILE      JSON lines written here (default quality.jsonl; truncated)\n"
        "  --runs N        timed runs per measurement, median reported (default 5)\n"
        "  --frames N      vtest.avi frames for the flicker measurement (default 200)\n"
        "  --only LIST     comma separated subset of synthesis,peers,filter,depth,scale,flicker\n"
        "                  (default all but peers, which takes minutes)\n"
        "  --threads N     OpenCV worker threads (default: OpenCV's choice)\n"
        "  --filter-mode M exact or separable: the depth filter of the depth and flicker\n"
        "                  studies (default: pseudo3dfilter's default)\n"
        "  --quick         smoke test: --runs 1 --frames 20\n"
        "Exit status: 0 ok, 1 missing data or I/O error, 64 bad usage.\n";
}

const p3d::tools::Cli kCli("pseudo3d-quality", print_usage, kExitUsage);
[[noreturn]] void usage_error(const std::string &msg) { kCli.fail(msg); }
int parse_int(const std::string &opt, const std::string &v, int lo, int hi) { return kCli.integer(opt, v, lo, hi); }

std::set<std::string> parse_parts(const std::string &v) {
  std::set<std::string> parts;
  std::stringstream ss(v);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!kParts.count(item)) usage_error("unknown part '" + item + "' in --only");
    parts.insert(item);
  }
  if (parts.empty()) usage_error("--only wants at least one part");
  return parts;
}

Options parse_args(int argc, char **argv) {
  Options o;
  bool quick = false, runs_given = false, frames_given = false;
  kCli.parse(argc, argv, "--quick", &o.argv, [&]() { quick = true; }, [&](const std::string &a, const std::string &v) {
    if (a == "--data") {
      o.data_dir = v;
    } else if (a == "--out") {
      o.out_path = v;
    } else if (a == "--runs") {
      o.runs = parse_int(a, v, 1, 1000);
      runs_given = true;
    } else if (a == "--frames") {
      o.frames = parse_int(a, v, 2, 100000);
      frames_given = true;
    } else if (a == "--threads") {
      o.threads = parse_int(a, v, 1, 1024);
    } else if (a == "--only") {
      o.parts = parse_parts(v);
    } else if (a == "--filter-mode") {
      if (v != "exact" && v != "separable") usage_error("--filter-mode wants exact or separable");
      o.filter_mode = v == "exact" ? BilateralMode::Exact : BilateralMode::Separable;
    } else {
      usage_error("unknown option " + a);
    }
  });
  if (quick) {
    if (!runs_given) o.runs = 1;
    if (!frames_given) o.frames = 20;
  }
  return o;
}

int run(const Options &o) {
  std::ofstream out(o.out_path, std::ios::trunc);
  if (!out) {
    std::cerr << "pseudo3d-quality: cannot write " << o.out_path << "\n";
    return 1;
  }
  Writer w(out);
  emit_run_line(w, o);
  int rc = 0;
  const bool need_aloe =
      o.parts.count("synthesis") || o.parts.count("peers") || o.parts.count("filter") || o.parts.count("depth") ||
      o.parts.count("scale");
  Aloe aloe, half;
  std::string err;
  if (need_aloe && (!load_aloe(o.data_dir, 1.0, aloe, err) || !load_aloe(o.data_dir, 0.5, half, err))) {
    w.error("aloe", err);
    rc = 1;
  } else if (need_aloe) {
    if (o.parts.count("synthesis")) {
      measure_baseline(w, aloe);
      measure_synthesis(w, aloe, o.runs);
    }
    if (o.parts.count("peers")) measure_peer_fills(w, aloe);
    if (o.parts.count("filter")) measure_filter_variants(w, aloe, o.runs);
    if (o.parts.count("depth")) measure_depth_rank(w, aloe, half, o.runs, o.filter_mode);
    if (o.parts.count("scale")) measure_filter_scale(w, aloe, o.runs);
  }
  if (o.parts.count("flicker")) measure_flicker(w, o.data_dir + "/vtest.avi", o.frames, o.filter_mode);
  return rc;
}

}  // namespace
}  // namespace p3d::quality

int main(int argc, char **argv) {
  const p3d::quality::Options o = p3d::quality::parse_args(argc, argv);
  if (o.threads > 0) cv::setNumThreads(o.threads);
  try {
    return p3d::quality::run(o);
  } catch (const cv::Exception &e) {
    std::cerr << "pseudo3d-quality: OpenCV error: " << e.what() << "\n";
    return 1;
  }
}
