#!/usr/bin/python3
"""Builds the cloud-model training set (docs/networks.md):

  /usr/bin/python3 networks/dataset.py --out build-nets/dataset

- arm_tsi: the 300 ARM TSI photographs of ../shared/skies/arm_tsi_sgp_20170524 (30 s cadence),
  each imported with the "arm-tsi" camera preset at --import-res exactly as `dynsky sky import
  --preset arm-tsi` does (same library call, same calibration: motion/cloud_model.h,
  import_preset_photo; the in-process call also keeps the import's not-sky mask, which the EXR
  written by the CLI does not carry), HDR-recovered, mapped to [0, 1] and area-averaged to --res.
- proc_*: procedural sequences (`dynsky sky procedural`, 30 s steps) with their exact flow.
Each sequence folder gets images, seen-sky and cloud masks, Farneback flow frame -> next (OpenCV,
at the import resolution) and, for procedural ones, the exact flow (`dynsky sky training-data`
writes them; networks/data.py documents the arrays and the flow encoding).

The split is by TIME: the last 20 % of every sequence is held out. It is written once to
OUT/split.json and never changed: a rebuild that would produce a different split stops.
"""
import argparse
import json
import os
import shutil
import subprocess

from script_errors import fail, run_main
from split_info import photographs_trained, same_split

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

# Procedural sequences: (name, seed, extra `sky procedural` arguments). 120 frames = 1 hour at 30 s.
PROCEDURAL = [
    ("proc_s1", 1, ["--coverage", "0.45", "--wind-speed", "9", "--wind-from", "300", "--sun-elevation", "55", "--sun-azimuth", "160"]),
    ("proc_s2", 2, ["--coverage", "0.6", "--wind-speed", "13", "--wind-from", "210", "--layers", "cumulus,cirrus", "--sun-elevation", "35",
                    "--sun-azimuth", "240"]),
]
HELDOUT_FRACTION = 0.2


def split_for(frame_count):
    cut = frame_count - int(round(HELDOUT_FRACTION * frame_count))
    return {"train": [0, cut], "heldout": [cut, frame_count]}


def run(cmd):
    """Runs a dynsky step; dynsky prints its own error on stderr, this adds one line and its exit code
    (check=True had followed every clear dynsky message with a CalledProcessError traceback)."""
    print("+", " ".join(cmd), flush=True)
    rc = subprocess.run(cmd).returncode
    if rc != 0:
        what = " ".join(os.path.basename(c) if i == 0 else c for i, c in enumerate(cmd[:3]))
        fail(f"{what} failed (exit {rc}; its message is above)", rc if 0 < rc < 256 else 1)


def check_split(name, frame_count, split):
    """A sequence too short for the time split (2 frames gave held-out [2, 2]) is refused here; it
    had failed only at the end of training (IndexError in export's write_reference)."""
    for part in ("train", "heldout"):
        lo, hi = split[part]
        if hi <= lo:
            fail(f"{name}: {frame_count} frames leave the {part} part of the time split empty (frames "
                 f"[{lo}, {hi})): use a longer sequence")


def main(argv=None):
    """Builds the data set. An --out folder this run created is removed when it stops before writing
    split.json (an empty or partial folder had been left behind)."""
    created = []
    try:
        return build(argv, created)
    except KeyboardInterrupt:
        remove(created)
        fail("interrupted; run it again", 3)
    except BaseException:
        remove(created)
        raise


def remove(folders):
    for folder in folders:
        shutil.rmtree(folder, ignore_errors=True)


def build(argv, created):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", required=True, help="dataset folder (one sub-folder per sequence + split.json)")
    p.add_argument("--dynsky", default=os.path.join(ROOT, "build-nets", "cli", "dynsky"), help="the dynsky program")
    p.add_argument("--shared", default=os.path.join(os.path.dirname(ROOT), "shared"), help="the shared data folder")
    p.add_argument("--res", type=int, default=128, help="training resolution N")
    p.add_argument("--import-res", type=int, default=256, help="import / Farneback resolution (a multiple of N)")
    p.add_argument("--procedural-frames", type=int, default=120, help="frames per procedural sequence (30 s apart)")
    p.add_argument("--no-procedural", action="store_true", help="only the real sequence")
    p.add_argument("--keep-frames", action="store_true", help="keep the procedural EXR frames")
    args = p.parse_args(argv)

    if not os.path.exists(args.dynsky):
        fail(f"{args.dynsky}: dynsky not found (build it, or give --dynsky)")
    if not os.path.exists(args.out):
        os.makedirs(args.out)
        created.append(args.out)
    common = ["--sky-res", str(args.res), "--import-res", str(args.import_res), "--quiet"]
    sequences = {}
    run([args.dynsky, "sky", "training-data", "--sequence", "arm-tsi", "--shared", args.shared, "--out",
         os.path.join(args.out, "arm_tsi")] + common)
    sequences["arm_tsi"] = os.path.join(args.out, "arm_tsi")
    if not args.no_procedural:
        for name, seed, extra in PROCEDURAL:
            frames = os.path.join(args.out, "frames_" + name)
            run([args.dynsky, "sky", "procedural", "--cloud-seed", str(seed), "--dt", "30", "--duration",
                 str(30 * (args.procedural_frames - 1)), "--sky-res", str(args.import_res), "--quiet", "--out", frames] + extra)
            run([args.dynsky, "sky", "training-data", "--procedural", frames, "--out", os.path.join(args.out, name)] + common)
            if not args.keep_frames:
                shutil.rmtree(frames)
            sequences[name] = os.path.join(args.out, name)

    split = {}
    for name, folder in sequences.items():
        with open(os.path.join(folder, "meta.json")) as f:
            meta = json.load(f)
        split[name] = split_for(meta["frame_count"])
        check_split(name, meta["frame_count"], split[name])
        split[name]["dt_s"] = meta["dt_s"]
        split[name].update(photographs_trained(meta, split[name]["train"][1]))
    path = os.path.join(args.out, "split.json")
    if os.path.exists(path):
        with open(path) as f:
            old = json.load(f)
        for name, s in split.items():
            if name in old and not same_split(old[name], s):
                fail(f"{path}: the fixed split for {name} is {old[name]}, this build would make {s}; "
                     "remove the dataset folder to start over")
        old.update(split)
        split = old
    with open(path, "w") as f:
        json.dump(split, f, indent=2)
    print(f"wrote {', '.join(sequences)} and {path}")


if __name__ == "__main__":
    run_main("dataset.py", main)
