#!/usr/bin/python3
"""Charts of `dynsky bench sampling` (run by it): reads the CSV files in the report folder given
as the only argument and writes PNGs beside them. Parts that were not run are skipped."""
import csv
import os
import signal
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1]
# An interrupt (the bench sends SIGTERM to its child) unwinds through save()'s clean-up.
signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))


def save(fig, name):
    """Writes the chart under a temporary name and renames it: a failed write (a full disk) leaves
    no partial PNG, and an earlier run's chart stays as it was."""
    path = os.path.join(out, name)
    stem, ext = os.path.splitext(name)
    temporary = os.path.join(out, ".tmp-%s-%d%s" % (stem, os.getpid(), ext))  # the project's naming
    try:
        fig.savefig(temporary, dpi=90)
        os.replace(temporary, path)
    except BaseException:
        if os.path.exists(temporary):
            os.remove(temporary)
        raise


def rows_of(name):
    path = os.path.join(out, name)
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return list(csv.DictReader(f))


# One colour per sampler in every chart (20 distinct: with matplotlib's 10 of its cycle, uniform and
# cdf+mis, alias and sun+cdf+mis, ... shared one in the failure bars).
_names = set()
for _file in ("accuracy_summary.csv", "rebuild.csv", "failures.csv"):
    _names.update(r.get("sampler", "") for r in rows_of(_file))
COLOUR = {n: plt.get_cmap("tab20")(i % 20) for i, n in enumerate(sorted(n for n in _names if n and n != "floor"))}
COLOUR["floor"] = "k"

# Error against spp and against modelled frame time, mean and one standard deviation over seeds.
groups = {}
for r in rows_of("accuracy_summary.csv"):
    groups.setdefault((r["scene"], r["sky"]), {}).setdefault(r["sampler"], []).append(r)
for (scene, sky), by in groups.items():
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.4))
    for name, rs in sorted(by.items()):
        rs.sort(key=lambda r: int(r["spp"]))
        style = "-" if name.endswith("+mis") else "--"
        e = [float(r["trimmed_rmse"]) for r in rs]
        sd = [float(r["trimmed_rmse_std"]) for r in rs]
        t = [1e3 * float(r["seconds"]) for r in rs]
        c = COLOUR.get(name)
        axes[0].errorbar([float(r["spp"]) for r in rs], e, yerr=sd, fmt=style, marker="o", ms=3, capsize=2, label=name,
                         color=c)
        axes[1].errorbar(t, e, yerr=sd, fmt=style, marker="o", ms=3, capsize=2, label=name, color=c)
        axes[2].plot(t, [float(r["rel_mse"]) for r in rs], style, marker="o", ms=3, label=name, color=c)
    axes[0].set_xlabel("samples per pixel")
    axes[1].set_xlabel("modelled frame time (ms): rebuild + spp x ms per spp")
    axes[2].set_xlabel("modelled frame time (ms)")
    axes[0].set_ylabel("RMSE without the worst 0.1% pixels")
    axes[1].set_ylabel("RMSE without the worst 0.1% pixels")
    axes[2].set_ylabel("relative MSE (all pixels, mean over seeds)")
    for a in axes:
        a.set_xscale("log"), a.set_yscale("log")
        a.grid(True, which="both", alpha=0.3)
    axes[1].legend(fontsize=6, ncol=2)
    fig.suptitle("%s scene, %s sky (error bars: one standard deviation over seeds)" % (scene, sky))
    fig.tight_layout()
    save(fig, "rmse_%s_%s.png" % (scene, sky))
    plt.close(fig)

rows = rows_of("rebuild.csv")
if rows:
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for k, threads in enumerate(["1", "all"]):
        by = {}
        for r in rows:
            if r["threads"] == threads:
                by.setdefault(r["sampler"], []).append(r)
        for name, rs in sorted(by.items()):
            rs.sort(key=lambda r: int(r["n"]))
            style = ":" if name == "floor" else "-"
            axes[k].loglog([int(r["n"]) for r in rs], [float(r["ms"]) for r in rs], style, marker="o", ms=3, label=name,
                           color=COLOUR.get(name))
        axes[k].set_title("rebuild, %s thread(s)" % threads)
        axes[k].set_xlabel("sky resolution N")
        axes[k].set_ylabel("ms")
        axes[k].grid(True, which="both", alpha=0.3)
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    save(fig, "rebuild.png")
    plt.close(fig)

rows = rows_of("failures.csv")
if rows:
    cases = sorted(set(r["case"] for r in rows))
    names = sorted(set(r["sampler"] for r in rows))
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    w = 0.8 / max(1, len(names))
    for i, name in enumerate(names):
        vals = {r["case"]: r for r in rows if r["sampler"] == name}
        xs = [c + i * w for c in range(len(cases))]
        axes[0].bar(xs, [float(vals[c]["rel_mse"]) if c in vals else 0 for c in cases], w, label=name,
                    color=COLOUR.get(name))
        axes[1].bar(xs, [float(vals[c]["firefly"]) if c in vals else 0 for c in cases], w, label=name,
                    color=COLOUR.get(name))
    for a, t in zip(axes, ["relative MSE (log)", "share of squared error in brightest 0.1% pixels"]):
        a.set_xticks([c + 0.4 for c in range(len(cases))])
        a.set_xticklabels(cases, rotation=30, fontsize=7)
        a.set_title(t)
    axes[0].set_yscale("log")
    axes[1].legend(fontsize=6, ncol=2)
    fig.tight_layout()
    save(fig, "failures.png")
    plt.close(fig)
