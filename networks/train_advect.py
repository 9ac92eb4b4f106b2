#!/usr/bin/python3
"""Trains the advect-residual model (networks/advect.py; docs/networks-advect-residual.md).

  /usr/bin/python3 networks/train_advect.py --data /work/data/dataset_v2 --out /work/data/runs/w16 \
      --widths 16,32,64,64 --kernel 0 --epochs 12

Each batch: samples drawn by networks/advect_data.py (a start frame k, a flow F = prev Farneback /
true motion / random wind on clear skies / 0, augmentation), the model steps K = --unroll times
with the same F (each prediction clamped, zeroed outside the disc and fed back), every step scored
against frame k + t: MSE + 0.05 (1 - cosine similarity of RGB vectors) (networks/train.py
step_losses' image part) on pixels seen at k and k + t and saturated in neither. Seeds are fixed,
a checkpoint is written every epoch (model, optimiser, schedule, sampler state) and --resume
continues from it (the same run, bit for bit on the same thread count). --part fit trains on the
first 70 % of every source and scores the validation part (70-80 %) for model selection; --part
train uses all of the first 80 %. The held-out last 20 % is never read here.
"""
import argparse
import json
import math
import os
import random
import sys
import time

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import advect as A  # noqa: E402
import advect_data as AD  # noqa: E402
import advect_eval as AE  # noqa: E402
from script_errors import ScriptError, fail, load_checkpoint, resume_checkpoint, run_main  # noqa: E402,F401

SCRIPT = "train_advect.py"
# Options a --resume may change: --epochs extends a run; the others do not change the model or the
# batches it is trained on.
RESUME_MAY_CHANGE = {"epochs", "threads", "eval_every", "val_starts", "out", "resume"}


def set_seed(seed):
    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)


def masked_mean(x, mask):
    return (x * mask).sum() / mask.sum().clamp(min=1.0)


def image_loss(pred, tgt, mask, cos_weight=0.5):
    mse = masked_mean(((pred - tgt) ** 2).mean(1, keepdim=True), mask)
    cos = torch.nn.functional.cosine_similarity(pred, tgt, dim=1, eps=1e-4)[:, None]
    return mse + cos_weight * 0.1 * masked_mean(1 - cos, mask), mse


def grad_mag(img):
    """|gradient| per pixel (forward differences, mean over channels), (B, 1, N-1, N-1)."""
    dx = img[:, :, :-1, 1:] - img[:, :, :-1, :-1]
    dy = img[:, :, 1:, :-1] - img[:, :, :-1, :-1]
    return torch.sqrt(dx * dx + dy * dy + 1e-8).mean(1, keepdim=True)


def image_loss_log(pred, tgt, mask, cos_weight=0.5, eps=1e-6, gdl_weight=0.0):
    """Per-sample loss l_b = MSE_b + 0.05 (1 - cos)_b on the sample's mask pixels, averaged as
    log(l_b + eps): the mean per-frame PSNR is what is scored, and a clear sky (MSE ~1e-5) counts
    as much as a cloudy one (MSE ~3e-3) instead of vanishing next to it."""
    m = mask.sum((1, 2, 3)).clamp(min=1.0)
    mse_b = (((pred - tgt) ** 2).mean(1, keepdim=True) * mask).sum((1, 2, 3)) / m
    cos = torch.nn.functional.cosine_similarity(pred, tgt, dim=1, eps=1e-4)[:, None]
    cos_b = ((1 - cos) * mask).sum((1, 2, 3)) / m
    l_b = mse_b + cos_weight * 0.1 * cos_b
    if gdl_weight:
        # gradient-magnitude difference (Mathieu et al. 2016's GDL, squared): penalises blur, which
        # MSE alone rewards under uncertainty and which compounds over a rollout
        m2 = mask[:, :, :-1, :-1] * mask[:, :, 1:, :-1] * mask[:, :, :-1, 1:]
        g = ((grad_mag(pred) - grad_mag(tgt)) ** 2 * m2).sum((1, 2, 3)) / m2.sum((1, 2, 3)).clamp(min=1.0)
        l_b = l_b + gdl_weight * g
    return torch.log(l_b + eps).mean(), masked_mean(((pred - tgt) ** 2).mean(1, keepdim=True), mask)


def rollout_loss(model, x, v, f, cos_weight=0.5, log_loss=False, pushforward=0, gdl_weight=0.0, comp=None):
    """x (B, K+1+P, 3, N, N), v (B, K+1+P, 1, N, N), f (B, 2, N, N). With pushforward P > 0 the
    model first steps P times without gradient (its own rollout, same F), then K scored steps
    against frames k+P+1 .. k+P+K: it learns to correct its own accumulated errors (the
    pushforward trick, Brandstetter et al. 2022)."""
    K = x.shape[1] - 1 - pushforward
    img = A.fill_saturated(x[:, 0])
    sat0 = A.saturated(x[:, 0])
    if pushforward:
        with torch.no_grad():
            for _ in range(pushforward):
                img = A.step(model, img, f, comp)
    total, mse1 = 0.0, None
    for t in range(pushforward + 1, pushforward + K + 1):
        img = A.step(model, img, f, comp)
        mask = v[:, 0] * v[:, t] * (1 - sat0) * (1 - A.saturated(x[:, t]))
        if log_loss:
            loss, mse = image_loss_log(img, x[:, t], mask, cos_weight, gdl_weight=gdl_weight)
        else:
            loss, mse = image_loss(img, x[:, t], mask, cos_weight)
        total = total + loss
        if mse1 is None:
            mse1 = mse
    return total / K, mse1


def parse_widths(text):
    return tuple(int(w) for w in text.split(","))


def build_model(args):
    try:
        widths = parse_widths(args.widths)
    except ValueError:
        fail(f"--widths {args.widths}: expected comma-separated integers (e.g. 16,32,64,64)", 2)
    return A.AdvectResidual(widths, args.kernel, args.bound, gate=args.gate)


def check_data(args):
    """The data set and the sources asked for: one-line refusals instead of tracebacks. Returns the
    source names to load (None: all of split.json)."""
    split_path = os.path.join(args.data, "split.json")
    if not os.path.isfile(split_path):
        fail(f"{split_path}: not found (--data must be a data set of networks/build_dataset_v2.py)")
    try:
        with open(split_path) as f:
            split = json.load(f)
    except (OSError, ValueError) as e:
        fail(f"{split_path}: not readable as JSON ({e})")
    known = sorted(split)
    names = [s for s in args.sources.split(",") if s] or None
    for opt, given in (("--sources", names or []), ("--exclude", [s for s in args.exclude.split(",") if s])):
        unknown = [s for s in given if s not in split]
        if unknown:
            fail(f"{opt} {','.join(unknown)}: no such source in {split_path} (it has: {', '.join(known) or 'none'})", 2)
    for name in names or known:
        if args.part not in split[name]:
            fail(f"{split_path}: source '{name}' has no '{args.part}' part (it has: {', '.join(k for k in sorted(split[name]) if isinstance(split[name][k], list))}; "
                 "a data set of networks/dataset.py?): use --part train, or build the data set with "
                 "networks/build_dataset_v2.py", 1)
        for f in ("meta.json", "images.npy", "valid.npy", "cloud.npy", "flow_farneback.npy"):
            if not os.path.isfile(os.path.join(args.data, name, f)):
                fail(f"{os.path.join(args.data, name, f)}: not found (rebuild the data set with networks/build_dataset_v2.py)")
        if args.compensated and not os.path.isfile(os.path.join(args.data, name, "background.npy")):
            fail(f"--compensated: {os.path.join(args.data, name, 'background.npy')} not found, and the compensated "
                 "warp needs the frames' clear background (rebuild the data set with networks/build_dataset_v2.py, "
                 "or drop --compensated)")
    return names


def train(args):
    torch.set_num_threads(args.threads)
    set_seed(args.seed)
    # Stored (and compared on --resume) as the folder itself: a relative --data named another data
    # set from another working folder, and the same one from there was refused.
    args.data = os.path.realpath(args.data)
    names = check_data(args)
    ckpt = os.path.join(args.out, "checkpoint.pt")
    ck = resume_checkpoint(ckpt, args, parser(), RESUME_MAY_CHANGE)
    sources, split = AD.load_sources(args.data, names)
    if args.exclude:
        ex = set(args.exclude.split(","))
        sources = [s for s in sources if s.name not in ex]
    if not sources:
        fail(f"--exclude {args.exclude}: leaves no source to train on", 2)
    n = sources[0].n
    if args.res and args.res != n:
        if n % args.res:
            fail(f"--res {args.res}: does not divide the data set's resolution {n}", 2)
        for s in sources:
            resize_sequence_advect(s, args.res)
        n = args.res
    sampler = AD.Sampler(sources, split, args.part, args.unroll + args.pushforward, p_zero=args.p_zero, seed=args.seed,
                         compensated=args.compensated, smooth=args.smooth)
    for s, (lo, hi) in zip(sources, sampler.ranges):
        if hi <= lo:
            fail(f"{args.data}/{s.name}: its '{args.part}' part is too short for --unroll {args.unroll} + --pushforward "
                 f"{args.pushforward} (a start frame needs the frame before it and the frames it predicts)")
    pf_rng = np.random.default_rng(args.seed + 1000)
    model = build_model(args)
    opt = torch.optim.Adam(model.parameters(), lr=args.lr)
    total_steps = args.steps_per_epoch * args.epochs
    sched = torch.optim.lr_scheduler.LambdaLR(
        opt, lambda i: 0.5 * (1 + math.cos(math.pi * min(i, total_steps) / total_steps)) * 0.97 + 0.03)
    os.makedirs(args.out, exist_ok=True)
    start_epoch, log, best = 0, [], None
    if ck is not None:
        model.load_state_dict(ck["model"])
        opt.load_state_dict(ck["opt"])
        sched.load_state_dict(ck["sched"])
        sampler.set_state(ck["sampler"])
        if "pf_rng" in ck:
            pf_rng.bit_generator.state = ck["pf_rng"]
        torch.set_rng_state(ck["rng"])
        start_epoch, log, best = ck["epoch"], ck["log"], ck.get("best")
        print(f"resumed at epoch {start_epoch}", flush=True)
    val_part = "val" if args.part == "fit" else None
    t0 = time.time()
    for epoch in range(start_epoch, args.epochs):
        model.train()
        losses, mses = [], []
        for b in range(args.steps_per_epoch):
            x, v, f, _, comp = sampler.batch(args.batch)
            pf = int(pf_rng.integers(0, args.pushforward + 1)) if args.pushforward else 0
            x, v = x[:, :pf + args.unroll + 1], v[:, :pf + args.unroll + 1]
            loss, mse1 = rollout_loss(model, x, v, f, args.cos_weight, args.loss == "log", pf, args.gdl_weight, comp)
            opt.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
            opt.step()
            sched.step()
            losses.append(float(loss))
            mses.append(float(mse1))
        entry = {"epoch": epoch + 1, "loss": float(np.mean(losses)),
                 "train_psnr1": float(10 * np.log10(1 / np.mean(mses))), "seconds": time.time() - t0}
        if val_part and args.eval_every and ((epoch + 1) % args.eval_every == 0 or epoch + 1 == args.epochs):
            ev = AE.evaluate(model, sources, split, val_part, (1, 2, 6), max_starts=args.val_starts,
                             methods=("model_prev", "model_true", "persistence", "farneback"),
                             compensated=args.compensated, smooth=args.smooth)
            entry["val_score"] = AE.selection_score(ev)
            entry["val"] = {k: {m: {str(h): round(p, 3) for h, p in r[m].items()} for m in
                                ("model_prev", "model_true", "persistence", "farneback")} for k, r in ev.items()}
            if best is None or entry["val_score"] > best["val_score"]:
                best = {"epoch": epoch + 1, "val_score": entry["val_score"]}
                torch.save({"model": model.state_dict(), "epoch": epoch + 1, "args": vars(args)},
                           os.path.join(args.out, "best.pt"))
        log.append(entry)
        short = {k: v for k, v in entry.items() if k != "val"}
        print(json.dumps(short), flush=True)
        torch.save({"model": model.state_dict(), "opt": opt.state_dict(), "sched": sched.state_dict(),
                    "sampler": sampler.state(), "pf_rng": pf_rng.bit_generator.state, "rng": torch.get_rng_state(), "epoch": epoch + 1, "log": log,
                    "best": best, "args": vars(args)}, ckpt)
        with open(os.path.join(args.out, "training_log.json"), "w") as fh:
            json.dump(log, fh, indent=1)
    torch.save({"model": model.state_dict(), "epoch": args.epochs, "args": vars(args)}, os.path.join(args.out, "final.pt"))
    return model, log


def resize_sequence_advect(s, n):
    """Area-downscales a loaded Source to n (images, valid, cloud, flows rescaled to pixels of n)."""
    import torch.nn.functional as F
    k = s.n // n
    assert k * n == s.n

    def pool(a):
        t = torch.from_numpy(np.ascontiguousarray(a)).float().permute(0, 3, 1, 2)
        return F.avg_pool2d(t, k).permute(0, 2, 3, 1).numpy()

    disc = A.disc_mask(n)
    s.images = pool(s.images) * disc[None, :, :, None]
    s.valid = ((pool(s.valid[..., None].astype(np.float32))[..., 0] > 0.999) & disc[None]).astype(np.uint8)
    s.cloud = (pool(s.cloud[..., None].astype(np.float32))[..., 0] > 0.5).astype(np.uint8)
    s.flow = pool(s.flow) / k
    if s.flow_exact is not None:
        s.flow_exact = pool(s.flow_exact) / k
    s.n = n


def load_model(path):
    """(model in eval mode, its training args) of a checkpoint of this script (checkpoint.pt, best.pt,
    final.pt); a ScriptError for a missing, unreadable or foreign (e.g. paper-form, networks/train.py)
    checkpoint."""
    ck = load_checkpoint(path)
    a = ck.get("args")
    if not isinstance(a, dict) or "widths" not in a:
        other = " (a checkpoint of networks/train.py, the paper's FlowNet + CloudNet)" if isinstance(a, dict) and \
            "flow_widths" in a else ""
        fail(f"{path}: not an advect-residual checkpoint of networks/train_advect.py{other}")
    try:
        m = A.AdvectResidual(parse_widths(a["widths"]), a["kernel"], a["bound"], gate=a.get("gate", False))
        m.load_state_dict(ck["model"])
    except (KeyError, ValueError, RuntimeError) as e:
        fail(f"{path}: its weights do not fit the model its args describe ({type(e).__name__}: "
             f"{str(e).splitlines()[0] if str(e) else ''})")
    return m.eval(), a


def parser():
    p = argparse.ArgumentParser(prog=SCRIPT, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", required=True)
    p.add_argument("--sources", default="", help="comma-separated sources (default: all in split.json)")
    p.add_argument("--exclude", default="", help="sources to leave out (the unseen-camera check: mobotix)")
    p.add_argument("--part", default="fit", choices=["fit", "train"], help="fit: 0-70 %% (+ val scoring); train: 0-80 %%")
    p.add_argument("--res", type=int, default=0, help="train at this resolution (area-downscaled); 0: the data's")
    p.add_argument("--widths", default="16,32,64,64")
    p.add_argument("--kernel", type=int, default=0, help="0: W + bound tanh; 3 or 5: k x k kernel blend of W + bound tanh")
    p.add_argument("--bound", type=float, default=0.1, help="bound of the per-step change")
    p.add_argument("--compensated", action="store_true",
                   help="W = warp(I) + B - warp(B) with the frames' clear background B (background.npy): only the clouds move")
    p.add_argument("--smooth", action="store_true", help="previous-frame flows smoothed (sigma N/32) as the C++ side does")
    p.add_argument("--gate", action="store_true", help="next = (1 - a) W + a I + bound tanh(c), a = sigmoid(learnt)")
    p.add_argument("--epochs", type=int, default=12)
    p.add_argument("--steps-per-epoch", type=int, default=100)
    p.add_argument("--batch", type=int, default=16)
    p.add_argument("--unroll", type=int, default=3)
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--p-zero", type=float, default=0.15)
    p.add_argument("--pushforward", type=int, default=0,
                   help="per batch, first step the model 0..P times without gradient (uniform), then --unroll scored steps")
    p.add_argument("--gdl-weight", type=float, default=0.0, help="weight of the gradient-magnitude difference term")
    p.add_argument("--cos-weight", type=float, default=0.5)
    p.add_argument("--loss", default="log", choices=["log", "mse"],
                   help="log: mean over samples of log(MSE + 0.05 (1 - cos) + 1e-6); mse: batch MSE + 0.05 (1 - cos)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--eval-every", type=int, default=2)
    p.add_argument("--val-starts", type=int, default=24)
    p.add_argument("--out", required=True, help="run folder (checkpoint.pt, best.pt, final.pt, training_log.json)")
    p.add_argument("--resume", action="store_true",
                   help="continue OUT/checkpoint.pt (refused when an option other than --epochs, --threads, "
                        "--eval-every, --val-starts differs from the checkpoint's)")
    return p


def main(argv=None):
    """Trains; a bad input raises ScriptError (the command line prints it as one line, exit 1 or 2)."""
    args = parser().parse_args(argv)
    return train(args)


if __name__ == "__main__":
    run_main(SCRIPT, main)
