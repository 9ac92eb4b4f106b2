#!/usr/bin/env python3
"""Chart of bench/sun_seeds' CSV: per seed, the moved sky's horizontal illuminance over the
procedural truth's, frame by frame (docs/animation.md, "The sun and passing clouds").

    /usr/bin/python3 scripts/sun_seeds_chart.py [CSV=docs/sun-seeds.csv] [PNG=docs/sun-seeds.png]
"""
import collections
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

src = sys.argv[1] if len(sys.argv) > 1 else "docs/sun-seeds.csv"
dst = sys.argv[2] if len(sys.argv) > 2 else "docs/sun-seeds.png"
runs = collections.defaultdict(list)
for r in csv.DictReader(open(src)):
    runs[(int(r["seed"]), int(r["kind"]))].append(
        (float(r["t_s"]), float(r["moved_lx"]) / float(r["truth_lx"]), float(r["truth_sun_T"])))
fig, axes = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
for (seed, kind), rows in sorted(runs.items()):
    ax = axes[kind - 1]
    t = [r[0] for r in rows]
    # 20 distinct colours (the default cycle has 10: seeds 3 and 27 came out alike).
    ax.plot(t, [r[1] for r in rows], marker=".", lw=1, label=f"seed {seed}",
            color=plt.get_cmap("tab20")(len(ax.lines) % 20))
for ax, title in zip(axes, ["sun starts clear, a cloud covers it", "sun starts covered, comes out"]):
    ax.axhspan(0.85, 1.15, color="0.9")
    ax.set_ylabel("moved / truth illuminance")
    ax.set_title(title)
    ax.legend(fontsize=6, ncol=7)
axes[1].set_xlabel("t (s)")
fig.tight_layout()
fig.savefig(dst, dpi=90)
print("wrote", dst)
