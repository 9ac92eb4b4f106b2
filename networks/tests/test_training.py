"""Tests of the cloud-model training code, run by CTest (tests/CMakeLists.txt, NetworksTraining):

  cd networks && /usr/bin/python3 -m unittest -v tests.test_training

Small and synthetic (a smooth texture drifting at a known speed), a few seconds on one core.
"""
import json
import os
import shutil
import sys
import tempfile
import unittest

try:
    import numpy as np
    import torch
    HAVE_TORCH = True
except ImportError:  # pragma: no cover
    HAVE_TORCH = False

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def drifting_sequence(frames, n, shift=(1.0, 0.5), seed=0):
    """Frames of a smooth random texture moving by `shift` px per frame, inside the fisheye disc,
    and the exact flow (the same everywhere)."""
    import data as D
    rng = np.random.default_rng(seed)
    big = rng.random((n * 2, n * 2, 3)).astype(np.float32)
    t = torch.from_numpy(big).permute(2, 0, 1)[None]
    t = torch.nn.functional.avg_pool2d(t, 5, stride=1, padding=2)
    t = torch.nn.functional.avg_pool2d(t, 5, stride=1, padding=2)
    disc = D.disc_mask(n)
    images = []
    for k in range(frames):
        theta = torch.tensor([[[1.0, 0.0, -2 * shift[0] * k / (2 * n)], [0.0, 1.0, -2 * shift[1] * k / (2 * n)]]])
        grid = torch.nn.functional.affine_grid(theta, (1, 3, 2 * n, 2 * n), align_corners=False)
        w = torch.nn.functional.grid_sample(t, grid, align_corners=False, padding_mode="reflection")
        img = w[0, :, n // 2:n // 2 + n, n // 2:n // 2 + n].permute(1, 2, 0).numpy()
        img = (img - img.min()) / (img.max() - img.min() + 1e-6) * 0.6 + 0.2
        images.append(img * disc[..., None])
    flow = np.zeros((frames - 1, n, n, 2), np.float32)
    flow[..., 0], flow[..., 1] = shift
    return np.stack(images).astype(np.float32), disc, flow


def write_dataset(folder, frames=24, n=32):
    images, disc, flow = drifting_sequence(frames, n)
    seq = os.path.join(folder, "synthetic")
    os.makedirs(seq)
    np.save(os.path.join(seq, "images.npy"), images)
    np.save(os.path.join(seq, "valid.npy"), np.repeat(disc[None], frames, 0).astype(np.uint8))
    np.save(os.path.join(seq, "cloud.npy"), np.repeat(disc[None], frames, 0).astype(np.uint8))
    np.save(os.path.join(seq, "flow_farneback.npy"), flow)
    with open(os.path.join(seq, "meta.json"), "w") as f:
        json.dump({"dt_s": 30.0, "resolution": n, "import_resolution": n, "frame_count": frames,
                   "source": "synthetic drifting texture (test)", "preset": "none"}, f)
    cut = frames - frames // 5
    with open(os.path.join(folder, "split.json"), "w") as f:
        json.dump({"synthetic": {"train": [0, cut], "heldout": [cut, frames], "dt_s": 30.0}}, f)


@unittest.skipUnless(HAVE_TORCH, "SKIPPED: torch (or numpy) is not installed for /usr/bin/python3")
class TrainingTest(unittest.TestCase):
    def setUp(self):
        torch.set_num_threads(1)
        torch.manual_seed(0)
        self.tmp = tempfile.mkdtemp(prefix="dynsky-networks-test-")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def test_tiny_network_loss_falls(self):
        import train as T
        import unet as U
        import data as D
        n = 32
        images, disc, flow = drifting_sequence(12, n)
        target = D.encode_flow(flow, np.repeat(disc[None], 11, 0).astype(np.uint8))
        model = U.CloudModel((4, 8), (4, 8))
        opt = torch.optim.Adam(model.parameters(), lr=3e-3)
        x = torch.from_numpy(images).permute(0, 3, 1, 2)
        tf = torch.from_numpy(target).permute(0, 3, 1, 2)
        dm = torch.from_numpy(disc.astype(np.float32))[None, None]
        valid = dm.expand(10, 1, n, n)
        losses = []
        for step in range(25):
            pred, f = model(x[:10], dm)
            il, fl, _ = T.step_losses(pred, f, x[1:11], tf[:10], valid)
            loss = il + 0.1 * fl
            opt.zero_grad()
            loss.backward()
            opt.step()
            losses.append(float(loss))
        self.assertTrue(all(np.isfinite(losses)))
        first, last = np.mean(losses[:3]), np.mean(losses[-3:])
        self.assertLess(last, 0.5 * first, f"loss {first:.4f} -> {last:.4f}")

    def test_flow_encoding_round_trip(self):
        import data as D
        rng = np.random.default_rng(1)
        flow = rng.normal(0, 2, (2, 16, 16, 2)).astype(np.float32)
        cloud = (rng.random((2, 16, 16)) > 0.3).astype(np.uint8)
        enc = D.encode_flow(flow, cloud)
        self.assertTrue(np.all(np.abs(enc[..., :2]) <= 1.0 + 1e-6))
        self.assertTrue(np.all((enc[..., 2] >= 0) & (enc[..., 2] <= 1)))
        dec = D.decode_flow(enc)
        expect = flow * cloud[..., None]
        small = np.sqrt((expect ** 2).sum(-1)) < D.FLOW_SCALE * 16  # not clipped by the encoding
        np.testing.assert_allclose(dec[small], expect[small], atol=1e-4)
        np.testing.assert_array_equal(enc[cloud == 0], 0.0)

    def test_export_is_in_opencv_form(self):
        import export as E
        import unet as U
        model = U.CloudModel((4, 8, 8), (4, 8, 8)).eval()
        E.export_onnx(model, 32, self.tmp)
        for name in ("flownet", "cloudnet"):
            ops = E.check_onnx_for_opencv(os.path.join(self.tmp, name + ".onnx"))
            self.assertIn("Resize", ops)
            self.assertNotIn("Shape", ops)

    def test_train_command_writes_a_model_folder_and_resumes(self):
        import train as T
        write_dataset(self.tmp, frames=16, n=32)
        out = os.path.join(self.tmp, "model")
        args = ["--data", self.tmp, "--sequences", "synthetic", "--flow-widths", "4,8", "--cloud-widths", "4,8",
                "--epochs", "2", "--batch", "4", "--unroll", "2", "--eval-every", "1", "--threads", "1", "--out", out]
        T.main(args[:-4] + ["--epochs", "1", "--no-export", "--out", out])
        self.assertTrue(os.path.exists(os.path.join(out, "checkpoint.pt")))
        _, log = T.main(args + ["--resume"])  # continues at epoch 2, then exports
        self.assertEqual([e["epoch"] for e in log], [1, 2])
        for f in ("flownet.onnx", "cloudnet.onnx", "model.json", "split.json", "MODEL_CARD.md",
                  "reference_input.npy", "reference_flow.npy", "reference_next.npy"):
            self.assertTrue(os.path.exists(os.path.join(out, f)), f)
        with open(os.path.join(out, "model.json")) as f:
            info = json.load(f)
        self.assertEqual(info["resolution"], 32)
        self.assertEqual(info["dt_s"], 30.0)
        self.assertEqual(info["flow_widths"], [4, 8])
        self.assertIn("heldout_psnr_python", info)
        ref_in = np.load(os.path.join(out, "reference_input.npy"))
        self.assertEqual(ref_in.shape, (32, 32, 3))


if __name__ == "__main__":
    unittest.main()
