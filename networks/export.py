"""Writing a trained model as a folder the C++ side loads (motion/cloud_model.h):

  flownet.onnx, cloudnet.onnx   opset 11, fixed 1 x C x N x N input, constant Resize scales (the
                                form OpenCV 4.6's importer runs exactly, ../shared/NOTES.md)
  model.json                    resolution, Delta t, flow encoding scale, widths, training facts
  split.json                    the frames trained on and held out, per sequence
  reference_*.npy               one held-out input and PyTorch's outputs of both networks, for the
                                C++ test that checks OpenCV agrees within 1e-4
  MODEL_CARD.md                 data, split, Delta t, resolution, widths, epochs, metrics
  training_log.json             per-epoch losses and held-out PSNR
"""
import datetime
import json
import os
import shutil

import numpy as np
import onnx
import torch

import data as D
import unet as U


def export_onnx(model, n, folder, opset=11):
    import copy
    model = copy.deepcopy(model).eval()
    for m in model.modules():
        if isinstance(m, U.UNet):
            m.freeze_position(n)
    paths = {}
    for name, net, channels, iname, oname in (("flownet", model.flownet, 3, "image", "flow"),
                                              ("cloudnet", model.cloudnet, 6, "image_and_flow", "next")):
        path = os.path.join(folder, name + ".onnx")
        torch.onnx.export(net, torch.zeros(1, channels, n, n), path, opset_version=opset, input_names=[iname],
                          output_names=[oname], do_constant_folding=True)
        inline_constant_identities(path)
        check_onnx_for_opencv(path)
        paths[name] = path
    return paths


def inline_constant_identities(path):
    """Constant folding shares equal tensors (e.g. the biases of untrained BatchNorms) through Identity
    nodes; copy the tensor instead so the graph holds only operators OpenCV's importer runs."""
    m = onnx.load(path)
    inits = {i.name: i for i in m.graph.initializer}
    keep = []
    for node in m.graph.node:
        if node.op_type == "Identity" and node.input[0] in inits:
            t = onnx.TensorProto()
            t.CopyFrom(inits[node.input[0]])
            t.name = node.output[0]
            m.graph.initializer.append(t)
        else:
            keep.append(node)
    if len(keep) != len(m.graph.node):
        del m.graph.node[:]
        m.graph.node.extend(keep)
        onnx.save(m, path)


def check_onnx_for_opencv(path):
    """The importer rules of ../shared/NOTES.md: opset >= 11, no run-time shapes, Resize scales constant."""
    m = onnx.load(path)
    onnx.checker.check_model(m)
    opset = max(o.version for o in m.opset_import if o.domain in ("", "ai.onnx"))
    assert opset >= 11, f"{path}: opset {opset} < 11"
    ops = {n.op_type for n in m.graph.node}
    allowed = {"Conv", "BatchNormalization", "LeakyRelu", "Relu", "Resize", "Concat", "Tanh", "Sigmoid", "Add", "Slice",
               "Constant", "Mul", "Div", "Exp"}
    assert ops <= allowed, f"{path}: operators outside what OpenCV's importer is known to run: {sorted(ops - allowed)}"
    consts = {i.name for i in m.graph.initializer} | {o for n in m.graph.node if n.op_type == "Constant" for o in n.output}
    for node in m.graph.node:
        if node.op_type == "Resize":
            assert all(i == "" or i in consts for i in node.input[1:]), f"{path}: Resize with computed scales"
            mode = [a.s.decode() for a in node.attribute if a.name == "mode"]
            assert mode == ["linear"], f"{path}: Resize mode {mode}"
    dims = [d.dim_value for d in m.graph.input[0].type.tensor_type.shape.dim]
    assert all(d > 0 for d in dims), f"{path}: input size not fixed: {dims}"
    return sorted(ops)


@torch.no_grad()
def write_reference(model, image, folder):
    """image (N, N, 3) float32 -> reference_input/flow/next.npy (HWC float32; next before clamping)."""
    model.eval()
    x = torch.from_numpy(np.ascontiguousarray(image)).permute(2, 0, 1)[None].float()
    f = model.flownet(x)
    nxt = model.cloudnet(torch.cat([x, f], 1))
    np.save(os.path.join(folder, "reference_input.npy"), image.astype(np.float32))
    np.save(os.path.join(folder, "reference_flow.npy"), f[0].permute(1, 2, 0).numpy().astype(np.float32))
    np.save(os.path.join(folder, "reference_next.npy"), nxt[0].permute(1, 2, 0).numpy().astype(np.float32))


# What write_model_folder writes; anything else in an existing model folder (train.py's checkpoint.pt,
# a user's notes) is carried into the new one.
EXPORTED = {"flownet.onnx", "cloudnet.onnx", "reference_input.npy", "reference_flow.npy", "reference_next.npy",
            "split.json", "model.json", "training_log.json", "MODEL_CARD.md"}


def write_model_folder(model, seqs, split, log, args, horizons=(1, 2, 3, 6)):
    """Writes the whole folder into a temporary sibling and swaps it in at the end: a failure or a
    kill midway had left new ONNX files under an old model.json, which dynsky then ran. The folder
    is the complete new one or the untouched old one (a failure is one line, exit 1)."""
    from script_errors import fail
    folder = os.path.realpath(args.out)
    parent, base = os.path.split(folder)
    remove_stale_temporaries(parent, base)
    work = os.path.join(parent, f".tmp-{base}-{os.getpid()}")
    try:
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(work)
        info = write_model_files(model, seqs, split, log, args, work, horizons)
        if os.path.isdir(folder):
            carry_other_files(folder, work)
        aside = os.path.join(parent, f".old-{base}-{os.getpid()}")
        if os.path.isdir(folder):
            os.rename(folder, aside)
            try:
                os.rename(work, folder)
            except OSError:
                os.rename(aside, folder)
                raise
            shutil.rmtree(aside, ignore_errors=True)
        else:
            os.rename(work, folder)
    except OSError as e:
        shutil.rmtree(work, ignore_errors=True)
        fail(f"{args.out}: could not write the model folder ({e}); the previous one is unchanged")
    except BaseException:
        shutil.rmtree(work, ignore_errors=True)
        raise
    return info


def remove_stale_temporaries(parent, base):
    """Removes the .tmp-/.old- folders of killed runs into this folder (their process is gone). Only
    while the folder exists: a kill between the two renames leaves it only as those folders."""
    if not os.path.isdir(os.path.join(parent, base)):
        return
    for name in os.listdir(parent):
        for prefix in (f".tmp-{base}-", f".old-{base}-"):
            pid = name[len(prefix):]
            if name.startswith(prefix) and pid.isdigit() and not process_alive(int(pid)):
                shutil.rmtree(os.path.join(parent, name), ignore_errors=True)


def process_alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def carry_other_files(old, new):
    """Hard-links (copies where links fail) what the old folder holds besides the exported files
    into the new one, so the swap keeps the checkpoint that --resume needs."""
    def link_or_copy(src, dst):
        try:
            os.link(src, dst)
        except OSError:
            shutil.copy2(src, dst)
    for name in os.listdir(old):
        if name in EXPORTED or name.startswith(".tmp-"):
            continue
        src, dst = os.path.join(old, name), os.path.join(new, name)
        if os.path.isdir(src) and not os.path.islink(src):
            shutil.copytree(src, dst, symlinks=True, copy_function=link_or_copy)
        elif os.path.islink(src):
            os.symlink(os.readlink(src), dst)
        else:
            link_or_copy(src, dst)


def write_model_files(model, seqs, split, log, args, folder, horizons):
    import train as T
    n = seqs[0].resolution
    paths = export_onnx(model, n, folder)
    ops = sorted(set(check_onnx_for_opencv(paths["flownet"])) | set(check_onnx_for_opencv(paths["cloudnet"])))
    real = [s for s in seqs if "preset" in s.meta]
    ref_seq = real[0] if real else seqs[0]
    write_reference(model, ref_seq.images[split[ref_seq.name]["heldout"][0]], folder)
    used_split = {s.name: split[s.name] for s in seqs}
    with open(os.path.join(folder, "split.json"), "w") as f:
        json.dump(used_split, f, indent=2)
    metrics = T.evaluate_heldout(model, seqs, split, horizons)
    cpu = T.cpu_time_per_step(model, n, threads=1)
    fw, cw = T.parse_widths(args.flow_widths), T.parse_widths(args.cloud_widths)
    info = {
        "format": "dynsky-cloud-model",
        "version": 1,
        "name": args.name or os.path.basename(os.path.normpath(args.out)),
        "resolution": n,
        "import_resolution": int(seqs[0].meta.get("import_resolution", n)),
        "dt_s": float(seqs[0].meta["dt_s"]),
        "flow_scale": D.FLOW_SCALE,
        # The [0, 1] form the networks were trained on (sky/hdr_recovery.h log map, sky/cloud_mask.h rule).
        "unit_scale": float(seqs[0].meta.get("unit_scale", 1.0)),
        "unit_max": float(seqs[0].meta.get("unit_max", 300.0)),
        "cloud_rule": seqs[0].meta.get("cloud_rule", "rb"),
        "cloud_threshold": float(seqs[0].meta.get("cloud_threshold", 0.75)),
        "flow_widths": list(fw),
        "cloud_widths": list(cw),
        "warp_kernel": args.kernel,
        "flow_encoding": "ch0, ch1 = (cos, sin) of the direction (+x right, +y down); ch2 = min(|flow| / (flow_scale N), 1); "
                         "flow = Farneback flow frame k -> k+1 times the cloud mask",
        "onnx_opset": 11,
        "onnx_ops": ops,
        "trained_on": [s.name for s in seqs],
        "epochs": args.epochs,
        "unroll": args.unroll,
        "seed": args.seed,
        "loss": loss_record(args),
        "parameters": U.parameter_count(model),
        "macs_per_step": U.step_flops(n, fw, cw, args.kernel),
        "pytorch_cpu_seconds_per_step_1_thread": cpu,
        "heldout_psnr_python": metrics,
        "created": datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%M:%SZ"),
    }
    with open(os.path.join(folder, "model.json"), "w") as f:
        json.dump(info, f, indent=2)
    with open(os.path.join(folder, "training_log.json"), "w") as f:
        json.dump(log, f, indent=1)
    write_model_card(args.out, info, seqs, used_split, log, metrics, args, into=folder)
    return info


def loss_record(args):
    """The training loss's weights for model.json (networks/train.py step_losses)."""
    cw = getattr(args, "cos_weight", 0.5)
    return {"image": f"MSE + {0.1 * cw:g} x (1 - cos of RGB vectors)",
            "flow": f"MSE + {cw:g} x (1 - cos of directions, cloud pixels)",
            "flow_weight": args.flow_weight, "cos_weight": cw}


def loss_text(args):
    cw = getattr(args, "cos_weight", 0.5)
    if cw == 0:
        return f"image MSE + {args.flow_weight} x flow MSE (MSE only: no cosine-similarity terms, --cos-weight 0)"
    return (f"image MSE + {0.1 * cw:g} x (1 - cosine similarity of RGB vectors) + {args.flow_weight} x (flow MSE + "
            f"{cw:g} x (1 - cosine similarity of directions) on cloud pixels) (--cos-weight {cw:g})")


def write_model_card(folder, info, seqs, split, log, metrics, args, into=None):
    """folder: the model folder the card names; into: where it is written (default: folder)."""
    lines = [f"# Model card: {info['name']}", "",
             "The medium-timescale cloud model of Satilmis & Bashford-Rogers, \"Deep Dynamic Cloud Lighting\": "
             "one step moves the clouds of a sky forward by Delta t, xi(I) = CloudNet(I concat FlowNet(I)). "
             "Run it with `dynsky sky predict --model " + folder + "` (docs/networks.md).", "",
             "## What it is", "",
             f"- Input/output: {info['resolution']} x {info['resolution']} canonical fisheye (equidistant, north up, "
             "east left), RGB in the networks' [0, 1] form (sky/hdr_recovery.h forward map); 0 outside the disc.",
             f"- Delta t = {info['dt_s']:g} s per step; predictions recurse for longer horizons.",
             f"- FlowNet widths {info['flow_widths']}, CloudNet widths {info['cloud_widths']} (UNet: 4x4 stride-2 "
             "conv + BatchNorm + LeakyReLU(0.2) down; bilinear x2 + 3x3 conv + BatchNorm + ReLU up; skips; 3x3 output conv). "
             f"CloudNet's output moves the input's pixels with predicted per-pixel {args.kernel} x {args.kernel} kernels "
             "(a softmax over the neighbours) plus a 0.1 tanh-bounded change; both UNets also see each pixel's (u, v) "
             "position (docs/networks.md says why).",
             f"- {info['parameters']:,} parameters, {info['macs_per_step'] / 1e6:.1f} M multiply-adds per step; "
             f"PyTorch CPU time per step (1 thread, this machine): {info['pytorch_cpu_seconds_per_step_1_thread'] * 1e3:.1f} ms.",
             f"- ONNX opset 11, fixed input size; operators: {', '.join(info['onnx_ops'])}.", "",
             "## Data and split", ""]
    for s in seqs:
        sp = split[s.name]
        lines.append(f"- `{s.name}`: {s.meta['source']}; {len(s)} frames every {s.meta['dt_s']:g} s, imported at "
                     f"{s.meta.get('import_resolution', '?')} px and area-averaged to {s.resolution} px. Training frames "
                     f"{sp['train'][0]}..{sp['train'][1] - 1}, held out (the last 20 % in time) {sp['heldout'][0]}.."
                     f"{sp['heldout'][1] - 1}.")
    lines += ["- Real photographs: ARM SGP C1 Total Sky Imager, 2017-05-24 (US DOE ARM user facility; "
              "../shared/skies/PROVENANCE.md). The photographs are not shipped; only weights trained on them.",
              "- Targets: the next real frame, and the Farneback flow (OpenCV) frame -> next masked by the cloud "
              "mask, encoded as (cos, sin, magnitude / (flow_scale N)), flow_scale = "
              f"{info['flow_scale']} (networks/data.py). Pixels hidden by the camera's arm and shadow band are "
              "left out of every loss and metric.", "",
              "## Training", "",
              f"- `/usr/bin/python3 networks/train.py {' '.join(getattr(args, 'argv_text', '').split())}`" if getattr(args, 'argv_text', '') else
              "- networks/train.py (see training_log.json for the arguments' effect per epoch)",
              f"- {args.epochs} epochs, batch {args.batch}, Adam lr {args.lr} with cosine decay, seed {args.seed}, "
              f"{args.unroll} recursive steps per window (each prediction fed back), loss = {loss_text(args)}; CPU only.",
              "", "## Held-out results (PyTorch, mean per-frame PSNR over seen sky pixels)", "",
              "| sequence | horizon | model PSNR | persistence PSNR |", "|---|---:|---:|---:|"]
    for name, r in metrics.items():
        for h, v in r.items():
            lines.append(f"| {name} | {h} | {v['model']:.2f} dB | {v['persistence']:.2f} dB |")
    lines += ["", "The full comparison with persistence and Farneback extrapolation (PSNR and SSIM, computed by "
              "`dynsky sky evaluate` with OpenCV) is in docs/networks.md.", "",
              "## Limits", "",
              "- Trained on one day of one camera: it has learnt that day's wind. It sees one frame, so it cannot "
              "know a different day's wind except from cloud shapes; expect persistence-like behaviour elsewhere.",
              "- The [0, 1] form cannot hold the sun; `dynsky sky predict` re-inserts the input's sun.", ""]
    with open(os.path.join(into or folder, "MODEL_CARD.md"), "w") as f:
        f.write("\n".join(lines))


def main(argv=None):
    """Not a command of its own: --help says what writes the model folder."""
    import argparse
    p = argparse.ArgumentParser(
        prog="export.py", formatter_class=argparse.RawDescriptionHelpFormatter,
        description=__doc__ + "\nA module, not a command: networks/train.py writes this folder at the end of training "
        "(write_model_folder). To write it again from a finished run's checkpoint, repeat the training command with "
        "--resume (every epoch is done, so it only exports). Advect-residual models: networks/export_advect.py.")
    p.parse_args(argv)
    p.exit(2, "export.py: error: not a command: networks/train.py writes the model folder (run it again with --resume "
              "to export a finished run's checkpoint); see export.py --help\n")


if __name__ == "__main__":
    main()
