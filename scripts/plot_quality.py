#!/usr/bin/python3
"""Turns pseudo3d-quality's JSON lines into docs/quality.md and the plot of
error against run time (docs/img/quality-vs-time.png).

Usage: plot_quality.py QUALITY.jsonl OUT.png OUT.md

Run with Debian's /usr/bin/python3 (python3-matplotlib); another python3
first in PATH may lack matplotlib. scripts/quality-report.sh calls this.
"""
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")  # no display on build machines
import matplotlib.pyplot as plt  # noqa: E402

LEVEL = 255.0  # depth errors are reported in 8-bit grey levels
FILL_STYLE = {
    "background": ("tab:blue", "o"),
    "neighbor-average": ("tab:green", "s"),
    "none": ("tab:red", "^"),
}
VARIANT_STYLE = {"exact": ("black", "o"), "stride2": ("tab:orange", "s"), "separable": ("tab:purple", "D")}


def load(path):
    rows = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if line:
                rows.append(json.loads(line))
    return rows


def of_kind(rows, kind):
    return [r for r in rows if r.get("kind") == kind and "error" not in r]


def fmt(v, digits=2):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:.{digits}f}"


def threads(run):
    n = run.get("cpu_threads")
    return f"{n} OpenCV thread{'' if n == 1 else 's'}" if n is not None else "? OpenCV threads"


def sfmt(v, digits=2):
    return fmt(v, digits) if v is None or v < 0 else "+" + fmt(v, digits)


def table(header, lines):
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in line) + " |" for line in lines]
    return "\n".join(out)


# ---- plot -----------------------------------------------------------------------


def plot(rows, png):
    synth = of_kind(rows, "synthesis")
    variants = of_kind(rows, "filter_variant")
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 5.4), dpi=90)

    for fill, (colour, marker) in FILL_STYLE.items():
        pts = sorted((r for r in synth if r["fill"] == fill), key=lambda r: r["radius"])
        if not pts:
            continue
        xs = [r["time_ms"] for r in pts]
        ax1.plot(xs, [r["psnr"] for r in pts], marker=marker, color=colour, label=f"{fill} (all pixels)")
        ax1.plot(xs, [r["psnr_masked"] for r in pts], marker=marker, color=colour, linestyle="--",
                 markerfacecolor="none", label=f"{fill} (known correspondences)")
        for r in pts:
            ax1.annotate(f"r{r['radius']}", (r["time_ms"], r["psnr"]), textcoords="offset points", xytext=(4, 4),
                         fontsize=7, color=colour)
    base = of_kind(rows, "baseline")
    if base:
        ax1.axhline(base[0]["psnr"], color="grey", linestyle=":", linewidth=1, label="left view as is")
    ax1.set_xscale("log")
    ax1.set_xlabel("filter + warp time per frame, ms (CPU, log scale)")
    ax1.set_ylabel("PSNR against aloeR, dB")
    ax1.set_title("Aloe right view: fill x filter radius (r0 = GT depth as is)", fontsize=9)
    ax1.grid(True, which="both", alpha=0.3)
    ax1.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False)

    for variant, (colour, marker) in VARIANT_STYLE.items():
        for inp, style in (("estimated", "-"), ("ground-truth", "--")):
            pts = sorted((r for r in variants if r["variant"] == variant and r["input"] == inp),
                         key=lambda r: r["radius"])
            if not pts:
                continue
            ax2.plot([r["time_ms"] for r in pts], [r["mean_abs"] * LEVEL for r in pts], marker=marker, color=colour,
                     linestyle=style, markerfacecolor=colour if inp == "estimated" else "none",
                     label=f"{variant}, {inp} depth")
            for r in pts:
                ax2.annotate(f"r{r['radius']}", (r["time_ms"], r["mean_abs"] * LEVEL), textcoords="offset points",
                             xytext=(4, 4), fontsize=7, color=colour)
    ax2.set_xscale("log")
    ax2.set_xlabel("filter time per frame, ms (CPU, log scale)")
    ax2.set_ylabel("mean |error| against the exact filter, 8-bit levels")
    ax2.set_title("Cross-bilateral filter: exact window vs faster variants", fontsize=9)
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False)

    run = next((r for r in rows if r.get("kind") == "run"), {})
    fig.suptitle(f"pseudo3d quality vs run time, 1282x1110 Aloe, {run.get('cpu', 'CPU')} "
                 f"({threads(run)}), {run.get('date', '')[:10]}", fontsize=10)
    fig.tight_layout()
    os.makedirs(os.path.dirname(png) or ".", exist_ok=True)
    fig.savefig(png, dpi=90)
    plt.close(fig)


# ---- report ---------------------------------------------------------------------


def outside_share(r):
    """Share of the squared error outside the known-correspondence mask: PSNR
    is 10 log10(peak^2 / MSE), so MSE_mask / MSE_all = 10^((psnr - psnr_masked) / 10)."""
    return 1 - r["mask_fraction"] * 10 ** ((r["psnr"] - r["psnr_masked"]) / 10)


def synthesis_section(rows):
    synth = of_kind(rows, "synthesis")
    if not synth:
        return ["No synthesis measurements in this run."]
    base = of_kind(rows, "baseline")
    lines = []
    for r in sorted(synth, key=lambda r: (r["radius"], list(FILL_STYLE).index(r["fill"]))):
        filt = "GT as is" if r["radius"] == 0 else f"r {r['radius']}, sigma_s {fmt(r['sigma_space'], 1)}"
        lines.append([filt, r["fill"], fmt(r["psnr"]), fmt(r["ssim"], 4), fmt(r["psnr_masked"]),
                      fmt(100 * r["hole_fraction"], 1), fmt(r["filter_ms"], 1), fmt(r["warp_ms"], 1),
                      fmt(r["time_ms"], 1)])
    if base:
        b = base[0]
        lines.append(["(no warp: aloeL as is)", "-", fmt(b["psnr"]), fmt(b["ssim"], 4), fmt(b["psnr_masked"]),
                      "-", "-", "-", "-"])
    out = [table(["depth filter", "fill", "PSNR dB", "SSIM", "PSNR dB, known corr.", "holes %", "filter ms",
                  "warp ms", "total ms"], lines)]
    get = {(r["radius"], r["fill"]): r for r in synth}
    notes = []
    bg0, bg5 = get.get((0, "background")), get.get((5, "background"))
    na0 = get.get((0, "neighbor-average"))
    if bg0 and base:
        notes.append(f"The warp with the true depth and background fill scores {fmt(bg0['psnr'])} dB / SSIM "
                     f"{fmt(bg0['ssim'], 3)}, {fmt(bg0['psnr'] - base[0]['psnr'])} dB over the unwarped left view; "
                     f"on the pixels with a known correspondence it reaches {fmt(bg0['psnr_masked'])} dB. "
                     f"{fmt(100 * outside_share(bg0), 0)} % of the squared error lies in the other "
                     f"{fmt(100 * (1 - bg0['mask_fraction']), 0)} % of the picture, mostly the "
                     f"{fmt(100 * bg0['hole_fraction'], 1)} % the warp leaves as holes: disocclusions, the right "
                     f"border band and the gaps beside unknown-GT pixels (GT 0, so they stay put as far).")
    if bg0 and na0:
        notes.append(f"Neighbour averaging (the paper's inpainting) changes PSNR by {sfmt(na0['psnr'] - bg0['psnr'])} dB "
                     f"and SSIM by {sfmt(na0['ssim'] - bg0['ssim'], 4)} against background fill (smooth colour in "
                     f"the holes suits SSIM, the wrong colour costs PSNR), at "
                     f"{fmt(na0['warp_ms'] / bg0['warp_ms'], 1)}x its warp time (iterations scale with the hole "
                     f"width); `none` shows the unfilled holes (magenta) for scale.")
    if bg0 and bg5:
        notes.append(f"Filtering the true depth does not help: radius 5 costs {fmt(bg0['psnr'] - bg5['psnr'])} dB "
                     f"overall and {fmt(bg0['psnr_masked'] - bg5['psnr_masked'])} dB on known correspondences, since "
                     f"it rounds the depth steps the GT has exactly (and spreads its unknown = 0 pixels). The filter "
                     f"is there for estimated, blocky depth, whose edges it moves onto image edges.")
    return out + [""] + notes


def filter_section(rows):
    variants = of_kind(rows, "filter_variant")
    if not variants:
        return ["No filter-variant measurements in this run."]
    exact = {(r["input"], r["radius"]): r for r in variants if r["variant"] == "exact"}
    lines = []
    for r in sorted(variants, key=lambda r: (r["input"] != "estimated", r["radius"],
                                             list(VARIANT_STYLE).index(r["variant"]))):
        e = exact.get((r["input"], r["radius"]))
        speed = fmt(e["time_ms"] / r["time_ms"], 1) + "x" if e and r["time_ms"] > 0 else "n/a"
        lines.append([r["input"], r["radius"], r["variant"], fmt(r["time_ms"], 1), speed,
                      fmt(r["max_abs"] * LEVEL, 1), fmt(r["mean_abs"] * LEVEL, 3),
                      "exact" if r["variant"] == "exact" else fmt(r["psnr_vs_exact"]),
                      fmt(r.get("synth_psnr")) if "synth_psnr" in r else "-"])
    out = [table(["input depth", "radius", "variant", "ms", "speed-up", "max abs err (levels)",
                  "mean abs err (levels)", "PSNR vs exact dB", "right-view PSNR dB"], lines)]
    notes = []
    for inp in ("estimated", "ground-truth"):
        for radius in (5, 10):
            e = exact.get((inp, radius))
            sep = next((r for r in variants if r["variant"] == "separable" and r["input"] == inp
                        and r["radius"] == radius), None)
            if inp == "estimated" and e and sep:
                notes.append(f"Radius {radius}, estimated depth: the separable variant takes "
                             f"{fmt(sep['time_ms'], 1)} ms against {fmt(e['time_ms'], 1)} ms "
                             f"({fmt(e['time_ms'] / sep['time_ms'], 1)}x faster), off by {fmt(sep['mean_abs'] * LEVEL, 2)} "
                             f"levels on average and {fmt(sep['max_abs'] * LEVEL, 0)} at worst.")
    gt5 = [r for r in variants if r["input"] == "ground-truth" and r["radius"] == 5 and "synth_psnr" in r]
    if gt5:
        spread = max(r["synth_psnr"] for r in gt5) - min(r["synth_psnr"] for r in gt5)
        notes.append(f"Through the warp the variants are within {fmt(spread, 3)} dB of the exact filter's right "
                     f"view at radius 5, although single pixels can be off by tens of levels: at a depth edge, a "
                     f"tap pattern that skips a thin structure (stride 2) or reaches it only through an L-shaped "
                     f"path (separable) can weigh the other side of the edge. The separable pass is the cheapest; "
                     f"its time grows linearly with the radius, the exact window's quadratically.")
    return out + [""] + notes


def depth_section(rows):
    ranks = of_kind(rows, "depth_rank")
    if not ranks:
        return ["No depth-rank measurements in this run."]
    lines = [[r["hypothesis"], fmt(r["edge_threshold"], 0), fmt(r["region_weight"], 2), r["filter_radius"],
              fmt(r["spearman"], 3), fmt(r["time_ms"], 1)] for r in ranks]
    out = [table(["hypothesis", "edge_threshold", "region_weight", "filter radius", "Spearman rho", "ms"], lines)]
    best = max((r for r in ranks if r["spearman"] is not None), key=lambda r: r["spearman"], default=None)
    default = next((r for r in ranks if r["hypothesis"] == "top-bottom" and r["edge_threshold"] == 24
                    and r["region_weight"] == 0.75 and r["filter_radius"] == 5), None)
    notes = []
    if default:
        notes.append(f"With the defaults (top-bottom, edge_threshold 24, region_weight 0.75, filter radius 5) the "
                     f"estimated depth ranks Aloe's pixels with rho = {fmt(default['spearman'], 3)} against the "
                     f"true disparity. The hypothesis decides most of it; edge_threshold and region_weight move rho "
                     f"by a few hundredths, and the filter hardly changes the ranking (it moves block edges onto "
                     f"image edges, a few pixels). Flat has no ordering (n/a).")
    if best:
        notes.append(f"Best here: {best['hypothesis']}, edge_threshold {fmt(best['edge_threshold'], 0)}, "
                     f"region_weight {fmt(best['region_weight'], 2)}, radius {best['filter_radius']} "
                     f"(rho {fmt(best['spearman'], 3)}). One scene is one scene: in Aloe the pot and the floor at "
                     f"the bottom are nearest and the backdrop behind the plant is far, which suits top-bottom.")
    return out + [""] + notes


def flicker_section(rows):
    flick = of_kind(rows, "flicker")
    errors = [r for r in rows if r.get("kind") == "flicker" and "error" in r]
    if errors:
        return [f"Flicker not measured: {errors[0]['error']}"]
    if not flick:
        return ["No flicker measurements in this run."]
    lines = [[r["stage"], fmt(r["temporal_smoothing"], 2), fmt(r["mean_abs"] * LEVEL, 3), fmt(r["p95_abs"] * LEVEL, 3),
              fmt(r["worst_frame_mean_abs"] * LEVEL, 3), fmt(100 * r["share_over_1_level"], 2),
              fmt(r["mean_abs_all_pixels"] * LEVEL, 3), f"{r['cuts']}/{r['smoothed']}/{r['reused']}",
              fmt(r["time_ms"], 1)] for r in flick]
    f0 = flick[0]
    out = [f"{f0['frames']} frames of {f0['video']} ({f0['width']}x{f0['height']}, decoded by OpenCV's "
           f"{f0.get('decoder') or '?'} backend); static background = "
           f"{fmt(100 * f0['mask_fraction'], 1)} % of the pixels (luma standard deviation under "
           f"{fmt(f0['static_std_levels'], 0)} levels over the run). Changes in 8-bit depth levels (1 level = 1/255).",
           "",
           table(["depth", "temporal_smoothing", "mean abs change", "p95", "worst frame mean", "% changes >= 1 level",
                  "mean abs change, all pixels", "cut/smooth/reuse", "ms/frame"], lines)]
    get = {(r["stage"], r["temporal_smoothing"]): r for r in flick}
    off, on = get.get(("filtered", 0.0)), get.get(("filtered", 0.5))
    if off and on and off["mean_abs"] > 0:
        out += ["", f"The depth the warp receives changes by {fmt(off['mean_abs'] * LEVEL, 3)} levels per frame on "
                f"the static background without smoothing and {fmt(on['mean_abs'] * LEVEL, 3)} with the default 0.5 "
                f"({fmt(100 * (1 - on['mean_abs'] / off['mean_abs']), 0)} % less); 95 % of the changes are under "
                f"{fmt(off['p95_abs'] * LEVEL, 2)} and {fmt(on['p95_abs'] * LEVEL, 2)} levels, and only "
                f"{fmt(100 * off['share_over_1_level'], 2)} % and {fmt(100 * on['share_over_1_level'], 2)} % reach "
                f"one level. Background blocks move at all because a block takes region_weight of its region's "
                f"mean: when a walker's blocks join or leave the large background region, that mean shifts and "
                f"every block of the region with it. Smoothing spreads such a step over several frames (so slightly "
                f"more, smaller changes reach one level); its cost is lag on moving objects, which this "
                f"measurement does not see. Frames that hardly change reuse the previous depth outright "
                f"({on['reused']} of {on['frames']} here), with or without smoothing."]
    return out


def report(rows, md, png_rel, data_rel):
    run = next((r for r in rows if r.get("kind") == "run"), {})
    parts = [
        "# Quality against run time",
        "",
        f"Generated by `scripts/quality-report.sh` (tools/pseudo3d_quality.cpp, scripts/plot_quality.py) on "
        f"{run.get('date', '?')}, commit `{run.get('git') or '?'}`, {run.get('cpu', '?')} with "
        f"{threads(run)}, OpenCV {run.get('opencv', '?')}. Raw data: "
        f"[{os.path.basename(data_rel)}]({data_rel}).",
        "",
        f"![error against run time]({png_rel})",
        "",
        "## How it is measured",
        "",
        "Everything runs the CPU reference code of `common/` (the CUDA kernels compute the same functions, so the "
        "errors hold for the GPU too; their times are in [benchmarks.md](benchmarks.md)). Times are wall-clock "
        f"medians of {run.get('runs', '?')} runs, taken round-robin across the configurations of a table so that "
        "a burst of other load slows them alike; the machine is shared: read them as ratios, not absolutes.",
        "",
        "* **View synthesis.** Aloe (Middlebury, 1282x1110): the right view is rendered from aloeL and its "
        "ground-truth disparity exactly as the Aloe element test does (depth = GT / max(GT), view=right, "
        "convergence 0, max-disparity = 100 max(GT) / width, so depth 1 moves by max(GT) pixels), for each hole "
        "fill, with the depth as is or cross-bilateral filtered first (guide aloeL, sigma_range 12, sigma_space = "
        "0.6 radius, which is the element's default 3 at radius 5). PSNR and SSIM against aloeR over the whole "
        "picture; \"known corr.\" is PSNR over the right-view pixels some known-GT left pixel lands on "
        "(x - GT(x), one-pixel gaps closed), which leaves out disocclusions, the right border band and unknown-GT "
        "areas. Time = filter + warp (`warp_render_cpu` renders both views; the left is a copy).",
        "* **Filter variants.** The exact windowed filter (`bilateral_filter_cpu`) against two approximations "
        "implemented in the tool with the same weight tables and threading: *stride2* (only taps with even dx, dy: "
        "a quarter of the window) and *separable* (a 1D cross-bilateral pass along rows, then along columns, "
        "each against the centre's guide: 2(2r+1) taps). Inputs: the estimator's depth of aloeL (what the element "
        "filters) and the GT depth (which also goes through the warp, background fill).",
        "* **Depth estimation.** `DepthEstimatorCpu` + the default filter on aloeL; Spearman rank correlation "
        "(ties get their average rank) with aloeGT over a fixed random sample of 50,000 known-GT pixels "
        "(disparity grows with nearness, like depth).",
        "* **Flicker.** vtest.avi (static camera, people walking) decoded with cv::VideoCapture and fed as I420; "
        "mean |depth(t) - depth(t-1)| over the static-background mask, per frame pair, averaged; p95 of all those "
        "per-pixel changes. `estimate` is the estimator's output, `filtered` what the warp receives. "
        "temporal_smoothing 0 still reuses the depth of frames that hardly change (static_threshold 0.5).",
        "",
        "## View synthesis (Aloe right view)",
        "",
        *synthesis_section(rows),
        "",
        "## Bilateral filter: exact vs faster variants",
        "",
        *filter_section(rows),
        "",
        "## Depth estimator against ground truth",
        "",
        *depth_section(rows),
        "",
        "## Flicker on a static background (vtest.avi)",
        "",
        *flicker_section(rows),
        "",
    ]
    with open(md, "w") as f:
        f.write("\n".join(parts))


def main():
    if len(sys.argv) != 4:
        sys.stderr.write(__doc__)
        return 64
    src, png, md = sys.argv[1:]
    rows = load(src)
    plot(rows, png)
    here = os.path.dirname(md) or "."
    report(rows, md, os.path.relpath(png, here), os.path.relpath(src, here))
    print(f"{png}: {os.path.getsize(png) // 1024} KiB; {md}: {sum(1 for _ in open(md))} lines")
    return 0


if __name__ == "__main__":
    sys.exit(main())
