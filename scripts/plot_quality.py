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
import re
import sys

import matplotlib

matplotlib.use("Agg")  # no display on build machines
import matplotlib.pyplot as plt  # noqa: E402

LEVEL = 255.0  # depth errors are reported in 8-bit grey levels
FILL_STYLE = {
    "background-smooth": ("tab:purple", "D"),
    "background": ("tab:blue", "o"),
    "neighbor-average": ("tab:green", "s"),
    "none": ("tab:red", "^"),
}
VARIANT_STYLE = {"exact": ("black", "o"), "stride2": ("tab:orange", "s"), "separable": ("tab:purple", "D")}


def load(path):
    """The file's rows, each measurement tagged (key "_run") with the run line
    before it: a study measured again is merged by replacing its rows with
    the new file's, run line first, so every row keeps its provenance."""
    rows, run = [], {}
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line:
                continue
            r = json.loads(line)
            if r.get("kind") == "run":
                run = r
            else:
                r["_run"] = run
                if "setting" in r:
                    r["setting"] = OLD_SETTINGS.get(r["setting"], r["setting"])
                if "cue" in r:
                    r["cue"] = OLD_CUES.get(r["cue"], r["cue"])
            rows.append(r)
    return rows


def run_of(rows):
    """The run line of a study's rows (its first row's)."""
    return rows[0].get("_run", {}) if rows else {}


def provenance(run):
    """Machine, date, commit and command of one run, for a table's header."""
    git = run.get("git") or "?"
    commit = f"`{git[:-6]}` (with uncommitted changes)" if git.endswith("-dirty") else f"`{git}`"
    runs = run.get("runs")
    timing = "one run per configuration" if runs == 1 else f"medians of {runs or '?'} runs"
    return (f"Measured on {cpu_name(run)} with {threads(run)}, OpenCV {run.get('opencv', '?')}, "
            f"{run.get('date', '?')[:10]}, commit {commit}, {timing}: `{run.get('args', '?')}`.")


# The comparison settings of the flicker and depth studies, as
# tools/dev/quality/ labels them. Lines written before those labels named
# what they set carry older keys; load() renames them.
COARSE = "4-pixel blocks, no feature smoothing"
COARSE_NO_CONTACT = "4-pixel blocks, no feature smoothing, no ground contact"
NO_CONTACT = "no ground contact"
OLD_SETTINGS = {"2026-11-22": COARSE, "previous": COARSE_NO_CONTACT}
OLD_CUES = {"previous": NO_CONTACT}


def setting_name(r):
    return r.get("setting", "defaults")


def of_kind(rows, kind):
    return [r for r in rows if r.get("kind") == kind and "error" not in r]


def fmt(v, digits=2):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:.{digits}f}"


def threads(run):
    n = run.get("cpu_threads")
    return f"{n} OpenCV thread{'' if n == 1 else 's'}" if n is not None else "? OpenCV threads"


def cpu_name(run):
    """The run's CPU model without trademark marks."""
    return " ".join(re.sub(r"\((R|TM)\)", "", run.get("cpu") or "?").split())


def machine(run):
    """A run's CPU, threads and date, for a plot's panel."""
    return f"{cpu_name(run)}, {threads(run)}, {run.get('date', '?')[:10]}"


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
    ax1.set_title(f"Aloe right view: fill x filter radius (r0 = GT depth as is)\n{machine(run_of(synth))}",
                  fontsize=9)
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
    ax2.set_title(f"Cross-bilateral filter: exact window vs faster variants\n{machine(run_of(variants))}",
                  fontsize=9)
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False)

    fig.suptitle("pseudo3d quality vs run time, 1282x1110 Aloe, CPU reference", fontsize=10)
    fig.tight_layout()
    os.makedirs(os.path.dirname(png) or ".", exist_ok=True)
    fig.savefig(png, dpi=90)
    plt.close(fig)


# ---- report ---------------------------------------------------------------------


def outside_share(r):
    """Share of the squared error outside the known-correspondence mask: PSNR
    is 10 log10(peak^2 / MSE), so MSE_mask / MSE_all = 10^((psnr - psnr_masked) / 10)."""
    return 1 - r["mask_fraction"] * 10 ** ((r["psnr"] - r["psnr_masked"]) / 10)


def lowers(a, b):
    """'lowers' where going from a to b lowers the figure, else 'raises'."""
    return "lowers" if b < a else "raises"


def synthesis_section(rows):
    synth = of_kind(rows, "synthesis")
    if not synth:
        return ["No synthesis measurements in this run."]
    base = of_kind(rows, "baseline")
    lines = []
    for r in sorted(synth, key=lambda r: (r["radius"], list(FILL_STYLE).index(r["fill"]))):
        filt = "GT as is" if r["radius"] == 0 else f"r {r['radius']}, sigma_s {fmt(r['sigma_space'], 1)}"
        lines.append([filt, r["fill"], fmt(r["psnr"]), fmt(r["ssim"], 4), fmt(r["psnr_masked"]),
                      fmt(r.get("psnr_holes")), fmt(100 * r["hole_fraction"], 1), fmt(r["filter_ms"], 1),
                      fmt(r["warp_ms"], 1), fmt(r["time_ms"], 1)])
    if base:
        b = base[0]
        lines.append(["(no warp: aloeL as is)", "-", fmt(b["psnr"]), fmt(b["ssim"], 4), fmt(b["psnr_masked"]),
                      "-", "-", "-", "-", "-"])
    out = [provenance(run_of(synth)) + " The bounds below come from the same run.", "",
           table(["depth filter", "fill", "PSNR dB", "SSIM", "PSNR dB, known corr.", "PSNR dB, holes", "holes %",
                  "filter ms", "warp ms", "total ms"], lines)]
    get = {(r["radius"], r["fill"]): r for r in synth}
    notes = []
    sm0, bg0 = get.get((0, "background-smooth")), get.get((0, "background"))
    sm5 = get.get((5, "background-smooth"))
    na0 = get.get((0, "neighbor-average"))
    if sm0 and bg0 and base:
        notes.append(f"The warp with the true depth scores {fmt(sm0['psnr'])} dB / SSIM {fmt(sm0['ssim'], 3)} with "
                     f"fill=background-smooth, the default, against {fmt(bg0['psnr'])} dB / {fmt(bg0['ssim'], 3)} "
                     f"with background ({sfmt(sm0['psnr'] - bg0['psnr'])} dB, {sfmt(sm0['ssim'] - bg0['ssim'], 4)} "
                     f"SSIM), for {fmt(sm0['warp_ms'] - bg0['warp_ms'], 1)} ms more warp time here; that gain is "
                     f"why it is the default (its GPU cost: [benchmarks.md](benchmarks.md#default-fill), "
                     f"\"Default fill\"). It scores "
                     f"{fmt(sm0['psnr'] - base[0]['psnr'])} dB over the unwarped left view. On the pixels with a known "
                     f"correspondence it reaches {fmt(sm0['psnr_masked'])} dB; "
                     f"{fmt(100 * outside_share(sm0), 0)} % of the squared error lies in the other "
                     f"{fmt(100 * (1 - sm0['mask_fraction']), 0)} % of the picture, mostly the "
                     f"{fmt(100 * sm0['hole_fraction'], 1)} % the warp leaves as holes (disocclusions, the right border "
                     f"band, the gaps beside unknown-GT pixels), where it scores {fmt(sm0['psnr_holes'])} dB against "
                     f"{fmt(bg0['psnr_holes'])} dB for background.")
    if sm0 and bg0 and na0:
        notes.append(f"Neighbour averaging (the paper's inpainting) scores {fmt(na0['psnr'])} dB / "
                     f"{fmt(na0['ssim'], 3)} at {fmt(na0['warp_ms'] / bg0['warp_ms'], 1)}x background's warp time "
                     f"(iterations scale with the hole width); `none` shows the unfilled holes (magenta) for scale.")
    if sm0 and sm5:
        notes.append(f"Filtering the true depth does not help: radius 5 costs {fmt(sm0['psnr'] - sm5['psnr'])} dB "
                     f"overall and {fmt(sm0['psnr_masked'] - sm5['psnr_masked'])} dB on known correspondences, since "
                     f"it rounds the depth steps the GT has exactly (and spreads its unknown = 0 pixels). The filter "
                     f"is there for estimated, blocky depth, whose edges it moves onto image edges.")
    return out + [""] + notes


def bounds_section(rows):
    bounds = of_kind(rows, "synthesis_bound")
    if not bounds:
        return ["No bounds in this run."]
    lines = [["aloeR itself" if r["blur_sigma"] == 0 else f"aloeR blurred, sigma {fmt(r['blur_sigma'], 0)}",
              fmt(r["psnr"]), fmt(r["ssim"], 4), fmt(r["psnr_holes"])] for r in bounds]
    out = [table(["in the GT warp's holes", "PSNR dB", "SSIM", "PSNR dB, holes"], lines)]
    get = {r["blur_sigma"]: r for r in bounds}
    smooth = next((r for r in of_kind(rows, "synthesis") if r["fill"] == "background-smooth" and r["radius"] == 0),
                  None)
    if 4.0 in get and 16.0 in get and smooth:
        out += ["", f"A fill sees nothing of the real right view in its holes. Even aloeR blurred with sigma 4 pixels "
                f"in the holes scores SSIM {fmt(get[4.0]['ssim'], 3)}, and sigma 16 {fmt(get[16.0]['ssim'], 3)}: SSIM's "
                f"11-pixel window rewards detail only where it matches the real view, and detail that does not match "
                f"(texture copied from the background, noise) scores lower than none. The best fill's (`background-smooth`) SSIM "
                f"({fmt(smooth['ssim'], 3)}) sits at the level of the blurred truth's; what is left to gain is "
                f"matching structure (exemplar inpainting, a learned model), not smoothness. In PSNR the fill reaches "
                f"{fmt(smooth['psnr_holes'])} dB in the holes, against {fmt(get[16.0]['psnr_holes'])} dB for the "
                f"truth blurred with sigma 16."]
    return out


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
    out = [provenance(run_of(variants)), "",
           table(["input depth", "radius", "variant", "ms", "speed-up", "max abs err (levels)",
                  "mean abs err (levels)", "PSNR vs exact dB", "right-view PSNR dB"], lines)]
    notes = []
    sep = {radius: next((r for r in variants if r["variant"] == "separable" and r["input"] == "estimated"
                         and r["radius"] == radius), None) for radius in (5, 10)}
    ex = {radius: exact.get(("estimated", radius)) for radius in (5, 10)}
    if all(sep.values()) and all(ex.values()):
        speed = {k: fmt(ex[k]["time_ms"] / sep[k]["time_ms"], 1) for k in (5, 10)}
        notes.append(f"On the estimated depth the separable variant is {speed[5]}x as fast as the exact window at "
                     f"radius 5 and {speed[10]}x at radius 10, off by {fmt(sep[5]['mean_abs'] * LEVEL, 2)} and "
                     f"{fmt(sep[10]['mean_abs'] * LEVEL, 2)} levels on average ({fmt(sep[5]['max_abs'] * LEVEL, 0)} "
                     f"and {fmt(sep[10]['max_abs'] * LEVEL, 0)} at worst).")
    gt5 = [r for r in variants if r["input"] == "ground-truth" and r["radius"] == 5 and r.get("synth_psnr")]
    if gt5:
        spread = max(r["synth_psnr"] for r in gt5) - min(r["synth_psnr"] for r in gt5)
        notes.append(f"Through the warp the variants are within {fmt(spread, 3)} dB of the exact filter's right "
                     f"view at radius 5, although single pixels can be off by tens of levels: at a depth edge, a "
                     f"tap pattern that skips a thin structure (stride 2) or reaches it only through an L-shaped "
                     f"path (separable) can weigh the other side of the edge. The separable pass is the cheapest; "
                     f"its time grows linearly with the radius, the exact window's quadratically. It is "
                     f"`BilateralParams::mode = Separable` in common/bilateral.h (CPU and GPU).")
    return out + [""] + notes


def cue_label(r):
    """A depth-rank row's cue by name; input_format rows with their format."""
    if r["cue"] == "input_format":
        return f"input_format {r.get('format', '?')}"
    return r["cue"]


def depth_section(rows):
    ranks = of_kind(rows, "depth_rank")
    if not ranks:
        return ["No depth-rank measurements in this run."]
    key = lambda r: (r["cue"], r.get("format"), r["hypothesis"], r["block_size"], r["edge_threshold"],
                     r["region_weight"], r["ground_contact"], r["filter_radius"])
    half = {key(r): r for r in ranks if r.get("scale") == "half"}
    lines = []
    for r in ranks:
        if r.get("scale") != "full":
            continue
        h = half.get(key(r))
        lines.append([cue_label(r), r["hypothesis"], block_label(r), fmt(r["edge_threshold"], 0),
                      fmt(r["region_weight"], 2), fmt(r["ground_contact"], 2), r["filter_radius"],
                      fmt(r["spearman"], 3), fmt(h["spearman"], 3) if h else "-", fmt(r["time_ms"], 1)])
    full0 = next((r for r in ranks if r.get("scale") == "full"), {})
    half0 = next((r for r in ranks if r.get("scale") == "half"), {})
    out = [provenance(run_of(ranks)), "",
           f"Full size {full0.get('width', '?')}x{full0.get('height', '?')}, half size "
           f"{half0.get('width', '?')}x{half0.get('height', '?')}, RGBA unless the cue is input_format; each row "
           f"moves one cue away from the defaults, but `{NO_CONTACT}`: the estimator without the "
           f"ground-contact cue and the automatic block size (ground_contact 0, block_size 4, region_weight 0.75). "
           f"block_size `auto (n)`: the automatic size and what it came to.",
           "",
           table(["cue", "hypothesis", "block_size", "edge_threshold", "region_weight", "ground_contact",
                  "filter radius", "rho full", "rho half", "ms (full)"], lines)]

    def find(scale, cue, **kv):
        return next((r for r in ranks if r.get("scale") == scale and r["cue"] == cue
                     and all(r.get(k) == v for k, v in kv.items())), None)
    d = {s: find(s, "defaults") for s in ("full", "half")}
    p = {s: find(s, NO_CONTACT) for s in ("full", "half")}
    b4 = {s: find(s, "block_size", block_size=4) for s in ("full", "half")}
    g0 = {s: find(s, "ground_contact", ground_contact=0.0) for s in ("full", "half")}
    notes = []
    if all(d.values()) and all(p.values()) and all(b4.values()):
        notes.append(f"With the defaults rho is {fmt(d['full']['spearman'], 3)} at full size and "
                     f"{fmt(d['half']['spearman'], 3)} at half size, against {fmt(b4['full']['spearman'], 3)} and "
                     f"{fmt(b4['half']['spearman'], 3)} with 4-pixel blocks and {fmt(p['full']['spearman'], 3)} and "
                     f"{fmt(p['half']['spearman'], 3)} with `{NO_CONTACT}`.")
    if all(d.values()) and all(g0.values()):
        notes.append(f"Ground contact (a region takes the hypothesis of its nearest block: for top-bottom its lowest "
                     f"one, where an object stands on the ground) with region_weight 0.9 raises rho from "
                     f"{fmt(g0['full']['spearman'], 3)} to {fmt(d['full']['spearman'], 3)} at full size and from "
                     f"{fmt(g0['half']['spearman'], 3)} to {fmt(d['half']['spearman'], 3)} at half size. The cue "
                     f"depends on regions staying whole: with 4-pixel blocks at half size, twice as coarse relative "
                     f"to the picture, thin leaves break away from the plant and each takes its own contact.")
    if all(d.values()):
        notes.append(f"The automatic block size (block_size 0, the default: one block per 540 pixels of the "
                     f"picture's shorter side, at least 2) comes to {d['full'].get('effective_block_size')} at both "
                     f"of Aloe's sizes, which keeps the leaves whole, and to 2 up to 1080p, 4 at 4K, 8 at 8K: blocks "
                     f"cover the same share of the scene at every resolution. On video, 2-pixel blocks flicker more "
                     f"than 4-pixel ones (see Flicker below).")
    notes.append("The other cues: region_weight moves rho monotonically (the more a block takes its region's value, "
                 "the more the ground contact counts); edge_threshold has a broad optimum around 24-32 and collapses "
                 "at 48, where the backdrop merges with the floor and one region spans the picture; the filter "
                 "hardly changes the ranking (it moves block edges onto image edges, a few pixels). Flat has no "
                 "ordering (n/a). One scene is one scene: in Aloe the pot and the floor are nearest and the plant "
                 "stands in front of a backdrop, which suits top-bottom and the ground contact; a scene whose ground "
                 "is one region reaching the bottom of the picture gets that whole region near (vtest.avi's lawn "
                 "and road), the depth then separates objects from the ground less by height in the picture.")
    return out + [""] + notes


def block_label(r):
    """block_size as set, with the size it came to for block_size 0 (auto)."""
    if r.get("block_size") == 0:
        return f"auto ({r.get('effective_block_size', '?')})"
    return r.get("block_size")


def flicker_section(rows):
    flick = of_kind(rows, "flicker")
    errors = [r for r in rows if r.get("kind") == "flicker" and "error" in r]
    if errors:
        return [f"Flicker not measured: {errors[0]['error']}"]
    if not flick:
        return ["No flicker measurements in this run."]
    lines = [[setting_name(r), r["stage"], fmt(r["temporal_smoothing"], 2),
              fmt(r["mean_abs"] * LEVEL, 3), fmt(r["p95_abs"] * LEVEL, 3),
              fmt(r["worst_frame_mean_abs"] * LEVEL, 3), fmt(100 * r["share_over_1_level"], 2),
              fmt(r["mean_abs_all_pixels"] * LEVEL, 3), fmt(r.get("depth_std", float("nan")) * LEVEL, 1),
              f"{r['cuts']}/{r['smoothed']}/{r['reused']}", fmt(r["time_ms"], 1)] for r in flick]
    f0 = flick[0]
    out = [provenance(run_of(flick)), "",
           f"{f0['frames']} frames of {f0['video']} ({f0['width']}x{f0['height']}, decoded by OpenCV's "
           f"{f0.get('decoder') or '?'} backend); static background = "
           f"{fmt(100 * f0['mask_fraction'], 1)} % of the pixels (luma standard deviation under "
           f"{fmt(f0['static_std_levels'], 0)} levels over the run). Changes in 8-bit depth levels (1 level = 1/255); "
           f"depth std = the spatial standard deviation of each depth map, averaged over the frames (how much of the "
           f"depth range the setting uses).",
           "",
           table(["setting", "depth", "temporal_smoothing", "mean abs change", "p95", "worst frame mean",
                  "% changes >= 1 level", "mean abs change, all pixels", "depth std", "cut/smooth/reuse",
                  "ms/frame"], lines)]
    get = {(r.get("setting", "defaults"), r["stage"], r["temporal_smoothing"]): r for r in flick}
    on, off = get.get(("defaults", "filtered", 0.5)), get.get(("defaults", "filtered", 0.0))
    strong = get.get(("defaults", "filtered", 0.9))
    coarse_plain, no_contact = get.get((COARSE, "filtered", 0.5)), get.get((COARSE_NO_CONTACT, "filtered", 0.5))
    fine = get.get(("block_size 2, no feature smoothing", "filtered", 0.5))
    coarse, light = get.get(("block_size 4", "filtered", 0.5)), get.get(("feature_smoothing 0.5", "filtered", 0.5))
    lv = lambda r: fmt(r["mean_abs"] * LEVEL, 3)
    notes = []
    if on and coarse_plain and no_contact:
        notes.append(f"With the defaults (automatic block size, here {on.get('effective_block_size', '?')} pixels; "
                     f"feature smoothing {fmt(on.get('feature_smoothing', float('nan')), 2)}; temporal smoothing 0.5) "
                     f"the depth the warp receives changes by {lv(on)} levels per frame on the static background; "
                     f"{fmt(100 * on['share_over_1_level'], 2)} % of the changes reach one level, and over all "
                     f"pixels, walkers included, the change is {fmt(on['mean_abs_all_pixels'] * LEVEL, 2)} levels per "
                     f"frame. With 4-pixel blocks and no feature smoothing the static background changes by "
                     f"{lv(coarse_plain)} levels, and without the ground-contact cue as well by {lv(no_contact)} "
                     f"(depth std {fmt(no_contact['depth_std'] * LEVEL, 1)} levels against "
                     f"{fmt(on['depth_std'] * LEVEL, 1)}). The defaults keep the finer blocks and the ground contact "
                     f"for the depth they give (Aloe's rank correlation above) at this cost in flicker.")
    if fine and coarse and light and coarse_plain and on:
        notes.append(f"Each setting alone: 4-pixel blocks with feature smoothing change by {lv(coarse)} levels per "
                     f"frame against {lv(on)} with the automatic 2-pixel blocks: a 2x2 block of 4:2:0 video carries "
                     f"one chroma sample and twice the noise of a 4x4 block mean, so edges near the threshold flip "
                     f"from frame to frame. Feature smoothing (edges compare block colours averaged over the frames "
                     f"since the block last moved by 8 levels) {lowers(fine['mean_abs'], on['mean_abs'])} the flicker "
                     f"from {lv(fine)} to {lv(on)} levels with 2-pixel blocks and from {lv(coarse_plain)} to "
                     f"{lv(coarse)} with 4-pixel blocks; a weight of 0.5 gives {lv(light)}.")
    if on and off and strong:
        notes.append(f"Temporal smoothing {lowers(off['mean_abs'], on['mean_abs'])} it from {lv(off)} levels "
                     f"(0) to {lv(on)} (0.5) and {lv(strong)} (0.9); its cost is lag on moving objects, which this "
                     f"measurement does not see. Frames that hardly change reuse the previous depth outright "
                     f"({on['reused']} of {on['frames']} here), with or without smoothing.")
    return out + [""] + notes


def hand_written(md, name):
    """Sections measured elsewhere (element tests, one-off studies), kept in
    quality-notes/ beside the report so that regenerating it keeps them."""
    path = os.path.join(os.path.dirname(os.path.abspath(md)), "quality-notes", name)
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return f.read().strip("\n").split("\n") + [""]


def report(rows, md, png_rel, data_rel):
    parts = [
        "# Quality against run time",
        "",
        "How close pseudo3d's output comes to the truth on real data (the Middlebury Aloe pair, vtest.avi) and "
        "what each setting costs in run time. `pseudo3d-quality` (tools/dev/quality/) runs the CPU reference code of "
        "`common/`; the CUDA kernels compute the same functions, so the errors hold for the GPU too. All times "
        "here are CPU times; the GPU's are in [benchmarks.md](benchmarks.md) (\"GPU chain\", \"Filter kernel "
        "variants\", \"Default fill\").",
        "",
        f"`scripts/quality-report.sh` runs every study and writes the raw lines "
        f"([{os.path.basename(data_rel)}]({data_rel})), this page and the plot (scripts/plot_quality.py); "
        f"`pseudo3d-quality --only PART` runs one study, whose lines, run line first, replace that study's in "
        f"{os.path.basename(data_rel)}. Sections measured elsewhere (element tests, studies kept apart) live in "
        f"[quality-notes/](quality-notes/) and are copied in. Each table names the machine, date, commit and "
        f"command that measured it.",
        "",
        f"![error against run time]({png_rel})",
        "",
        "## How it is measured",
        "",
        "Times are wall-clock medians of the runs a table's header gives, taken round-robin across the "
        "configurations of a table so that a burst of other load slows them alike; the machines are shared: read "
        "times as ratios within a table, not as absolutes.",
        "",
        "* **View synthesis.** Aloe (Middlebury, 1282x1110): the right view is rendered from aloeL and its "
        "ground-truth disparity exactly as the Aloe element test does (depth = GT / max(GT), view=right, "
        "convergence 0, max-disparity = 100 max(GT) / width, so depth 1 moves by max(GT) pixels), for each hole "
        "fill, with the depth as is or cross-bilateral filtered first (guide aloeL, sigma_range 12, sigma_space = "
        "0.6 radius, which is the element's default 3 at radius 5). PSNR and SSIM against aloeR over the whole "
        "picture; \"known corr.\" is PSNR over the right-view pixels some known-GT left pixel lands on "
        "(x - GT(x), one-pixel gaps closed), which leaves out disocclusions, the right border band and unknown-GT "
        "areas; \"holes\" is PSNR over the pixels the warp leaves as holes. Time = filter + warp "
        "(`warp_render_cpu` renders both views; the left is a copy). The bounds put aloeR itself (sharp or "
        "blurred) into the holes of the GT warp.",
        "* **Filter variants.** The exact windowed filter (`bilateral_filter_cpu`, mode Exact) against two "
        "approximations with the same weight tables and threading: *separable* (mode Separable of "
        "common/bilateral.h: a 1D cross-bilateral pass along rows, then along columns, each against the centre's "
        "guide: 2(2r+1) taps) and *stride2* (a study in tools/dev/quality/: only taps with even dx, dy, a quarter of "
        "the window). Inputs: the estimator's depth of aloeL (what the element filters) and the GT depth (which "
        "also goes through the warp, fill=background-smooth).",
        "* **Depth estimation.** `DepthEstimatorCpu` + the default filter on aloeL; Spearman rank correlation "
        "(ties get their average rank) with aloeGT over a fixed random sample of 50,000 known-GT pixels "
        "(disparity grows with nearness, like depth), at full size and at half size (aloeL INTER_AREA-downscaled, "
        "the GT sampled nearest).",
        "* **Flicker.** vtest.avi (static camera, people walking) decoded with cv::VideoCapture and fed as I420; "
        "mean |depth(t) - depth(t-1)| over the static-background mask, per frame pair, averaged; p95 of all those "
        "per-pixel changes. `estimate` is the estimator's output, `filtered` what the warp receives. "
        "temporal_smoothing 0 still reuses the depth of frames that hardly change (static_threshold 0.5). "
        f"Settings: the defaults at three temporal smoothings; \"{COARSE}\"; "
        f"\"{COARSE_NO_CONTACT}\" (region_weight 0.75 too); and the block size and the feature smoothing "
        "each moved alone.",
        "",
        "## View synthesis (Aloe right view)",
        "",
        *synthesis_section(rows),
        "",
        "### What a fill can reach",
        "",
        *bounds_section(rows),
        "",
        *hand_written(md, "peer-fills.md"),
        *hand_written(md, "external-depth.md"),
        "## Bilateral filter: exact vs faster variants",
        "",
        *filter_section(rows),
        "",
        *hand_written(md, "filter-mode.md"),
        *hand_written(md, "filter-scale.md"),
        "## Depth estimator against ground truth",
        "",
        *depth_section(rows),
        "",
        *hand_written(md, "depth-vtest.md"),
        *hand_written(md, "input-format.md"),
        "## Flicker on a static background (vtest.avi)",
        "",
        *flicker_section(rows),
        "",
        *hand_written(md, "reuse-tolerance.md"),
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
