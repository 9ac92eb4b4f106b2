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
        self.assertTrue(os.path.exists(os.path.join(out, "checkpoint.pt")))  # the export keeps it

    def tiny_args(self, out, **over):
        """train.py's arguments for a tiny run on write_dataset's data; over: option -> value (None: drop)."""
        opts = {"--data": self.tmp, "--sequences": "synthetic", "--flow-widths": "4,8", "--cloud-widths": "4,8",
                "--epochs": "1", "--batch": "4", "--unroll": "2", "--eval-every": "1", "--threads": "1", "--out": out}
        opts.update(over)
        args = [a for k, v in opts.items() if v is not None for a in (k, v)]
        return args

    def test_failed_export_leaves_the_old_model_folder_and_the_checkpoint(self):
        """The export wrote the ONNX files, then model.json, into the folder itself: a failure midway
        left new networks under an old model.json, which dynsky ran (an audit)."""
        import export as E
        import train as T
        from unittest import mock
        from script_errors import ScriptError
        write_dataset(self.tmp, frames=16, n=32)
        out = os.path.join(self.tmp, "model")
        T.main(self.tiny_args(out))
        with open(os.path.join(out, "notes.txt"), "w") as f:
            f.write("a user's file")
        def read(f):
            with open(os.path.join(out, f), "rb") as fh:
                return fh.read()
        before = {f: read(f) for f in ("model.json", "flownet.onnx", "MODEL_CARD.md")}
        with mock.patch.object(E, "write_model_card", side_effect=OSError(28, "No space left on device")):
            with self.assertRaises(ScriptError) as e:
                T.main(self.tiny_args(out, **{"--epochs": "2"}) + ["--resume"])
        self.assertEqual(e.exception.code, 1)
        self.assertIn("unchanged", str(e.exception))
        for f, data in before.items():
            self.assertEqual(read(f), data, f)
        self.assertEqual(torch.load(os.path.join(out, "checkpoint.pt"))["epoch"], 2)
        self.assertEqual([f for f in os.listdir(self.tmp) if f.startswith(".")], [])  # no temporary left
        T.main(self.tiny_args(out, **{"--epochs": "2"}) + ["--resume"])  # every epoch done: exports only
        with open(os.path.join(out, "model.json")) as f:
            self.assertEqual(json.load(f)["epochs"], 2)
        self.assertEqual(torch.load(os.path.join(out, "checkpoint.pt"))["epoch"], 2)
        self.assertTrue(os.path.exists(os.path.join(out, "notes.txt")))
        self.assertEqual([f for f in os.listdir(self.tmp) if f.startswith(".")], [])

    def test_empty_heldout_part_is_refused_before_training(self):
        """A 2-frame sequence has held-out [2, 2]: training ran and died in export (IndexError)."""
        import train as T
        from script_errors import ScriptError
        write_dataset(self.tmp, frames=16, n=32)
        with open(os.path.join(self.tmp, "split.json"), "w") as f:
            json.dump({"synthetic": {"train": [0, 16], "heldout": [16, 16], "dt_s": 30.0}}, f)
        out = os.path.join(self.tmp, "model")
        with self.assertRaises(ScriptError) as e:
            T.main(self.tiny_args(out))
        self.assertEqual(e.exception.code, 1)
        self.assertIn("empty heldout part", str(e.exception))
        self.assertFalse(os.path.exists(out))

    def test_interrupted_checkpoint_write_keeps_the_previous_checkpoint(self):
        """torch.save wrote straight onto the only checkpoint: a kill during the write lost every
        epoch; Ctrl-C printed a traceback."""
        import train as T
        from unittest import mock
        from script_errors import ScriptError
        write_dataset(self.tmp, frames=16, n=32)
        out = os.path.join(self.tmp, "model")
        T.main(self.tiny_args(out, **{"--no-export": None}) + ["--no-export"])

        def cut_short(obj, f, *a, **k):  # half a file, then Ctrl-C
            if isinstance(f, str):
                f = open(f, "wb")
            f.write(b"PK\x03\x04 half a checkpoint")
            f.flush()
            raise KeyboardInterrupt

        def interrupted(args):
            try:
                T.main(args)
            except ScriptError as e:
                return e
            except KeyboardInterrupt:
                self.fail("Ctrl-C ended in a KeyboardInterrupt traceback")
            self.fail("not interrupted")

        with mock.patch("torch.save", side_effect=cut_short):
            e = interrupted(self.tiny_args(out, **{"--epochs": "2"}) + ["--no-export", "--resume"])
            self.assertEqual(e.code, 3)
            self.assertIn("--resume", str(e))
            e = interrupted(self.tiny_args(os.path.join(self.tmp, "new")) + ["--no-export"])  # in its first epoch
            self.assertEqual(e.code, 3)
            self.assertIn("nothing to resume", str(e))
        self.assertEqual(torch.load(os.path.join(out, "checkpoint.pt"))["epoch"], 1)
        self.assertEqual(sorted(os.listdir(out)), ["checkpoint.pt"])

    def test_option_values_training_cannot_use_are_usage_errors(self):
        """--epochs -1 exited 0 with an untrained model, --epochs 0 with ZeroDivisionError; the others
        died with tracebacks (an even --kernel, 6 levels at 32 px: BatchNorm on a 1 x 1 map)."""
        import train as T
        from script_errors import ScriptError
        write_dataset(self.tmp, frames=16, n=32)
        out = os.path.join(self.tmp, "model")
        for over, name in (({"--epochs": "0"}, "--epochs"), ({"--epochs": "-1"}, "--epochs"),
                           ({"--unroll": "0"}, "--unroll"), ({"--batch": "0"}, "--batch"),
                           ({"--kernel": "4"}, "--kernel"), ({"--lr": "0"}, "--lr"), ({"--lr": "-0.001"}, "--lr"),
                           ({"--flow-widths": "4,4,4,4,4,4"}, "--flow-widths"),
                           ({"--res": "16", "--cloud-widths": "4,4,4,4,4"}, "--cloud-widths"),
                           ({"--cloud-widths": "4,4,4,4,4", "--batch": "1"}, "--cloud-widths")):
            with self.assertRaises(ScriptError, msg=str(over)) as e:
                T.main(self.tiny_args(out, **over))
            self.assertEqual(e.exception.code, 2, str(over))
            self.assertIn(name, str(e.exception))
            self.assertEqual(len(str(e.exception).splitlines()), 1)
        self.assertFalse(os.path.exists(out))

    def test_resume_with_fewer_epochs_than_finished_is_refused(self):
        """It exported the checkpoint's 2-epoch weights and wrote "epochs": 1 in model.json and the card."""
        import train as T
        from script_errors import ScriptError
        write_dataset(self.tmp, frames=16, n=32)
        out = os.path.join(self.tmp, "model")
        T.main(self.tiny_args(out, **{"--epochs": "2"}) + ["--no-export"])
        with self.assertRaises(ScriptError) as e:
            T.main(self.tiny_args(out) + ["--resume"])
        self.assertEqual(e.exception.code, 2)
        self.assertIn("--epochs 1", str(e.exception))
        self.assertIn("2 epochs", str(e.exception))
        self.assertFalse(os.path.exists(os.path.join(out, "model.json")))


class DatasetScriptTest(unittest.TestCase):
    """networks/dataset.py with a stand-in for dynsky (no build needed, no torch)."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="dynsky-networks-test-")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def fake_dynsky(self, body):
        path = os.path.join(self.tmp, "dynsky")
        with open(path, "w") as f:
            f.write(f"#!{sys.executable}\nimport json, os, sys\n{body}\n")
        os.chmod(path, 0o755)
        return path

    def dataset(self, dynsky, out):
        import subprocess
        script = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "dataset.py")
        return subprocess.run([sys.executable, script, "--out", out, "--dynsky", dynsky, "--no-procedural"],
                              capture_output=True, text=True, timeout=60)

    def test_dynsky_errors_are_one_line_with_dynsky_exit_code(self):
        """check=True followed each clear dynsky message with a CalledProcessError traceback, and an
        empty --out folder was left behind."""
        for code in (1, 2):
            dynsky = self.fake_dynsky(f"print('dynsky: error: skies: no photographs', file=sys.stderr)\nsys.exit({code})")
            out = os.path.join(self.tmp, "data")
            r = self.dataset(dynsky, out)
            self.assertEqual(r.returncode, code, r.stderr)
            self.assertIn("dynsky: error: skies: no photographs", r.stderr)
            self.assertIn("dataset.py: error:", r.stderr)
            self.assertNotIn("Traceback", r.stderr)
            self.assertFalse(os.path.exists(out))
        os.makedirs(out)  # a folder the run did not create stays
        self.dataset(dynsky, out)
        self.assertTrue(os.path.isdir(out))

    def test_sequence_too_short_for_the_split_is_refused(self):
        """2 frames gave held-out [2, 2]; training died at its end with IndexError."""
        dynsky = self.fake_dynsky("out = sys.argv[sys.argv.index('--out') + 1]\nos.makedirs(out)\n"
                                  "json.dump({'frame_count': 2, 'dt_s': 30.0}, open(os.path.join(out, 'meta.json'), 'w'))")
        out = os.path.join(self.tmp, "data")
        r = self.dataset(dynsky, out)
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("heldout part", r.stderr)
        self.assertNotIn("Traceback", r.stderr)
        self.assertFalse(os.path.exists(out))


@unittest.skipUnless(HAVE_TORCH, "SKIPPED: torch (or numpy) is not installed for /usr/bin/python3")
class AdvectResidualTest(unittest.TestCase):
    """The advect-residual model (networks/advect.py): warp rule, symmetries, training, export."""

    def setUp(self):
        torch.set_num_threads(1)
        torch.manual_seed(0)
        self.tmp = tempfile.mkdtemp()

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    @staticmethod
    def bilinear(img, x, y):
        """Hand bilinear sample of img (C, N, N) at pixel (x, y), border replicate."""
        n = img.shape[-1]
        x = min(max(x, 0.0), n - 1.0)
        y = min(max(y, 0.0), n - 1.0)
        x0, y0 = int(np.floor(x)), int(np.floor(y))
        x1, y1 = min(x0 + 1, n - 1), min(y0 + 1, n - 1)
        fx, fy = x - x0, y - y0
        return ((1 - fx) * (1 - fy) * img[:, y0, x0] + fx * (1 - fy) * img[:, y0, x1]
                + (1 - fx) * fy * img[:, y1, x0] + fx * fy * img[:, y1, x1])

    def test_warp_matches_hand_computation(self):
        import advect as A
        n = 8
        rng = np.random.default_rng(3)
        img = rng.random((3, n, n)).astype(np.float32) * A.disc_mask(n)[None]
        # Rim extension of the corner pixel (0, 0): u = v = -0.875, r = 1.2374 > r_in = 0.8125.
        u = 2 * 0.5 / n - 1
        s = (1 - 1.5 / n) / np.hypot(u, u)
        x = (u * s + 1) * n / 2 - 0.5
        e = A.rim_extend(torch.from_numpy(img)[None])[0].numpy()
        np.testing.assert_allclose(e[:, 0, 0], self.bilinear(img, x, x), atol=1e-5)
        np.testing.assert_allclose(e[:, 3, 4], img[:, 3, 4], atol=1e-6)  # inside r_in: unchanged
        # Warp with a flow of (0.5, -0.25) px at pixel (i=4, j=3): W = E(I)(4 - 0.5, 3 + 0.25).
        flow = np.zeros((2, n, n), np.float32)
        flow[:, 3, 4] = (0.5, -0.25)
        flow[:, 0, 0] = (2.0, 2.0)  # outside the disc: W is 0 there whatever F says
        w = A.warp(torch.from_numpy(img)[None], torch.from_numpy(flow)[None])[0].numpy()
        np.testing.assert_allclose(w[:, 3, 4], self.bilinear(e, 3.5, 3.25), atol=1e-5)
        np.testing.assert_allclose(w[:, 0, 0], 0.0)
        # The Farneback baseline (sky_metrics.cpp advect_by_flow): 0 beyond the image, 2 steps.
        flow[:, 3, 0] = (1.0, 0.0)
        adv = A.advect_by_flow(torch.from_numpy(img)[None], torch.from_numpy(flow)[None], 2)[0].numpy()
        np.testing.assert_allclose(adv[:, 3, 4], self.bilinear(img, 3.0, 3.5), atol=1e-5)
        np.testing.assert_allclose(adv[:, 3, 0], 0.0, atol=1e-7)  # samples x = -2: black
        # The network input: [W, I, F / (0.08 N)].
        x8 = A.network_input(torch.from_numpy(img)[None], torch.from_numpy(flow)[None])[0].numpy()
        self.assertEqual(x8.shape, (8, n, n))
        np.testing.assert_allclose(x8[6:, 3, 4], np.array([0.5, -0.25]) / (0.08 * n), atol=1e-6)

    def smooth_disc_image(self, n):
        import advect as A
        c = A.pixel_centres(n)
        u, v = np.meshgrid(c, c)
        img = np.stack([0.5 + 0.3 * np.sin(3 * u + 1) * np.cos(2 * v), 0.4 + 0.2 * np.cos(2 * u - v),
                        0.6 + 0.1 * u * v]).astype(np.float32)
        return torch.from_numpy(img * A.disc_mask(n)[None])[None]

    def test_rotating_image_and_flow_commutes_with_warping(self):
        import advect as A
        n = 32
        img = self.smooth_disc_image(n)
        flow = A.wind_flow(n, [[0.12, -0.05]])
        disc = A._disc_t(n, "cpu")
        inner = torch.from_numpy((np.hypot(*np.meshgrid(A.pixel_centres(n), A.pixel_centres(n))) < 0.8)
                                 .astype(np.float32))
        for deg, tol in ((90.0, 1e-5), (180.0, 1e-5), (33.0, 0.01)):
            ang = torch.tensor([np.radians(deg)], dtype=torch.float32)
            a = A.rotate(A.warp(img, flow), ang) * disc
            b = A.warp(A.rotate(img, ang) * disc, A.rotate_flow(flow, ang) * disc)
            err = float(((a - b).abs() * inner).max())
            self.assertLess(err, tol, f"rotation by {deg} deg: max difference {err}")
        # Rotation by 90 deg is a pixel permutation: the flow vectors turn with it.
        f90 = A.rotate_flow(flow, torch.tensor([np.pi / 2]))
        np.testing.assert_allclose(f90[0, 0].numpy(), -torch.rot90(flow[0, 1], -1, (0, 1)).numpy(), atol=1e-5)
        # Mirroring (flip x, negate flow x) commutes exactly.
        a = A.mirror(A.warp(img, flow))
        b = A.warp(A.mirror(img), A.mirror_flow(flow))
        self.assertLess(float((a - b).abs().max()), 1e-5)

    def test_uniform_wind_fit_recovers_the_wind(self):
        import advect as A
        n = 32
        w = torch.tensor([[0.08, -0.15]])
        f = A.wind_flow(n, w)
        fit_w, fit = A.fit_uniform_wind(f, A._disc_t(n, "cpu"), n)
        np.testing.assert_allclose(fit_w.numpy(), w.numpy(), atol=2e-3)
        # At the zenith the flow is the layer displacement's angle: atan(|w|) / 90 deg x N / 2.
        z = float(torch.hypot(f[0, 0, 15:17, 15:17], f[0, 1, 15:17, 15:17]).mean())
        self.assertAlmostEqual(z, np.arctan(float(w.norm())) / (np.pi / 2) * n / 2, delta=0.05)

    def test_tiny_model_loss_falls(self):
        import advect as A
        import train_advect as T
        n = 32
        images, disc, flow = drifting_sequence(8, n)
        images = images + 0.04 * np.arange(8)[:, None, None, None] * disc[None, :, :, None]  # clouds brighten
        x = torch.from_numpy(images.astype(np.float32)).permute(0, 3, 1, 2)
        xs = torch.stack([x[0:4], x[1:5], x[2:6]])  # 3 windows of K + 1 = 4 frames
        v = torch.from_numpy(disc.astype(np.float32))[None, None, None].expand(3, 4, 1, n, n)
        f = torch.from_numpy(flow[:3]).permute(0, 3, 1, 2)
        model = A.AdvectResidual((4, 8), kernel=0)
        opt = torch.optim.Adam(model.parameters(), lr=3e-3)
        losses = []
        for _ in range(30):
            loss, _ = T.rollout_loss(model, xs, v, f)
            opt.zero_grad()
            loss.backward()
            opt.step()
            losses.append(float(loss))
        self.assertTrue(all(np.isfinite(losses)))
        self.assertLess(np.mean(losses[-3:]), 0.5 * np.mean(losses[:3]), f"{losses[0]:.5f} -> {losses[-1]:.5f}")

    def test_untrained_model_is_pure_advection_and_exports(self):
        import advect as A
        import export_advect as X
        n = 32
        img = self.smooth_disc_image(n)
        flow = A.wind_flow(n, [[0.1, 0.05]])
        for kernel in (0, 3):
            model = A.AdvectResidual((4, 8, 8), kernel=kernel).eval()
            x = A.network_input(img, flow)
            y = model(x)
            if kernel == 0:
                self.assertLess(float((y - x[:, 0:3]).abs().max()), 1e-6)
            else:  # starts near (not at) the centre tap: a slight 3 x 3 blur of W
                self.assertLess(float((y - x[:, 0:3]).abs().mean()), 0.01)
            path = os.path.join(self.tmp, f"k{kernel}.onnx")
            ops = X.export_onnx(model, n, path)
            self.assertIn("Resize", ops)
            self.assertNotIn("GridSample", ops)
            import onnx
            m = onnx.load(path)
            dims = [d.dim_value for d in m.graph.input[0].type.tensor_type.shape.dim]
            self.assertEqual(dims, [1, 8, n, n])

    def test_export_of_a_compensated_checkpoint_says_so(self):
        """A checkpoint trained on the compensated warp exports a model.json that tells the C++ side
        ("base": "compensated"; without it the sky's gradient moved with the clouds), and a
        reference pair built with the background."""
        import advect as A
        import export_advect as X
        import train_advect as TA
        n = 32
        write_dataset(self.tmp, frames=24, n=n)
        seq = os.path.join(self.tmp, "synthetic")
        images = np.load(os.path.join(seq, "images.npy"))
        yy = np.linspace(0.3, 0.6, n, dtype=np.float32)[None, :, None, None]
        np.save(os.path.join(seq, "background.npy"), np.broadcast_to(yy, images.shape).astype(np.float32))
        with open(os.path.join(self.tmp, "split.json")) as f:
            split = json.load(f)
        split["synthetic"].update({"fit": [0, 16], "val": [16, 19]})
        with open(os.path.join(self.tmp, "split.json"), "w") as f:
            json.dump(split, f)
        run = os.path.join(self.tmp, "run")
        TA.main(["--data", self.tmp, "--widths", "4,8", "--compensated", "--smooth", "--gate", "--epochs", "1",
                 "--steps-per-epoch", "2", "--batch", "2", "--unroll", "1", "--eval-every", "5", "--out", run])
        out = os.path.join(self.tmp, "model")
        X.main(["--checkpoint", os.path.join(run, "final.pt"), "--data", self.tmp, "--out", out])
        with open(os.path.join(out, "model.json")) as f:
            info = json.load(f)
        self.assertEqual(info["base"], "compensated")
        self.assertIn("smoothed", info["previous_frame_flow"])
        image = torch.from_numpy(np.load(os.path.join(out, "reference_image.npy")))
        flow = torch.from_numpy(np.load(os.path.join(out, "reference_flow.npy")))
        background = torch.from_numpy(np.load(os.path.join(out, "reference_background.npy")))
        x = np.load(os.path.join(out, "reference_input.npy"))
        expected = A.network_input(image, flow, A.compensation(background, flow)).numpy()
        self.assertLess(float(np.abs(x - expected).max()), 1e-6)
        self.assertGreater(float(np.abs(x - A.network_input(image, flow).numpy()).max()), 1e-3)


    def advect_dataset(self, background=True):
        """A tiny data set of build_dataset_v2.py's form (fit / val parts; background.npy optional)."""
        write_dataset(self.tmp, frames=24, n=32)
        seq = os.path.join(self.tmp, "synthetic")
        if background:
            images = np.load(os.path.join(seq, "images.npy"))
            np.save(os.path.join(seq, "background.npy"), np.full_like(images, 0.4))
        with open(os.path.join(self.tmp, "split.json")) as f:
            split = json.load(f)
        split["synthetic"].update({"fit": [0, 16], "val": [16, 19]})
        with open(os.path.join(self.tmp, "split.json"), "w") as f:
            json.dump(split, f)

    TINY = ["--widths", "4,8", "--epochs", "1", "--steps-per-epoch", "2", "--batch", "2", "--unroll", "1",
            "--eval-every", "5", "--threads", "1"]

    def test_compensated_training_without_backgrounds_is_refused_before_it_starts(self):
        """It trained as if the background were zero (the same weights as without --compensated) and
        export then labelled the model compensated (a researcher's audit)."""
        import train_advect as TA
        from script_errors import ScriptError
        self.advect_dataset(background=False)
        run = os.path.join(self.tmp, "run")
        with self.assertRaises(ScriptError) as e:
            TA.train(TA.parser().parse_args(["--data", self.tmp, "--compensated", "--out", run] + self.TINY))
        self.assertIn("background.npy", str(e.exception))
        self.assertFalse(os.path.exists(os.path.join(run, "checkpoint.pt")))

    def test_resume_refuses_other_options_and_a_missing_checkpoint_and_allows_more_epochs(self):
        """--resume went on silently under another seed, learning rate or warp (the checkpoint's args
        then said the new ones), died with a traceback for other widths, and started from scratch
        when there was no checkpoint."""
        import train_advect as TA
        from script_errors import ScriptError
        self.advect_dataset()
        run = os.path.join(self.tmp, "run")
        TA.main(["--data", self.tmp, "--out", run] + self.TINY)
        for changed in (["--seed", "7"], ["--widths", "4,8,8"], ["--compensated"]):
            args = ["--data", self.tmp, "--out", run, "--resume"] + self.TINY + changed
            with self.assertRaises(ScriptError) as e:
                TA.train(TA.parser().parse_args(args))
            self.assertEqual(e.exception.code, 2)
            self.assertIn(changed[0], str(e.exception))
        with self.assertRaises(ScriptError) as e:
            TA.train(TA.parser().parse_args(["--data", self.tmp, "--out", os.path.join(self.tmp, "none"),
                                             "--resume"] + self.TINY))
        self.assertIn("no checkpoint", str(e.exception))
        more = [a if a != "1" or self.TINY[i - 1] != "--epochs" else "2" for i, a in enumerate(self.TINY)]
        TA.main(["--data", self.tmp, "--out", run, "--resume"] + more)  # more epochs: allowed
        self.assertTrue(os.path.exists(os.path.join(run, "final.pt")))

    def test_resume_compares_the_data_folder_itself(self):
        """A relative --data was compared as written: the same folder from another working folder was
        refused, another folder of the same name accepted (a review)."""
        import train_advect as TA
        from script_errors import ScriptError
        self.advect_dataset()
        run = os.path.join(self.tmp, "run")
        other = tempfile.mkdtemp()
        cwd = os.getcwd()
        try:
            os.chdir(os.path.dirname(self.tmp))
            TA.main(["--data", os.path.basename(self.tmp), "--out", run] + self.TINY)
            os.chdir(self.tmp)
            more = [a if a != "1" or self.TINY[i - 1] != "--epochs" else "2" for i, a in enumerate(self.TINY)]
            TA.main(["--data", ".", "--out", run, "--resume"] + more)  # the same folder, spelt otherwise
            shutil.copytree(self.tmp, os.path.join(other, os.path.basename(self.tmp)), ignore=shutil.ignore_patterns("run"))
            os.chdir(other)
            with self.assertRaises(ScriptError) as e:
                TA.train(TA.parser().parse_args(["--data", os.path.basename(self.tmp), "--out", run, "--resume"] + more))
            self.assertIn("--data", str(e.exception))
        finally:
            os.chdir(cwd)
            shutil.rmtree(other, ignore_errors=True)

    def test_foreign_and_truncated_checkpoints_are_refused_in_one_line(self):
        import train_advect as TA
        from script_errors import ScriptError
        bad = os.path.join(self.tmp, "cut.pt")
        with open(bad, "wb") as f:
            f.write(b"PK\x03\x04 not a whole zip")
        with self.assertRaises(ScriptError) as e:
            TA.load_model(bad)
        self.assertIn("cut.pt", str(e.exception))
        paper = os.path.join(self.tmp, "paper.pt")
        torch.save({"model": {}, "args": {"flow_widths": "4,8"}}, paper)
        with self.assertRaises(ScriptError) as e:
            TA.load_model(paper)
        self.assertIn("FlowNet", str(e.exception))

if __name__ == "__main__":
    unittest.main()
