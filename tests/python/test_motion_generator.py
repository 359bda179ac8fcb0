"""Tests of the example MotionGenerator service (client/python/examples/motion_generator_service.py).

Each test class starts the service as a subprocess on a free port and calls it with a plain gRPC
stub; no modskill server is needed. Run with PYTHONPATH=client/python:

    PYTHONPATH=client/python /usr/bin/python3 -m unittest tests/python/test_motion_generator.py -v
"""

import os
import queue
import socket
import subprocess
import threading
import unittest

import grpc
import numpy as np

from modskill import tensors
from modskill.v1 import modskill_pb2 as pb
from modskill.v1 import modskill_pb2_grpc as pb_grpc

REPO_DIR = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SERVICE = os.path.join(REPO_DIR, "client", "python", "examples", "motion_generator_service.py")
PYTHON = "/usr/bin/python3"
FRAMES, BODIES, FPS = 40, 24, 30.0
MAX_AMPLITUDE = 0.15


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_service(*args):
    """Starts the service; returns (process, address) once it printed its listening line."""
    port = free_port()
    process = subprocess.Popen([PYTHON, SERVICE, "--port", str(port), *args], stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, env=dict(os.environ, PYTHONUNBUFFERED="1"))
    lines = queue.Queue()
    # readline blocks; a reader thread lets the wait time out when the service never starts.
    process.reader = threading.Thread(
        target=lambda: [lines.put(line) for line in iter(process.stdout.readline, b"")], daemon=True)
    process.reader.start()
    output = []
    try:
        while True:
            line = lines.get(timeout=15).decode("utf-8", "replace")
            output.append(line)
            if "motion generator listening on" in line:
                return process, f"127.0.0.1:{port}"
    except queue.Empty:
        pass
    stop_service(process)
    raise RuntimeError("the motion generator did not start:\n" + "".join(output))


def stop_service(process) -> int:
    """Sends SIGTERM (SIGKILL after 10 s); returns the exit status."""
    process.terminate()
    try:
        returncode = process.wait(timeout=10)
    except subprocess.TimeoutExpired:
        process.kill()
        returncode = process.wait()
    process.reader.join(timeout=5)  # the pipe reaches EOF once the process is gone
    process.stdout.close()
    return returncode


def make_parent():
    """A 40-frame walk-like clip: small random local rotations, root moving forward along x."""
    rng = np.random.default_rng(7)
    axes = rng.normal(size=(FRAMES, BODIES, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    angle = 0.2 * np.sin(np.linspace(0, 2 * np.pi, FRAMES))[:, None, None] * rng.uniform(0.2, 1, (1, BODIES, 1))
    rot = np.concatenate([np.cos(angle / 2), np.sin(angle / 2) * axes], axis=-1).astype(np.float32)
    t = np.arange(FRAMES) / FPS
    root = np.stack([1.2 * t, np.zeros_like(t), np.full_like(t, 0.9)], axis=1).astype(np.float32)
    parent = pb.MotionData(name="walk01", label="a person walks forward", fps=FPS,
                           body_names=[f"body{i}" for i in range(BODIES)])
    tensors.encode(root, parent.root_pos)
    tensors.encode(rot, parent.local_rot)
    return parent, root, rot


def relative_angle(a, b):
    """Rotation angle (rad) between unit quaternions, per element."""
    dot = np.clip(np.abs(np.sum(a.astype(np.float64) * b, axis=-1)), 0.0, 1.0)
    return 2 * np.arccos(dot)


class MotionGeneratorTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.process, address = start_service("--generator_name", "test_gen")
        cls.channel = grpc.insecure_channel(address)
        cls.stub = pb_grpc.MotionGeneratorStub(cls.channel)
        cls.parent, cls.root, cls.rot = make_parent()

    @classmethod
    def tearDownClass(cls):
        cls.channel.close()
        cls.returncode = stop_service(cls.process)

    def generate(self, **fields):
        request = pb.GenerateMotionRequest(text=fields.pop("text", "a person walks forward"),
                                           parent=fields.pop("parent", self.parent),
                                           count=fields.pop("count", 3), seed=fields.pop("seed", 11), **fields)
        return self.stub.Generate(request, timeout=10)

    def decoded(self, clip):
        return tensors.decode(clip.root_pos, "root_pos"), tensors.decode(clip.local_rot, "local_rot")

    def test_whole_body(self):
        for mask in ([], [True] * BODIES):
            response = self.generate(part_mask=mask, count=3)
            self.assertEqual(response.generator, "test_gen")
            self.assertEqual(len(response.clips), 3)
            for k, clip in enumerate(response.clips):
                self.assertEqual(clip.name, f"walk01~py~{k}")
                self.assertEqual(clip.label, "a person walks forward")
                self.assertEqual(clip.fps, FPS)
                self.assertEqual(list(clip.body_names), list(self.parent.body_names))
                root, rot = self.decoded(clip)
                self.assertEqual(rot.shape, (FRAMES, BODIES, 4))
                self.assertEqual(rot.dtype, np.float32)
                np.testing.assert_allclose(np.linalg.norm(rot, axis=-1), 1.0, atol=1e-5)
                np.testing.assert_array_equal(root, self.root)
                np.testing.assert_array_equal(rot[:, 0], self.rot[:, 0])  # the heading stays
                angles = relative_angle(rot[:, 1:], self.rot[:, 1:])
                self.assertTrue((angles.max(axis=0) > 1e-3).all(), "every non-root body changes")
                self.assertLessEqual(angles.max(), MAX_AMPLITUDE + 1e-3)

    def test_part_level_leaves_other_bodies(self):
        mask = np.zeros(BODIES, bool)
        mask[[0, 1, 4, 7]] = True  # the pelvis is in the mask but must still not rotate
        response = self.generate(part_mask=mask.tolist(), part="L_Leg", count=2)
        self.assertEqual(len(response.clips), 2)
        for clip in response.clips:
            root, rot = self.decoded(clip)
            np.testing.assert_array_equal(root, self.root)
            np.testing.assert_array_equal(rot[:, ~mask], self.rot[:, ~mask])
            np.testing.assert_array_equal(rot[:, 0], self.rot[:, 0])
            self.assertTrue((relative_angle(rot[:, [1, 4, 7]], self.rot[:, [1, 4, 7]]).max(axis=0) > 1e-3).all())

    def test_seed_determinism(self):
        first = self.generate(seed=5, count=2)
        again = self.generate(seed=5, count=2)
        other = self.generate(seed=6, count=2)
        self.assertEqual(first.SerializeToString(deterministic=True), again.SerializeToString(deterministic=True))
        self.assertNotEqual(first.clips[0].local_rot.data, other.clips[0].local_rot.data)
        self.assertNotEqual(first.clips[0].local_rot.data, first.clips[1].local_rot.data)

    def test_text_hook(self):
        response = self.generate(text="a person runs fast", count=4)
        _, rot = self.decoded(response.clips[0])
        self.assertLessEqual(relative_angle(rot, self.rot).max(), MAX_AMPLITUDE / 2 + 1e-3)

    def test_invalid_arguments(self):
        parent, root, rot = make_parent()
        flat = pb.MotionData()
        flat.CopyFrom(parent)
        tensors.encode(rot[..., :3].copy(), flat.local_rot)
        short_root = pb.MotionData()
        short_root.CopyFrom(parent)
        tensors.encode(root[:10], short_root.root_pos)
        ints = pb.MotionData()
        ints.CopyFrom(parent)
        tensors.encode(np.zeros((FRAMES, BODIES, 4), np.int32), ints.local_rot)
        no_fps = pb.MotionData()
        no_fps.CopyFrom(parent)
        no_fps.fps = 0
        cases = [
            (dict(count=0), "count"),
            (dict(count=65), "count"),
            (dict(parent=flat), "parent.local_rot"),
            (dict(parent=short_root), "parent.local_rot"),
            (dict(parent=ints), "parent.local_rot"),
            (dict(parent=no_fps), "parent.fps"),
            (dict(part_mask=[True] * (BODIES - 1)), "part_mask"),
            (dict(part_mask=[False] * BODIES), "part_mask"),
        ]
        for fields, field in cases:
            with self.subTest(field=field, fields=list(fields)):
                with self.assertRaises(grpc.RpcError) as caught:
                    self.generate(**fields)
                self.assertEqual(caught.exception.code(), grpc.StatusCode.INVALID_ARGUMENT)
                self.assertIn(field, caught.exception.details())


class DelayTest(unittest.TestCase):
    """--delay_s makes a caller's deadline expire; SIGTERM ends the service cleanly."""

    def test_delay_and_sigterm(self):
        process, address = start_service("--delay_s", "3")
        try:
            with grpc.insecure_channel(address) as channel:
                stub = pb_grpc.MotionGeneratorStub(channel)
                parent, _, _ = make_parent()
                with self.assertRaises(grpc.RpcError) as caught:
                    stub.Generate(pb.GenerateMotionRequest(parent=parent, count=1), timeout=0.5)
                self.assertEqual(caught.exception.code(), grpc.StatusCode.DEADLINE_EXCEEDED)
        finally:
            returncode = stop_service(process)
        self.assertEqual(returncode, 0)


if __name__ == "__main__":
    unittest.main()


SERVER_BINARY = os.environ.get("MODSKILL_SERVER_BINARY", "")


@unittest.skipUnless(SERVER_BINARY and os.path.exists(SERVER_BINARY), "MODSKILL_SERVER_BINARY is not set")
class ServerWithExampleGeneratorTest(unittest.TestCase):
    """modskill-server --generator <the example service>: failed clips get variants from Python."""

    def setUp(self):
        self.generator, self.generator_address = start_service("--generator_name", "python_example")
        port = free_port()
        self.server = subprocess.Popen(
            [SERVER_BINARY, f"--port={port}", "--threads=1", f"--generator={self.generator_address}",
             "--failures_per_round=4", "--variants_per_failure=2", "--generator_timeout_ms=5000"],
            stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
        self.address = f"127.0.0.1:{port}"

    def tearDown(self):
        self.server.terminate()
        try:
            self.server.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.server.kill()
            self.server.wait()
        stop_service(self.generator)

    def connect(self):
        import modskill
        for _ in range(40):
            try:
                return modskill.Client(self.address, timeout=0.25)
            except modskill.ConnectError:
                self.assertIsNone(self.server.poll(), "the server exited")
        self.fail("the server did not start")

    def test_failed_clip_gets_variants_from_the_python_generator(self):
        import time
        with self.connect() as client, client.session(num_envs=8, seed=3) as session:
            parts = [part.name for part in session.spec.parts]
            errors = [0.8 if name == "L_Arm" else 0.1 for name in parts]
            client.report_failures(session.session_id,
                                   [{"clip": "deepmimic_walk", "part_errors": errors}] * 4)
            zeros = np.zeros((8, session.spec.action_size), np.float32)
            deadline = time.monotonic() + 20
            while len(session.clip_provenance) < 2 and time.monotonic() < deadline:
                session.step(zeros)
            self.assertEqual(len(session.clip_provenance), 2, "no generated clips were announced")
            for clip_id, provenance in session.clip_provenance.items():
                self.assertEqual(provenance["generator"], "python_example")
                self.assertEqual(provenance["parent"], "deepmimic_walk")
                self.assertEqual(provenance["part"], "L_Arm")
                self.assertTrue(session.clip_names[clip_id].startswith("deepmimic_walk~L_Arm~"))
            stats = client.stats()
            [mine] = [s for s in stats["sessions"] if s["session_id"] == session.session_id]
            generation = mine["generation"]
            self.assertEqual(int(generation["generated"]), 2)
            self.assertEqual(int(generation.get("generator_errors", 0)), 0)
            generated = [c for c in mine["clips"] if (c.get("provenance") or {}).get("parent")]
            self.assertEqual(len(generated), 2)
