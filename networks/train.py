#!/usr/bin/python3
"""Trains the medium-timescale cloud model xi(I) = CloudNet(I concat FlowNet(I)) from scratch and
writes a shippable model folder (ONNX for OpenCV's importer, model.json, model card, split).

  /usr/bin/python3 networks/train.py --data build-nets/dataset --out networks/models/arm_tsi_128 \
      --sequences arm_tsi,proc_s1,proc_s2 --epochs 30

Training: windows of K+1 consecutive training frames; the model steps K times, each prediction
fed back as the next input (the paper's recursion), and every step is scored against the real
frame (image: MSE + cosine similarity of RGB vectors) and its flow target (Farneback flow masked
by the cloud mask: MSE + cosine similarity of directions on cloud pixels). Losses only count
pixels the camera saw (valid.npy). Seeds are fixed; a checkpoint is written every epoch and
--resume continues from it.
"""
import argparse
import csv
import json
import math
import os
import random
import shutil
import sys
import time

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import data as D  # noqa: E402
import unet as U  # noqa: E402
from script_errors import ScriptError, fail, load_checkpoint, resume_checkpoint, run_main  # noqa: E402,F401

SCRIPT = "train.py"
# Options a --resume may change: --epochs extends a run; the others do not change the model or the
# batches it is trained on (--no-export, --name: what is written after training).
RESUME_MAY_CHANGE = {"epochs", "threads", "eval_every", "out", "checkpoint_dir", "resume", "no_export", "name",
                     "argv_text"}


def set_seed(seed):
    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)


def parse_widths(text):
    return tuple(int(w) for w in text.split(","))


class Windows:
    """All (sequence, start) with frames start..start+K inside the given frame range."""

    def __init__(self, seqs, split, part, unroll, weights):
        self.seqs = seqs
        self.items = []
        for si, s in enumerate(seqs):
            lo, hi = split[s.name][part]  # [lo, hi) frame indices
            reps = max(1, int(round(weights.get(s.name, 1.0))))
            for start in range(lo, hi - unroll):
                self.items.extend([(si, start)] * reps)
        self.unroll = unroll

    def batch(self, idx):
        k = self.unroll
        imgs, valid, flow = [], [], []
        for i in idx:
            si, st = self.items[i]
            s = self.seqs[si]
            imgs.append(s.images[st:st + k + 1])
            valid.append(s.valid[st:st + k + 1])
            flow.append(s.flow_target[st:st + k])
        # -> (B, K+1, 3, N, N), (B, K+1, 1, N, N), (B, K, 3, N, N)
        imgs = torch.from_numpy(np.stack(imgs)).permute(0, 1, 4, 2, 3).contiguous()
        valid = torch.from_numpy(np.stack(valid).astype(np.float32))[:, :, None]
        flow = torch.from_numpy(np.stack(flow)).permute(0, 1, 4, 2, 3).contiguous()
        return imgs, valid, flow


def masked_mean(x, mask):
    return (x * mask).sum() / mask.sum().clamp(min=1.0)


def step_losses(pred_img, pred_flow, tgt_img, tgt_flow, valid, cos_weight=0.5):
    img_mse = masked_mean(((pred_img - tgt_img) ** 2).mean(1, keepdim=True), valid)
    cos_img = torch.nn.functional.cosine_similarity(pred_img, tgt_img, dim=1, eps=1e-4)[:, None]
    img_loss = img_mse + cos_weight * 0.1 * masked_mean(1 - cos_img, valid)
    flow_mse = masked_mean(((pred_flow - tgt_flow) ** 2).mean(1, keepdim=True), valid)
    moving = valid * (tgt_flow[:, 2:3] > 0).float()
    cos_flow = torch.nn.functional.cosine_similarity(pred_flow[:, 0:2], tgt_flow[:, 0:2], dim=1, eps=1e-4)[:, None]
    flow_loss = flow_mse + cos_weight * masked_mean(1 - cos_flow, moving)
    return img_loss, flow_loss, img_mse


def rollout_loss(model, imgs, valid, flow, disc, flow_weight, cos_weight=0.5):
    k = flow.shape[1]
    x = imgs[:, 0]
    total, mse0 = 0.0, None
    for t in range(k):
        x, f = model(x, disc)
        il, fl, mse = step_losses(x, f, imgs[:, t + 1], flow[:, t], valid[:, t + 1] * valid[:, t], cos_weight)
        total = total + il + flow_weight * fl
        if t == 0:
            mse0 = mse
    return total / k, mse0


@torch.no_grad()
def evaluate_heldout(model, seqs, split, horizons=(1,), max_windows=None):
    """Mean per-frame PSNR (valid pixels) of model and persistence on held-out frames, per sequence."""
    model.eval()
    out = {}
    for s in seqs:
        lo, hi = split[s.name]["heldout"]
        disc = torch.from_numpy(s.disc.astype(np.float32))[None, None]
        hs = [h for h in horizons if hi - lo > h]
        if not hs:
            continue
        H = max(hs)
        starts = list(range(lo, hi - H))
        if max_windows and len(starts) > max_windows:
            starts = starts[:: int(math.ceil(len(starts) / max_windows))]
        res = {h: {"model": [], "persistence": []} for h in hs}
        for b in range(0, len(starts), 16):
            st = starts[b:b + 16]
            x = torch.from_numpy(np.stack([s.images[i] for i in st])).permute(0, 3, 1, 2)
            x0 = x
            for h in range(1, H + 1):
                x, _ = model(x, disc)
                if h in res:
                    tgt = torch.from_numpy(np.stack([s.images[i + h] for i in st])).permute(0, 3, 1, 2)
                    v = torch.from_numpy(np.stack([s.valid[i + h] * s.valid[i] for i in st]).astype(np.float32))[:, None]
                    for name, p in (("model", x), ("persistence", x0)):
                        mse = ((p - tgt) ** 2).mean(1, keepdim=True)
                        mse = (mse * v).sum((1, 2, 3)) / v.sum((1, 2, 3))
                        res[h][name].extend((10 * torch.log10(1.0 / mse.clamp(min=1e-10))).tolist())
        out[s.name] = {h: {k: float(np.mean(v)) for k, v in r.items()} for h, r in res.items()}
    model.train()
    return out


def cpu_time_per_step(model, n, threads=1, repeats=20):
    """Seconds of one medium step (both networks, batch 1) in PyTorch on `threads` threads."""
    old = torch.get_num_threads()
    torch.set_num_threads(threads)
    model.eval()
    x = torch.rand(1, 3, n, n)
    disc = torch.from_numpy(D.disc_mask(n).astype(np.float32))[None, None]
    with torch.no_grad():
        for _ in range(3):
            model(x, disc)
        times = []
        for _ in range(repeats):
            t0 = time.process_time()
            model(x, disc)
            times.append(time.process_time() - t0)
    torch.set_num_threads(old)
    model.train()
    return float(np.median(times))


def check_options(args):
    """Option values the training cannot run with: one-line usage errors (exit 2) before any work.
    (--epochs -1 had exited 0 with an untrained model, 0 with ZeroDivisionError; an even --kernel
    and a zero --unroll or --batch died with tracebacks.)"""
    for opt, value in (("epochs", args.epochs), ("unroll", args.unroll), ("batch", args.batch)):
        if value < 1:
            fail(f"--{opt} {value}: must be at least 1", 2)
    if args.kernel < 0 or (args.kernel and args.kernel % 2 == 0):
        fail(f"--kernel {args.kernel}: must be odd (e.g. 3 or 5), or 0 for the plain residual", 2)
    if not (args.lr > 0 and math.isfinite(args.lr)):
        fail(f"--lr {args.lr}: must be a positive number", 2)
    if args.res < 0:
        fail(f"--res {args.res}: must be positive (or 0: the data set's resolution)", 2)


def check_depth(fw, cw, n, batch):
    """Each UNet level halves the map: n must be divisible by 2^levels, and a 1 x 1 bottleneck's
    BatchNorm needs at least 2 images per batch (else PyTorch errors midway through training)."""
    levels = (n & -n).bit_length() - 1  # how often n halves evenly
    for opt, widths in (("--flow-widths", fw), ("--cloud-widths", cw)):
        if any(w < 1 for w in widths):
            fail(f"{opt} {','.join(map(str, widths))}: widths must be at least 1", 2)
        if len(widths) > levels:
            fail(f"{opt} {','.join(map(str, widths))}: {len(widths)} levels need a resolution divisible by "
                 f"2^{len(widths)} = {2 ** len(widths)}, the training resolution is {n} (use at most {levels} "
                 "levels, or another --res)", 2)
        if n >> len(widths) == 1 and batch < 2:
            fail(f"{opt} {','.join(map(str, widths))}: {len(widths)} levels leave a 1 x 1 map at {n} px, which "
                 f"needs batches of at least 2 windows (this run has {batch}): use fewer levels or a larger --batch", 2)


def check_data(args):
    """The data set and the sequences asked for: one-line refusals instead of tracebacks."""
    split_path = os.path.join(args.data, "split.json")
    if not os.path.isfile(split_path):
        fail(f"{split_path}: not found (--data must be a data set of networks/dataset.py)")
    try:
        split = D.load_split(args.data)
    except (OSError, ValueError) as e:
        fail(f"{split_path}: not readable as JSON ({e})")
    names = [s for s in args.sequences.split(",") if s]
    if not names:
        fail("--sequences: empty", 2)
    unknown = [s for s in names if s not in split]
    if unknown:
        fail(f"--sequences {','.join(unknown)}: no such sequence in {split_path} (it has: {', '.join(sorted(split)) or 'none'})", 2)
    for name in names:
        for part in ("train", "heldout"):
            if part not in split[name]:
                fail(f"{split_path}: sequence '{name}' has no '{part}' part (a data set of networks/dataset.py has both)")
            lo, hi = split[name][part]
            if hi <= lo:  # an empty held-out part died in export's write_reference with IndexError
                fail(f"{split_path}: sequence '{name}' has an empty {part} part (frames [{lo}, {hi})): the sequence "
                     "is too short; rebuild the data set from a longer one")
        for f in ("meta.json", "images.npy", "valid.npy", "cloud.npy", "flow_farneback.npy"):
            if not os.path.isfile(os.path.join(args.data, name, f)):
                fail(f"{os.path.join(args.data, name, f)}: not found (rebuild the data set with networks/dataset.py)")
    try:
        fw, cw = parse_widths(args.flow_widths), parse_widths(args.cloud_widths)
    except ValueError:
        fail(f"--flow-widths {args.flow_widths} / --cloud-widths {args.cloud_widths}: expected comma-separated "
             "integers (e.g. 16,32,64,64)", 2)
    return split, names, fw, cw


def train(args):
    check_options(args)
    torch.set_num_threads(min(args.threads, 2))
    set_seed(args.seed)
    # Stored (and compared on --resume) as the folder itself: a relative --data named another data
    # set from another working folder, and the same one from there was refused.
    args.data = os.path.realpath(args.data)
    split, names, fw, cw = check_data(args)
    ckpt_path = os.path.join(args.checkpoint_dir or args.out, "checkpoint.pt")
    ck = resume_checkpoint(ckpt_path, args, parser(), RESUME_MAY_CHANGE)
    if ck is not None and ck["epoch"] > args.epochs:
        # It would export the checkpoint's weights under model.json's and the card's smaller count.
        fail(f"--epochs {args.epochs}: {ckpt_path} has already finished {ck['epoch']} epochs (resume with "
             f"--epochs {ck['epoch']} or more, or train into a new --out)", 2)
    seqs = []
    for name in names:
        s = D.Sequence(os.path.join(args.data, name))
        if args.res and s.resolution != args.res:
            if s.resolution % args.res:
                fail(f"--res {args.res}: does not divide the resolution {s.resolution} of {args.data}/{name}", 2)
            s = D.resize_sequence(s, args.res)
        seqs.append(s)
    n = seqs[0].resolution
    if not all(s.resolution == n for s in seqs):
        fail(f"--sequences {args.sequences}: the sequences differ in resolution (give --res)", 2)
    dt = seqs[0].meta["dt_s"]
    if not all(abs(s.meta["dt_s"] - dt) < 1e-6 for s in seqs):
        fail(f"--sequences {args.sequences}: the sequences differ in Delta t (dt_s in meta.json)", 2)
    weights = {}
    for w in (args.weights or "").split(","):
        if w:
            k, _, v = w.partition("=")
            try:
                weights[k] = float(v)
            except ValueError:
                fail(f"--weights {args.weights}: expected NAME=REPEATS,...", 2)
    train_w = Windows(seqs, split, "train", args.unroll, weights)
    if not train_w.items:
        parts = ", ".join(f"{s.name} frames {split[s.name]['train'][0]}-{split[s.name]['train'][1] - 1}" for s in seqs)
        fail(f"{args.data}: no training window of --unroll {args.unroll} + 1 = {args.unroll + 1} frames fits in the "
             f"train part ({parts}): use a longer sequence or a smaller --unroll")
    check_depth(fw, cw, n, min(args.batch, len(train_w.items)))
    disc = torch.from_numpy(D.disc_mask(n).astype(np.float32))[None, None]
    model = U.CloudModel(fw, cw, args.kernel)
    opt = torch.optim.Adam(model.parameters(), lr=args.lr)
    steps_per_epoch = max(1, len(train_w.items) // args.batch)
    total_steps = steps_per_epoch * args.epochs
    sched = torch.optim.lr_scheduler.LambdaLR(
        opt, lambda i: 0.5 * (1 + math.cos(math.pi * min(i, total_steps) / total_steps)) * 0.97 + 0.03)
    os.makedirs(args.out, exist_ok=True)
    start_epoch, log = 0, []
    if ck is not None:
        model.load_state_dict(ck["model"])
        opt.load_state_dict(ck["opt"])
        sched.load_state_dict(ck["sched"])
        start_epoch, log = ck["epoch"], ck["log"]
        torch.set_rng_state(ck["rng"])
        print(f"resumed at epoch {start_epoch}")
    rng = np.random.default_rng(args.seed)
    for _ in range(start_epoch):  # keep the shuffles identical to an uninterrupted run
        rng.permutation(len(train_w.items))
    t_start = time.time()
    for epoch in range(start_epoch, args.epochs):
        order = rng.permutation(len(train_w.items))
        losses, mses = [], []
        for b in range(steps_per_epoch):
            imgs, valid, flow = train_w.batch(order[b * args.batch:(b + 1) * args.batch])
            loss, mse0 = rollout_loss(model, imgs, valid, flow, disc, args.flow_weight, args.cos_weight)
            opt.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
            opt.step()
            sched.step()
            losses.append(float(loss))
            mses.append(float(mse0))
            if args.max_steps and b + 1 >= args.max_steps:
                break
        entry = {"epoch": epoch + 1, "loss": float(np.mean(losses)), "train_psnr1": float(10 * np.log10(1 / np.mean(mses))),
                 "seconds": time.time() - t_start}
        if args.eval_every and ((epoch + 1) % args.eval_every == 0 or epoch + 1 == args.epochs):
            ev = evaluate_heldout(model, seqs, split, (1,), max_windows=64)
            for name, r in ev.items():
                entry[f"heldout_psnr1_{name}"] = r[1]["model"]
                entry[f"persistence_psnr1_{name}"] = r[1]["persistence"]
        log.append(entry)
        print(json.dumps(entry), flush=True)
        save_checkpoint({"model": model.state_dict(), "opt": opt.state_dict(), "sched": sched.state_dict(),
                         "epoch": epoch + 1, "log": log, "rng": torch.get_rng_state(), "args": vars(args)}, ckpt_path)
    return model, seqs, split, log


def save_checkpoint(state, path):
    """Writes a temporary file beside path, fsyncs it and renames it over path: a kill or a full disk
    during the write (torch.save straight onto the only checkpoint lost every epoch) leaves the
    previous checkpoint whole."""
    folder = os.path.dirname(path) or "."
    tmp = os.path.join(folder, f".tmp-checkpoint-{os.getpid()}.pt")
    try:
        with open(tmp, "wb") as f:
            torch.save(state, f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException as e:
        if os.path.exists(tmp):
            os.remove(tmp)
        if isinstance(e, OSError):
            fail(f"{path}: could not write the checkpoint ({e.strerror or e}); the previous one is unchanged")
        raise
    try:  # make the rename itself durable
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
    except OSError:
        pass


def parser():
    p = argparse.ArgumentParser(prog=SCRIPT, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", required=True, help="dataset folder made by networks/dataset.py (with split.json)")
    p.add_argument("--sequences", default="arm_tsi", help="comma-separated sequence folders to train on")
    p.add_argument("--weights", default="", help="NAME=REPEATS,... how often each sequence's windows repeat per epoch")
    p.add_argument("--res", type=int, default=0, help="train at this resolution (area-downscaled); 0: the dataset's")
    p.add_argument("--flow-widths", default="16,32,64,64", help="FlowNet encoder widths (depth = count)")
    p.add_argument("--cloud-widths", default="16,32,64,64", help="CloudNet encoder widths (depth = count)")
    p.add_argument("--kernel", type=int, default=5, help="CloudNet's per-pixel warp kernel size (odd; 0: plain residual)")
    p.add_argument("--epochs", type=int, default=30)
    p.add_argument("--batch", type=int, default=8)
    p.add_argument("--unroll", type=int, default=3, help="recursive steps per training window (K)")
    p.add_argument("--lr", type=float, default=2e-3)
    p.add_argument("--flow-weight", type=float, default=0.1, help="weight of the flow loss against the image loss")
    p.add_argument("--cos-weight", type=float, default=0.5,
                   help="weight of the cosine-similarity terms: image 0.1 x this x (1 - cos of RGB vectors), flow "
                        "this x (1 - cos of directions); 0: MSE only (the loss ablation, networks/ablation.py)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--max-steps", type=int, default=0, help="stop each epoch after this many batches (tests)")
    p.add_argument("--eval-every", type=int, default=5, help="held-out PSNR every this many epochs (0: never)")
    p.add_argument("--out", required=True, help="model folder to write (ONNX, model.json, MODEL_CARD.md)")
    p.add_argument("--checkpoint-dir", default="", help="where checkpoint.pt goes (default: --out)")
    p.add_argument("--resume", action="store_true",
                   help="continue from the checkpoint (refused when an option other than --epochs, --threads, "
                        "--eval-every, --out, --checkpoint-dir, --no-export, --name differs from the checkpoint's)")
    p.add_argument("--no-export", action="store_true", help="train only (no ONNX / model card)")
    p.add_argument("--name", default="", help="model name for the card (default: the folder name)")
    return p


def file_id(path):
    try:
        st = os.stat(path)
        return st.st_ino, st.st_mtime_ns
    except OSError:
        return None


def main(argv=None):
    """Trains (and exports); a bad input raises ScriptError (the command line prints it as one line,
    exit 1 or 2; 3 for Ctrl-C)."""
    args = parser().parse_args(argv)
    # For the model card: the from-scratch command (a resumed run reproduces it).
    args.argv_text = " ".join(a for a in (argv if argv is not None else sys.argv[1:]) if a != "--resume")
    ckpt = os.path.join(args.checkpoint_dir or args.out, "checkpoint.pt")
    before = file_id(ckpt)
    try:
        model, seqs, split, log = train(args)
        if not args.no_export:
            import export as E
            E.write_model_folder(model, seqs, split, log, args)
    except KeyboardInterrupt:
        # Ctrl-C: one line and exit 3 (docs/exit-codes.md), not a traceback. The checkpoint is this
        # run's when it resumed or wrote a new one (an older run's may lie there too).
        if file_id(ckpt) is not None and (args.resume or file_id(ckpt) != before):
            fail(f"interrupted; the last finished epoch is in {ckpt}: rerun with --resume to continue "
                 "(or to export a finished run)", 3)
        fail("interrupted before the first epoch finished; nothing to resume", 3)
    return model, log


if __name__ == "__main__":
    run_main(SCRIPT, main)
