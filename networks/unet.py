"""The two UNets of the medium-timescale cloud model (Satilmis & Bashford-Rogers, "Deep Dynamic
Cloud Lighting"): xi(I) = CloudNet(I concat FlowNet(I)).

Architecture as in the paper: encoder blocks are 4x4 stride-2 convolutions + BatchNorm +
LeakyReLU(0.2); decoder blocks are x2 bilinear upsampling + 3x3 convolution + BatchNorm + ReLU,
each concatenated with the encoder features of the same size (skips). Width and depth are
parameters so that small configurations can be compared (networks/sweep.py).

Everything here exports to ONNX in the form OpenCV 4.6's importer runs exactly (../shared/NOTES.md):
opset 11, fixed input size, Resize with constant scales (nn.Upsample(scale_factor=2)), Conv,
BatchNorm, LeakyRelu, Relu, Concat, Tanh, Sigmoid, Add, Slice with constant bounds.
"""
import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F


class EncoderBlock(nn.Module):
    def __init__(self, cin, cout, norm=True):
        super().__init__()
        self.conv = nn.Conv2d(cin, cout, 4, stride=2, padding=1, bias=not norm)
        self.norm = nn.BatchNorm2d(cout) if norm else nn.Identity()
        self.act = nn.LeakyReLU(0.2)

    def forward(self, x):
        return self.act(self.norm(self.conv(x)))


class DecoderBlock(nn.Module):
    def __init__(self, cin, cout):
        super().__init__()
        self.up = nn.Upsample(scale_factor=2, mode="bilinear", align_corners=False)
        self.conv = nn.Conv2d(cin, cout, 3, padding=1, bias=False)
        self.norm = nn.BatchNorm2d(cout)
        self.act = nn.ReLU()

    def forward(self, x, skip):
        x = self.act(self.norm(self.conv(self.up(x))))
        return torch.cat([x, skip], dim=1) if skip is not None else x


def coordinate_planes(n, batch=1):
    """(u, v) of every pixel centre in [-1, 1] (sky/fisheye.h), as a 1 x 2 x n x n tensor."""
    c = (np.arange(n, dtype=np.float32) + 0.5) * (2.0 / n) - 1.0
    planes = torch.from_numpy(np.stack([np.tile(c[None, :], (n, 1)), np.tile(c[:, None], (1, n))])[None])
    return planes if batch == 1 else planes.expand(batch, 2, n, n)


class UNet(nn.Module):
    """widths[k] is the channel count after encoder block k (len(widths) = depth); the input size
    must be divisible by 2^depth. The last decoder block upsamples back to full resolution and a
    3x3 convolution maps to out_channels (no activation: the wrappers below add theirs).

    Position (a deviation from the paper, measured on the ARM sequence): the fisheye makes cloud
    motion depend strongly on where in the image a cloud is (warping held-out frames by the
    per-pixel mean training flow gives 27.5 dB at 64 px, by the global mean flow 21.5 dB,
    persistence 22.0 dB), and a UNet alone is translation-equivariant. So the first convolution and
    the output convolution also see the pixel's (u, v), as if two coordinate planes were
    concatenated to their inputs. They are added as separate convolutions of the planes because
    OpenCV 4.6 mis-runs an ONNX Concat with a constant input, while Add of a constant tensor is
    exact; freeze_position() turns them into such constants before export."""

    def __init__(self, in_channels, out_channels, widths=(16, 32, 64, 64), coords=True):
        super().__init__()
        self.widths = tuple(int(w) for w in widths)
        self.coords = coords
        self.encoders = nn.ModuleList()
        cin = in_channels
        for k, w in enumerate(self.widths):
            # pix2pix's convention: no normalisation on the first block (it sees raw pixels).
            self.encoders.append(EncoderBlock(cin, w, norm=k > 0))
            cin = w
        self.decoders = nn.ModuleList()
        depth = len(self.widths)
        for k in reversed(range(depth)):
            skip = self.widths[k - 1] if k > 0 else in_channels
            cout = self.widths[k - 1] if k > 0 else max(self.widths[0] // 2, 8)
            self.decoders.append(DecoderBlock(cin, cout))
            cin = cout + skip
        # 3x3, not 1x1: the output layer sees the input's own spatial derivatives at full
        # resolution, which is what moving an edge by a pixel or two amounts to.
        self.head = nn.Conv2d(cin, out_channels, 3, padding=1)
        if coords:
            self.pos_in = nn.Conv2d(2, self.widths[0], 4, stride=2, padding=1, bias=False)
            self.pos_out = nn.Conv2d(2, out_channels, 3, padding=1, bias=False)
        self.frozen = None

    def position_terms(self, n):
        planes = coordinate_planes(n)
        return self.pos_in(planes), self.pos_out(planes)

    def freeze_position(self, n):
        """For export: the position terms become constant tensors (ONNX Add of an initializer)."""
        if self.coords:
            with torch.no_grad():
                a, b = self.position_terms(n)
            self.frozen = (a.detach().clone(), b.detach().clone())

    def forward(self, x):
        if self.coords:
            pin, pout = self.frozen if self.frozen is not None else self.position_terms(int(x.shape[-1]))
        skips = [x]
        enc0 = self.encoders[0]
        h = enc0.conv(x)
        if self.coords:
            h = h + pin
        x = enc0.act(enc0.norm(h))
        skips.append(x)
        for enc in self.encoders[1:]:
            x = enc(x)
            skips.append(x)
        skips.pop()  # the bottleneck is not a skip
        for dec in self.decoders:
            x = dec(x, skips.pop())
        y = self.head(x)
        return y + pout if self.coords else y


class FlowNet(nn.Module):
    """Sky image in [0,1] (3 channels) -> flow (3 channels): (cos, sin) of the direction, in
    [-1, 1] via tanh, and the normalised magnitude in [0, 1] via sigmoid (encoding: dataset.py)."""

    def __init__(self, widths=(16, 32, 64, 64)):
        super().__init__()
        self.unet = UNet(3, 3, widths)

    def forward(self, image):
        y = self.unet(image)
        return torch.cat([torch.tanh(y[:, 0:2]), torch.sigmoid(y[:, 2:3])], dim=1)


class LocalKernelWarp(nn.Module):
    """Moves pixels by predicted per-pixel k x k kernels: out(x) = sum_j w_j(x) I(x + o_j) with
    w_j = e_j / sum e, e_j = exp(4 tanh(logit_j)) (a softmax over the k^2 offsets, bounded).

    Why: a plain UNet cannot warp, and cloud motion in the fisheye is a position-dependent shift of
    1-4 px per step at 64 px. A convex combination of neighbours can represent any such sub-pixel
    shift, and it cannot create values outside the input's range, so recursive rollouts cannot run
    away (kernel-prediction networks, e.g. Niklaus et al. 2017, "Video Frame Interpolation via
    Adaptive Convolution"). Built from Conv (fixed one-hot shift kernels), Tanh, Exp, Mul, Div and
    Concat on tensors of equal shape, which OpenCV's ONNX importer runs."""

    def __init__(self, k=5):
        super().__init__()
        self.k = k
        shifts = torch.zeros(k * k, 1, k, k)
        for j in range(k * k):
            shifts[j, 0, j // k, j % k] = 1.0
        self.register_buffer("shifts", shifts)
        self.register_buffer("ones", torch.ones(1, k * k, 1, 1))

    def forward(self, image, logits):
        e = torch.exp(4.0 * torch.tanh(logits))
        norm = F.conv2d(e, self.ones)
        out = []
        for c in range(image.shape[1]):
            neighbours = F.conv2d(image[:, c:c + 1], self.shifts, padding=self.k // 2)
            out.append(F.conv2d(neighbours * e, self.ones) / norm)
        return torch.cat(out, dim=1)


class CloudNet(nn.Module):
    """Image (3) concat flow (3) -> the next image: the UNet predicts, per pixel, k x k kernel
    weights that move the input's pixels (LocalKernelWarp) and a small bounded change (0.1 tanh)
    for clouds that form, grow or fade. Starts as the identity (persistence). The caller clamps to
    [0, 1]. kernel=0 gives the plain residual form (input + tanh(UNet)) of the first experiments."""

    def __init__(self, widths=(16, 32, 64, 64), kernel=5):
        super().__init__()
        self.kernel = kernel
        if kernel:
            self.unet = UNet(6, kernel * kernel + 3, widths)
            self.warp = LocalKernelWarp(kernel)
            with torch.no_grad():  # start at the identity: the centre tap dominates
                self.unet.head.bias.zero_()
                self.unet.head.bias[(kernel * kernel) // 2] = 1.0
        else:
            self.unet = UNet(6, 3, widths)

    def forward(self, image_and_flow):
        y = self.unet(image_and_flow)
        image = image_and_flow[:, 0:3]
        if not self.kernel:
            return image + torch.tanh(y)
        kk = self.kernel * self.kernel
        return self.warp(image, y[:, 0:kk]) + 0.1 * torch.tanh(y[:, kk:kk + 3])


class CloudModel(nn.Module):
    """One medium step xi on [0,1] images, with the sky-disc mask applied so pixels outside the
    disc stay 0 (what the canonical image holds there)."""

    def __init__(self, flow_widths, cloud_widths, kernel=5):
        super().__init__()
        self.flownet = FlowNet(flow_widths)
        self.cloudnet = CloudNet(cloud_widths, kernel)

    def forward(self, image, disc):
        flow = self.flownet(image)
        nxt = self.cloudnet(torch.cat([image, flow], dim=1))
        return torch.clamp(nxt, 0.0, 1.0) * disc, flow


def parameter_count(module):
    return sum(p.numel() for p in module.parameters())


def step_flops(resolution, flow_widths, cloud_widths, kernel=5):
    """Multiply-accumulates of one step (both networks), by running a forward pass with hooks."""
    macs = [0]

    def hook(mod, inp, out):
        if isinstance(mod, nn.Conv2d):
            k = mod.kernel_size[0] * mod.kernel_size[1] * mod.in_channels // mod.groups
            macs[0] += out.numel() * k

    model = CloudModel(flow_widths, cloud_widths, kernel).eval()
    handles = [m.register_forward_hook(hook) for m in model.modules() if isinstance(m, nn.Conv2d)]
    with torch.no_grad():
        model(torch.zeros(1, 3, resolution, resolution), torch.ones(1, 1, resolution, resolution))
    for h in handles:
        h.remove()
    return macs[0]
