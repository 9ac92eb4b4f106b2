#!/usr/bin/python3
"""Builds the data set of the advection-residual model (docs/networks-advect-residual.md):

  /usr/bin/python3 networks/build_dataset_v2.py --out /work/data/dataset_v2 \
      --dynsky build/cli/dynsky --shared ../shared

Sources (one sub-folder each, written by `dynsky sky training-data`; arrays: networks/data.py):
- arm_tsi:          ARM TSI 2017-05-24 15:40-18:09 UTC, broken cumulus, 300 frames, 30 s
- arm_clear:        ARM TSI 12:00-15:39 UTC, clear morning, 440 frames, 30 s
- arm_dusk:         ARM TSI 00:00-01:30 UTC, overcast clearing at dusk, 181 frames, 30 s
- mobotix:          Mobotix, Sophia Antipolis 2020-08-12 06:00-13:59, 480 frames, 60 s (other camera)
- proc_*:           procedural sequences (30 s steps) with exact flow, 8 wind directions, 3-25 m/s,
                    coverage 0.1-0.9, cumulus and cumulus + cirrus; proc_clear_*: coverage 0
                    (clear, the right answer is "no new cloud") at several sun positions.
The clear morning and dusk sets are imported through fake shared folders (the CLI only knows the
names arm-tsi and mobotix): OUT/_shared_NAME/skies/arm_tsi_sgp_20170524 -> the real folder.

Split (by time, fixed): the last 20 % of every source is held out (the existing rule, dataset.py
split_for); of the first 80 %, the last eighth (frames 70-80 %) is a validation part used for
model selection, the rest trains. split.json keeps "train" = [0, 80 %) as before, and adds
"fit" = [0, 70 %) and "val" = [70 %, 80 %).
"""
import argparse
import json
import os
import shutil
import subprocess
import sys

from split_info import photographs_trained, same_split

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
HELDOUT_FRACTION = 0.2
VAL_FRACTION = 0.1

REAL = [  # name, CLI sequence name, folder under shared/skies that plays it
    ("arm_tsi", "arm-tsi", "arm_tsi_sgp_20170524"),
    ("arm_clear", "arm-tsi", "arm_tsi_sgp_20170524_clear_morning"),
    ("arm_dusk", "arm-tsi", "arm_tsi_sgp_20170524_overcast_dusk"),
    ("mobotix", "mobotix", "mobotix_sophia_20200812_morning"),
]
CLI_FOLDER = {"arm-tsi": "arm_tsi_sgp_20170524", "mobotix": "mobotix_sophia_20200812_morning"}


def procedural_list():
    """(name, seed, args, frames): 16 cloudy sequences over 8 wind directions (each direction once
    with cumulus, once with cumulus + cirrus), speeds 3-25 m/s, coverage 0.1-0.9, cumulus heights
    1.5-3 km, varied sun; and 4 clear ones (coverage 0) at sun elevations 15-75 deg."""
    out = []
    speeds = [3, 6, 9, 12, 15, 18, 22, 25]
    covers = [0.1, 0.25, 0.4, 0.55, 0.7, 0.8, 0.9, 0.3]
    heights = [1500, 2000, 2500, 3000]
    for i in range(16):
        direction = (i % 8) * 45 + (10 if i >= 8 else 0)
        speed = speeds[(i * 3) % 8]
        cover = covers[(i * 5) % 8]
        cirrus = i >= 8
        sun_el = [20, 35, 50, 65, 80, 30, 45, 60][(i * 3 + 1) % 8]
        sun_az = (i * 67 + 30) % 360
        args = ["--coverage", str(cover), "--wind-speed", str(speed), "--wind-from", str(direction), "--cloud-height",
                str(heights[i % 4]), "--sun-elevation", str(sun_el), "--sun-azimuth", str(sun_az),
                "--layers", "cumulus,cirrus" if cirrus else "cumulus"]
        if cirrus:
            args += ["--cirrus-wind", f"{min(30, speed + 8)},{(direction + 30) % 360}"]
        out.append((f"proc_{i:02d}", 100 + i, args, 80))
    for i, (el, az) in enumerate([(15, 90), (35, 200), (55, 300), (75, 140)]):
        out.append((f"proc_clear_{i}", 200 + i, ["--coverage", "0", "--wind-speed", "10", "--wind-from", "270", "--sun-elevation", str(el),
                                                 "--sun-azimuth", str(az)], 60))
    return out


def split_for(frame_count):
    cut = frame_count - int(round(HELDOUT_FRACTION * frame_count))
    val = cut - int(round(VAL_FRACTION * frame_count))
    return {"train": [0, cut], "heldout": [cut, frame_count], "fit": [0, val], "val": [val, cut]}


def run(cmd):
    print("+", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", required=True)
    p.add_argument("--dynsky", default=os.path.join(ROOT, "build", "cli", "dynsky"),
                   help="the dynsky program (default: this checkout's build/cli/dynsky)")
    p.add_argument("--shared", default=os.path.join(os.path.dirname(ROOT), "shared"))
    p.add_argument("--res", type=int, default=64)
    p.add_argument("--import-res", type=int, default=256)
    p.add_argument("--only", default="", help="comma-separated names to (re)build; default all missing")
    args = p.parse_args(argv)
    if not (os.path.isfile(args.dynsky) and os.access(args.dynsky, os.X_OK)):
        sys.exit(f"{args.dynsky}: no dynsky program there (build it, or give --dynsky PATH)")
    os.makedirs(args.out, exist_ok=True)
    common = ["--sky-res", str(args.res), "--import-res", str(args.import_res), "--quiet"]
    only = set(a for a in args.only.split(",") if a)
    names = []
    for name, cli, folder in REAL:
        names.append(name)
        dest = os.path.join(args.out, name)
        if (only and name not in only) or (not only and os.path.exists(os.path.join(dest, "meta.json"))):
            continue
        shared = args.shared
        if folder != CLI_FOLDER[cli]:
            shared = os.path.join(args.out, "_shared_" + name)
            link = os.path.join(shared, "skies", CLI_FOLDER[cli])
            os.makedirs(os.path.dirname(link), exist_ok=True)
            if not os.path.islink(link):
                os.symlink(os.path.join(os.path.abspath(args.shared), "skies", folder), link)
        run([args.dynsky, "sky", "training-data", "--sequence", cli, "--shared", shared, "--out", dest] + common)
    for name, seed, extra, frames in procedural_list():
        names.append(name)
        dest = os.path.join(args.out, name)
        if (only and name not in only) or (not only and os.path.exists(os.path.join(dest, "meta.json"))):
            continue
        tmp = os.path.join(args.out, "_frames_" + name)
        run([args.dynsky, "sky", "procedural", "--cloud-seed", str(seed), "--dt", "30", "--duration", str(30 * (frames - 1)),
             "--sky-res", str(args.import_res), "--quiet", "--out", tmp] + extra)
        run([args.dynsky, "sky", "training-data", "--procedural", tmp, "--out", dest] + common)
        shutil.rmtree(tmp)
    split = {}
    for name in names:
        if not os.path.exists(os.path.join(args.out, name, "meta.json")):
            continue  # not built (--only built others)
        with open(os.path.join(args.out, name, "meta.json")) as f:
            meta = json.load(f)
        split[name] = split_for(meta["frame_count"])
        split[name]["dt_s"] = meta["dt_s"]
        split[name].update(photographs_trained(meta, split[name]["train"][1]))
    path = os.path.join(args.out, "split.json")
    if os.path.exists(path):
        with open(path) as f:
            old = json.load(f)
        for name, s in split.items():
            if name in old and not same_split(old[name], s):
                sys.exit(f"{path}: the fixed split for {name} is {old[name]}, this build would make {s}")
        old.update(split)
        split = old
    with open(path, "w") as f:
        json.dump(split, f, indent=2)
    print(f"wrote {path}: {len(split)} sequences")


if __name__ == "__main__":
    main()
