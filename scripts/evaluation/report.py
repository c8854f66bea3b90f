#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Plots and summary of the evaluation report, called by scripts/evaluate.sh.

    report.py encoding|quality|compressors|latency|codecs|summary|check OUTDIR [--size S --wall SECONDS]

Every PNG is written beside the CSV it plots (same stem) together with STEM.cmd.txt, the
commands that made the CSV and the plot (taken from OUTDIR/commands.log).
"""
import csv
import glob
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402

COLORS = {"DS": "tab:gray", "FAM": "tab:blue", "Adaptive-FAM": "tab:red", "inlevel": "tab:purple",
          "adaptive": "tab:red", "fixed": "tab:blue", "zfp": "tab:green", "fpzip": "tab:orange"}


def read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def num(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return float("nan")


def commands(out, words):
    """Lines of commands.log mentioning any of words, plus the plotting command."""
    lines = []
    log = os.path.join(out, "commands.log")
    if os.path.exists(log):
        for line in open(log):
            if line.startswith("#"):
                continue
            if any(w in line for w in words):
                lines.append(line.rstrip())
    return lines


def save(fig, png, out, words):
    # Log axes: plain numbers at the decades only (minor labels like 3x10^0 overlap).
    for ax in fig.axes:
        for axis, scale in ((ax.xaxis, ax.get_xscale()), (ax.yaxis, ax.get_yscale())):
            if scale == "log":
                axis.set_minor_formatter(matplotlib.ticker.NullFormatter())
                axis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
    fig.tight_layout()
    fig.savefig(png, dpi=80)
    plt.close(fig)
    stem = os.path.splitext(png)[0]
    with open(stem + ".cmd.txt", "w") as f:
        f.write("# commands that produced %s and its CSV (see commands.log for all)\n" % os.path.basename(png))
        for line in commands(out, words):
            f.write(line + "\n")
        f.write(" ".join([os.path.basename(sys.executable)] + sys.argv) + "\n")


def encoding(out):
    rows = read(os.path.join(out, "encoding", "encoding.csv"))
    vols = sorted({r["volume"] for r in rows}, key=lambda v: (v != "ml", v))
    ncol = min(4, len(vols))
    nrow = int(math.ceil(len(vols) / ncol))
    for kind, xkey, xlabel in (("encoding_rmse_vs_time", "seconds", "encode time (s)"),
                               ("encoding_ratio_vs_rmse", "rmse", "achieved RMSE (finest level)")):
        fig, axes = plt.subplots(nrow, ncol, figsize=(3.4 * ncol, 2.9 * nrow), squeeze=False)
        for i, v in enumerate(vols):
            ax = axes[i // ncol][i % ncol]
            for mode in ("adaptive", "inlevel", "fixed"):
                pts = [r for r in rows if r["volume"] == v and r["mode"] == mode]
                if not pts:
                    continue
                if kind == "encoding_rmse_vs_time":
                    xs = [num(r["seconds"]) for r in pts]
                    ys = [num(r["rmse"]) for r in pts]
                else:
                    xs = [num(r["rmse"]) for r in pts]
                    ys = [num(r["ratio_float32"]) for r in pts]
                keep = [k for k in range(len(xs)) if xs[k] > 0 and ys[k] > 0]
                order = sorted(keep, key=lambda k: xs[k])
                if not order:
                    continue
                ax.plot([xs[k] for k in order], [ys[k] for k in order], "o-", color=COLORS[mode],
                        label={"fixed": "fixed NCP (FAM)", "inlevel": "in-level only"}.get(mode, mode), ms=4)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_title(v, fontsize=9)
            ax.set_xlabel(xlabel, fontsize=8)
            ax.set_ylabel("RMSE" if kind == "encoding_rmse_vs_time" else "compression ratio (float32)", fontsize=8)
            ax.tick_params(labelsize=7)
            if i == 0:
                ax.legend(fontsize=7)
        for j in range(len(vols), nrow * ncol):
            axes[j // ncol][j % ncol].axis("off")
        png = os.path.join(out, "encoding", kind + ".png")
        save(fig, png, out, [" encode ", " verify ", " ml "])
        # the CSV beside the plot: the same table
        os.path.exists(png[:-4] + ".csv") or os.symlink("encoding.csv", png[:-4] + ".csv")


def method_of(label):
    for m in ("Adaptive-FAM", "FAM", "DS", "inlevel", "zfp", "fpzip"):
        if label.startswith(m):
            return m
    return label


def quality(out):
    rows = read(os.path.join(out, "quality", "quality.csv"))
    labels = list(dict.fromkeys(r["label"] for r in rows))
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6))
    for ax, key, ylab in zip(axes, ("mse", "psnr", "ssim"), ("image MSE (8-bit RGB)", "PSNR (dB)", "SSIM")):
        for lab in labels:
            pts = [r for r in rows if r["label"] == lab]
            xs = [num(r["render_ms"]) for r in pts]
            ys = [num(r[key]) for r in pts]
            m = method_of(lab)
            ls = "--" if lab.endswith("1e-3") else "-"
            ax.plot(xs, ys, "o" + ls, color=COLORS.get(m, "k"), label=lab, ms=4)
            for r, x, y in zip(pts, xs, ys):
                ax.annotate("%g" % num(r["sample_distance"]), (x, y), fontsize=6, alpha=0.6)
        ax.set_xscale("log")
        if key == "mse":
            ax.set_yscale("log")
        ax.set_xlabel("frame time, warm cache (ms)")
        ax.set_ylabel(ylab)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    v = rows[0]["view"] if rows else "?"
    fig.suptitle("Marschner-Lobb, cross-level view %s of user_1 (labels: sample distance)" % v, fontsize=9)
    png = os.path.join(out, "quality", "quality.png")
    save(fig, png, out, [" quality ", " encode "])


def compressors(out):
    codec = read(os.path.join(out, "compressors", "compressors_codec.csv"))
    q = read(os.path.join(out, "compressors", "compressors_quality.csv"))
    ratio = {}
    dec = {}
    for r in codec:
        ratio["%s_%s" % (r["codec"], r["param"])] = num(r["ratio"])
        dec["%s_%s" % (r["codec"], r["param"])] = num(r["decompress_us_per_block"])
    for r in q:  # B-spline files: float32 micro-block samples / payload bytes (same basis as the codecs)
        if r["label"] not in ratio:
            ratio[r["label"]] = num(r["ratio"])
    rows = []
    for r in q:
        lab = r["label"]
        if lab == "DS":
            continue
        rows.append(dict(method=method_of(lab), label=lab, ratio=ratio.get(lab, float("nan")), mse=num(r["mse"]),
                         psnr=num(r["psnr"]), ssim=num(r["ssim"]), render_ms=num(r["render_ms"]),
                         caching_ms=num(r["caching_ms"]), blocks=int(num(r["blocks"])),
                         decompress_ms=dec.get(lab, 0.0) * num(r["blocks"]) / 1000.0))
    path = os.path.join(out, "compressors", "compressors_vs_ratio.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6))
    for m in ("Adaptive-FAM", "zfp", "fpzip"):
        pts = sorted([r for r in rows if r["method"] == m], key=lambda r: r["ratio"])
        for ax, key in zip(axes[:2], ("psnr", "ssim")):
            ax.plot([r["ratio"] for r in pts], [r[key] for r in pts], "o-", color=COLORS[m], label=m, ms=4)
        axes[2].plot([r["ratio"] for r in pts], [r["caching_ms"] + r["decompress_ms"] for r in pts], "o-",
                     color=COLORS[m], label=m, ms=4)
    for ax, lab in zip(axes, ("PSNR (dB)", "SSIM", "caching + decompression of the view (ms)")):
        ax.set_xscale("log")
        ax.set_xlabel("compression ratio (float32 micro-blocks)")
        ax.set_ylabel(lab)
        ax.axvline(20, color="k", lw=0.5, ls=":")
        ax.grid(alpha=0.3)
    axes[2].set_yscale("log")
    axes[0].legend(fontsize=8)
    fig.suptitle("Compressors on the same micro-blocks (no ghost layer), cross-level view; SZ3 and TTHRESH are not "
                 "packaged in Debian 12", fontsize=9)
    save(fig, path[:-4] + ".png", out, [" compress ", " quality "])


def latency(out):
    summ = read(os.path.join(out, "latency", "latency_summary.csv"))
    trajs = sorted({r["trajectory"] for r in summ})
    fig, axes = plt.subplots(len(trajs), 1, figsize=(10, 3.2 * len(trajs)), squeeze=False)
    for ax, t in zip(axes[:, 0], trajs):
        for meth in ("DS", "FAM", "Adaptive-FAM"):
            rs = [r for r in summ if r["trajectory"] == t and r["method"] == meth and r["prefetch"] == "none"]
            if not rs:
                continue
            per = read(rs[0]["csv"])
            ax.plot([int(p["pov"]) for p in per], [num(p["latency_ms"]) for p in per], color=COLORS[meth],
                    lw=0.8, label="%s (median %.1f ms)" % (meth, num(rs[0]["median_latency_ms"])))
        ax.set_yscale("log")
        ax.set_xlabel("point of view")
        ax.set_ylabel("input latency (ms)")
        ax.set_title("%s, no prefetching" % t, fontsize=9)
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    save(fig, os.path.join(out, "latency", "latency_summary.png"), out, [" replay "])
    # miss rates and medians per prefetcher
    pfs = list(dict.fromkeys(r["prefetch"] for r in summ))
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.4))
    width = 0.8 / max(1, len(pfs))
    meths = ["DS", "FAM", "Adaptive-FAM"]
    for k, pf in enumerate(pfs):
        for ax, key in zip(axes, ("median_latency_ms", "miss_rate")):
            vals = []
            for meth in meths:
                rs = [num(r[key]) for r in summ if r["method"] == meth and r["prefetch"] == pf]
                vals.append(sum(rs) / len(rs) if rs else float("nan"))
            ax.bar([i + k * width for i in range(len(meths))], vals, width, label=pf)
    for ax, lab in zip(axes, ("median input latency (ms), mean of the trajectories", "miss rate")):
        ax.set_xticks([i + 0.4 - width / 2 for i in range(len(meths))])
        ax.set_xticklabels(meths)
        ax.set_ylabel(lab, fontsize=8)
    axes[0].legend(fontsize=7, title="prefetcher", title_fontsize=7)
    path = os.path.join(out, "latency", "latency_prefetch.png")
    save(fig, path, out, [" replay "])
    os.path.exists(path[:-4] + ".csv") or os.symlink("latency_summary.csv", path[:-4] + ".csv")


def codec_pairs(out):
    """(volume, bound, Adaptive-FAM row, ZFP row) from codecs/compare_codecs.csv, in file order."""
    rows = read(os.path.join(out, "codecs", "compare_codecs.csv"))
    afam = {(r["volume"], r["bound"]): r for r in rows if r["codec"] == "adaptive-fam"}
    return [(r["volume"], r["bound"], afam[(r["volume"], r["bound"])], r) for r in rows
            if r["codec"] == "zfp" and (r["volume"], r["bound"]) in afam]


def codecs(out):
    """Adaptive-FAM against ZFP at the same RMSE (afam compare-codecs): ratio per volume, one
    panel per relative bound, log scale, the line at ratio 1 = the raw file's size."""
    pairs = codec_pairs(out)
    bounds = list(dict.fromkeys(b for _, b, _, _ in pairs))
    fig, axes = plt.subplots(1, len(bounds), figsize=(5.5 * len(bounds), 3.8), squeeze=False)
    for ax, b in zip(axes[0], bounds):
        pts = [p for p in pairs if p[1] == b]
        xs = range(len(pts))
        for k, (name, key, color) in enumerate((("Adaptive-FAM (all levels)", 2, COLORS["Adaptive-FAM"]),
                                                 ("ZFP accuracy, RMSE <= Adaptive-FAM's", 3, COLORS["zfp"]))):
            ax.bar([x + (k - 0.5) * 0.4 for x in xs], [num(p[key]["ratio"]) for p in pts], 0.4, color=color,
                   label=name)
        ax.axhline(1, color="k", lw=0.6, ls=":")
        ax.set_yscale("log")
        ax.set_ylim(top=8 * max(num(p[key]["ratio"]) for p in pts for key in (2, 3)))  # room for the legend
        ax.set_xticks(list(xs))
        ax.set_xticklabels([p[0].rsplit("_", 2)[0] for p in pts], rotation=30, ha="right", fontsize=7)
        ax.set_ylabel("ratio: raw file bytes / compressed bytes", fontsize=8)
        ax.set_title("relative RMSE bound %s" % b, fontsize=9)
        ax.grid(alpha=0.3, axis="y")
        ax.legend(fontsize=7, loc="upper left")
    save(fig, os.path.join(out, "codecs", "compare_codecs.png"), out, [" compare-codecs "])


def median(xs):
    xs = sorted(x for x in xs if math.isfinite(x))
    if not xs:
        return float("nan")
    m = len(xs) // 2
    return xs[m] if len(xs) % 2 else 0.5 * (xs[m - 1] + xs[m])


def pareto_replays(out):
    """Pooled figures of the interleaved Pareto replays (scripts/evaluation/pareto_replays.sh):
    per method, medians over every point of view of every round and both trajectories, the range
    of the per-round medians, and the paired per-view difference against Adaptive-FAM (same
    trajectory, same round, same point of view: the same blocks are visible)."""
    path = os.path.join(out, "latency", "pareto_replays.csv")
    if not os.path.exists(path):
        return None
    runs = read(path)
    per = {}  # method -> list of (round, trajectory, pov, latency, caching, render)
    for r in runs:
        for p in read(r["csv"]):
            per.setdefault(r["method"], []).append((r["round"], r["trajectory"], p["pov"], num(p["latency_ms"]),
                                                   num(p["caching_ms"]), num(p["render_ms"])))
    res = {}
    afam = {(a, b, c): l for a, b, c, l, _, _ in per.get("Adaptive-FAM", [])}
    for meth, rows in per.items():
        rounds = sorted({x[0] for x in rows})
        round_meds = [median([x[3] for x in rows if x[0] == k]) for k in rounds]
        d = [x[3] - afam[x[:3]] for x in rows if x[:3] in afam] if meth != "Adaptive-FAM" else []
        res[meth] = dict(latency=median([x[3] for x in rows]), caching=median([x[4] for x in rows]),
                         render=median([x[5] for x in rows]), rounds=len(rounds), views=len(rows),
                         round_min=min(round_meds), round_max=max(round_meds),
                         paired=median(d) if d else float("nan"),
                         frac_faster=(sum(1 for v in d if v < 0) / len(d)) if d else float("nan"))
    return res


def pareto(out):
    """Error (image MSE at the cross-level view, middle sample distance) against latency for
    every method measured on ML. Latency: the interleaved Pareto replays when present (pooled
    medians over every round, both trajectories, no prefetching), otherwise the mean of the
    user_1 and user_2 medians of the single replays without prefetching."""
    q = read(os.path.join(out, "compressors", "compressors_quality.csv"))
    q0 = read(os.path.join(out, "quality", "quality.csv"))
    summ = read(os.path.join(out, "latency", "latency_summary.csv"))
    lat, cach = {}, {}
    pr = pareto_replays(out)
    for meth in ("DS", "FAM", "Adaptive-FAM"):
        if pr is not None and meth in pr:
            lat[meth] = pr[meth]["latency"]
            cach[meth] = pr[meth]["caching"]
            continue
        rs = [num(r["median_latency_ms"]) for r in summ if r["method"] == meth and r["prefetch"] == "none"]
        cs = [num(r["median_caching_ms"]) for r in summ if r["method"] == meth and r["prefetch"] == "none"]
        if rs:
            lat[meth] = sum(rs) / len(rs)
            cach[meth] = sum(cs) / len(cs)
    sd = q[0]["sample_distance"] if q else None
    mse = {}
    for r in q0:
        if r["sample_distance"] == sd:
            mse[r["label"]] = num(r["mse"])
    # the replayed Adaptive-FAM file is the tightest quality bound
    afam_labels = [l for l in mse if l.startswith("Adaptive-FAM")]
    afam_label = sorted(afam_labels, key=lambda l: num(l.split("_")[-1]))[0] if afam_labels else None
    pts = []
    if "DS" in mse and "DS" in lat:
        pts.append(("DS", lat["DS"], mse["DS"]))
    if "FAM" in mse and "FAM" in lat:
        pts.append(("FAM", lat["FAM"], mse["FAM"]))
    if afam_label and "Adaptive-FAM" in lat:
        pts.append(("Adaptive-FAM", lat["Adaptive-FAM"], mse[afam_label]))
    rows = []
    for name, l, e in pts:
        # the bar: no other method is both faster AND more accurate (strictly, in both)
        dominated_by = [o for o, l2, e2 in pts if o != name and l2 < l and e2 < e]
        c = cach[name]
        dom_c = [o for o, _, e2 in pts if o != name and cach[o] < c and e2 < e]
        x = (pr or {}).get(name)
        rows.append(dict(method=name, median_latency_ms=l, image_mse=e, pareto=int(not dominated_by),
                         dominated_by=";".join(dominated_by), median_caching_ms=c,
                         pareto_caching=int(not dom_c), caching_dominated_by=";".join(dom_c),
                         median_render_ms=x["render"] if x else "", rounds=x["rounds"] if x else "",
                         views=x["views"] if x else "",
                         latency_round_min_ms=x["round_min"] if x else "",
                         latency_round_max_ms=x["round_max"] if x else "",
                         paired_minus_afam_ms=x["paired"] if x and name != "Adaptive-FAM" else "",
                         frac_views_faster_than_afam=x["frac_faster"] if x and name != "Adaptive-FAM" else ""))
    path = os.path.join(out, "quality", "pareto_error_vs_latency.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["method", "median_latency_ms", "image_mse", "pareto", "dominated_by",
                                          "median_caching_ms", "pareto_caching", "caching_dominated_by",
                                          "median_render_ms", "rounds", "views", "latency_round_min_ms",
                                          "latency_round_max_ms", "paired_minus_afam_ms",
                                          "frac_views_faster_than_afam"])
        w.writeheader()
        w.writerows(rows)
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    for ax, key, pk, xl in ((axes[0], "median_latency_ms", "pareto", "median input latency (ms)"),
                            (axes[1], "median_caching_ms", "pareto_caching", "median caching time (ms)")):
        for r in rows:
            lab = "%s%s" % (r["method"], "" if r[pk] else " (dominated)")
            if key == "median_latency_ms" and r["latency_round_min_ms"] != "":
                ax.errorbar(r[key], r["image_mse"], xerr=[[r[key] - r["latency_round_min_ms"]],
                                                          [r["latency_round_max_ms"] - r[key]]],
                            fmt="o", color=COLORS[r["method"]], ms=8, capsize=4, label=lab)
            else:
                ax.plot(r[key], r["image_mse"], "o", color=COLORS[r["method"]], ms=8, label=lab)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
        ticks = []
        for t in sorted(round(r[key], 1) for r in rows):
            if not ticks or t > 1.03 * ticks[-1]:
                ticks.append(t)  # methods closer than 3 % share a tick
        ax.set_xticks(ticks)
        ax.set_xlabel(xl + ("\npooled over %s rounds, user_1 + user_2" % rows[0]["rounds"]
                            if pr else "\nmean of user_1, user_2"), fontsize=8)
        ax.set_ylabel("image MSE at the cross-level view")
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    save(fig, path[:-4] + ".png", out, [" replay ", " quality ", "pareto_replays"])
    return rows, afam_label


def summary(out, size, wall):
    rows, afam_label = pareto(out)
    lines = ["# Evaluation summary (%s, wall %s s)" % (size, wall), ""]
    log = os.path.join(out, "commands.log")
    if os.path.exists(log):  # the run's header: command, date, host, git, CPU, device, sizes
        with open(log) as f:
            head = [l.rstrip("\n") for l in f if l.startswith("# ") and not l.startswith("#   ")]
        lines += ["    " + l[2:] for l in head[:5]] + [""]
    af = [r for r in rows if r["method"] == "Adaptive-FAM"]
    if af:
        r = af[0]
        lines.append("Pareto (error vs latency, ML, no prefetching; Adaptive-FAM = %s): Adaptive-FAM is %s%s" % (
            afam_label, "ON the Pareto front" if r["pareto"] else "NOT on the Pareto front",
            "" if r["pareto"] else " (dominated by %s)" % r["dominated_by"]))
        for o in rows:
            if o["method"] != "Adaptive-FAM" and o["paired_minus_afam_ms"] != "":
                lines.append("Paired per view, %s minus Adaptive-FAM latency: median %+.3f ms; %s faster on %.0f%% of "
                             "%s views (%s rounds; per-round medians %s %.2f-%.2f ms, Adaptive-FAM %.2f-%.2f ms)" % (
                                 o["method"], o["paired_minus_afam_ms"], o["method"],
                                 100 * o["frac_views_faster_than_afam"], o["views"], o["rounds"], o["method"],
                                 o["latency_round_min_ms"], o["latency_round_max_ms"],
                                 r["latency_round_min_ms"], r["latency_round_max_ms"]))
        lines.append("Pareto (error vs caching time, the representation-dependent term): Adaptive-FAM is %s" % (
            "ON the front" if r["pareto_caching"] else "NOT on the front (dominated by %s)" % r["caching_dominated_by"]))
    lines.append("")
    lines.append("| method | median latency (ms) | median caching (ms) | image MSE | Pareto (latency) | Pareto (caching) |")
    lines.append("|---|---|---|---|---|---|")
    for r in rows:
        lines.append("| %s | %.2f | %.2f | %.4g | %s | %s |" % (
            r["method"], r["median_latency_ms"], r["median_caching_ms"], r["image_mse"],
            "yes" if r["pareto"] else "no (%s)" % r["dominated_by"],
            "yes" if r["pareto_caching"] else "no (%s)" % r["caching_dominated_by"]))
    lines.append("")
    if os.path.exists(os.path.join(out, "codecs", "compare_codecs.csv")):
        lines.append("| volume | bound | Adaptive-FAM ratio | its RMSE | ZFP ratio, RMSE <= it | ZFP RMSE |")
        lines.append("|---|---|---|---|---|---|")
        for v, b, a, z in codec_pairs(out):
            lines.append("| %s | %s | %.3g | %.4g | %.3g | %.4g |" % (v, b, num(a["ratio"]), num(a["rmse"]),
                                                                  num(z["ratio"]), num(z["rmse"])))
        lines.append("")
    lat = read(os.path.join(out, "latency", "latency_summary.csv"))
    lines.append("| trajectory | method | prefetch | median latency | caching | render | miss rate |")
    lines.append("|---|---|---|---|---|---|---|")
    for r in lat:
        lines.append("| %s | %s | %s | %s | %s | %s | %s |" % (r["trajectory"], r["method"], r["prefetch"],
                                                             r["median_latency_ms"], r["median_caching_ms"],
                                                             r["median_render_ms"], r["miss_rate"]))
    lines.append("")
    for name in ("stability/stability.csv", "stability/seams.csv"):
        rs = read(os.path.join(out, name))
        if not rs:
            continue
        keys = list(rs[0].keys())
        lines.append("| " + " | ".join(keys) + " |")
        lines.append("|" + "---|" * len(keys))
        for r in rs:
            lines.append("| " + " | ".join(r[k] for k in keys) + " |")
        lines.append("")
    # finiteness check of every CSV (the smoke test relies on it)
    bad = []
    for path in glob.glob(os.path.join(out, "*", "*.csv")):
        rs = read(path)
        if not rs:
            bad.append(path + ": empty")
            continue
    with open(os.path.join(out, "summary.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines[:14]))
    if bad:
        print("\n".join(bad), file=sys.stderr)
        sys.exit(1)


def check(out):
    """Every expected CSV exists and is non-empty; every numeric cell is finite (a refused
    stability case may carry nan: that row documents a refusal)."""
    expected = ["encoding/encoding.csv", "quality/quality.csv", "compressors/compressors_codec.csv",
                "compressors/compressors_quality.csv", "compressors/compressors_vs_ratio.csv",
                "latency/latency_summary.csv", "stability/stability.csv", "stability/seams.csv",
                "quality/pareto_error_vs_latency.csv", "latency/pareto_replays.csv", "codecs/compare_codecs.csv"]
    bad = []
    for name in expected:
        path = os.path.join(out, name)
        if not os.path.exists(path):
            bad.append(name + ": missing")
            continue
        rows = read(path)
        if not rows:
            bad.append(name + ": no rows")
        for i, r in enumerate(rows):
            if r.get("status", "ok").startswith("refused"):
                continue
            for k, v in r.items():
                try:
                    x = float(v)
                except (TypeError, ValueError):
                    continue
                if not math.isfinite(x):
                    bad.append("%s row %d %s=%s" % (name, i + 1, k, v))
    for png in glob.glob(os.path.join(out, "*", "*.png")):
        if not os.path.exists(png[:-4] + ".csv") or not os.path.exists(png[:-4] + ".cmd.txt"):
            bad.append(png + ": no CSV or .cmd.txt beside it")
    if bad:
        print("\n".join(bad))
        sys.exit(1)
    print("check ok: %d CSVs, %d PNGs" % (len(expected), len(glob.glob(os.path.join(out, "*", "*.png")))))


def main():
    part, out = sys.argv[1], sys.argv[2]
    if part == "encoding":
        encoding(out)
    elif part == "quality":
        quality(out)
    elif part == "compressors":
        compressors(out)
    elif part == "latency":
        latency(out)
    elif part == "codecs":
        codecs(out)
    elif part == "check":
        check(out)
    elif part == "summary":
        args = dict(zip(sys.argv[3::2], sys.argv[4::2]))
        summary(out, args.get("--size", "?"), args.get("--wall", "?"))
    else:
        sys.exit("unknown part " + part)


if __name__ == "__main__":
    main()
