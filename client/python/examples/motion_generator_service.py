#!/usr/bin/env python3
"""An example MotionGenerator service: answers a server's Generate calls with variants of the
parent clip made by a smooth, bounded rotation displacement of the requested bodies.

A server started with ``--generator host:port`` calls this for each failed clip. A real
deployment would run a text-to-motion model (MDM, T2M-GPT, ...) in ``Generate`` instead, conditioned
on ``request.text`` and constrained to ``request.part_mask``; this example only shows the contract:
same skeleton, frame count, fps and root, unit quaternions, unmasked bodies left alone.

    /usr/bin/python3 client/python/examples/motion_generator_service.py --port 50061
"""

import argparse
import signal
import sys
import threading
from concurrent import futures

from _path import ensure_modskill_importable

ensure_modskill_importable()
import grpc  # noqa: E402
import numpy as np  # noqa: E402

from modskill import tensors  # noqa: E402
from modskill.v1 import modskill_pb2 as pb  # noqa: E402
from modskill.v1 import modskill_pb2_grpc as pb_grpc  # noqa: E402

MAX_COUNT = 64
MAX_AMPLITUDE = 0.15  # rad: small enough that the variant stays trackable
MAX_MESSAGE_BYTES = 64 << 20  # 64 clips of a long parent exceed gRPC's default 4 MiB


def amplitude_for(text: str) -> float:
    """Where a text model would plug in: here fast motions get a smaller displacement, since a
    perturbed run falls more easily than a perturbed walk. MDM etc. would read the text itself."""
    words = text.lower()
    return MAX_AMPLITUDE / 2 if ("fast" in words or "run" in words) else MAX_AMPLITUDE


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of (..., 4) wxyz quaternions."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz,
                     aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw], axis=-1)


def displace(local_rot: np.ndarray, bodies: np.ndarray, fps: float, amplitude: float,
             rng: np.random.Generator) -> np.ndarray:
    """q' = q * exp(d(t)) on each listed body, d(t) = axis * A sin(2 pi f t / T + phase)."""
    frames = local_rot.shape[0]
    t = np.arange(frames) / fps
    duration = frames / fps
    out = local_rot.copy()  # unlisted bodies stay bit-identical to the parent
    for body in bodies:
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        amp = rng.uniform(0.5, 1.0) * amplitude
        cycles = rng.uniform(0.25, 1.0)  # low frequency: at most one period over the clip
        angle = amp * np.sin(2 * np.pi * cycles * t / duration + rng.uniform(0, 2 * np.pi))
        delta = np.concatenate([np.cos(angle / 2)[:, None], np.sin(angle / 2)[:, None] * axis], axis=1)
        q = quat_mul(local_rot[:, body].astype(np.float64), delta)
        out[:, body] = (q / np.linalg.norm(q, axis=1, keepdims=True)).astype(np.float32)
    return out


class Generator(pb_grpc.MotionGeneratorServicer):
    def __init__(self, name: str, delay_s: float, stopping: threading.Event):
        self.name = name
        self.delay_s = delay_s
        self.stopping = stopping

    def _parse(self, request, context):
        """Returns (root_pos, local_rot, mask) or aborts with INVALID_ARGUMENT naming the field."""
        def fail(message):
            context.abort(grpc.StatusCode.INVALID_ARGUMENT, message)  # raises

        if not 1 <= request.count <= MAX_COUNT:
            fail(f"count: {request.count}, expected 1 .. {MAX_COUNT}")
        parent = request.parent
        if not parent.fps > 0:
            fail(f"parent.fps: {parent.fps}, expected > 0")
        for field in ("root_pos", "local_rot"):
            if getattr(parent, field).dtype != pb.FLOAT32:
                fail(f"parent.{field}.dtype: expected FLOAT32")
        try:
            root = tensors.decode(parent.root_pos, "parent.root_pos")
            rot = tensors.decode(parent.local_rot, "parent.local_rot")
        except ValueError as error:
            fail(str(error))
        if root.ndim != 2 or root.shape[1] != 3 or root.shape[0] < 1:
            fail(f"parent.root_pos.shape: {list(root.shape)}, expected [frames, 3]")
        if rot.ndim != 3 or rot.shape[0] != root.shape[0] or rot.shape[2] != 4 or rot.shape[1] < 1:
            fail(f"parent.local_rot.shape: {list(rot.shape)}, expected [{root.shape[0]}, bodies, 4]")
        if not (np.isfinite(root).all() and np.isfinite(rot).all()):
            fail("parent: root_pos or local_rot holds non-finite values")
        bodies = rot.shape[1]
        if parent.body_names and len(parent.body_names) != bodies:
            fail(f"parent.body_names: {len(parent.body_names)} names for {bodies} bodies")
        if request.part_mask and len(request.part_mask) != bodies:
            fail(f"part_mask: {len(request.part_mask)} entries for {bodies} bodies")
        mask = np.array(request.part_mask, bool) if request.part_mask else np.ones(bodies, bool)
        if not mask.any():
            fail("part_mask: selects no body")
        return root, rot, mask

    def Generate(self, request, context):
        root, rot, mask = self._parse(request, context)
        if self.delay_s > 0:
            # Lets tests exercise the caller's deadline; a shutdown cuts the wait short.
            self.stopping.wait(self.delay_s)
        mask[0] = False  # body 0 is the pelvis's world rotation: rotating it would change the heading
        bodies = np.flatnonzero(mask)
        amplitude = amplitude_for(request.text)
        parent = request.parent
        response = pb.GenerateMotionResponse(generator=self.name)
        for k in range(request.count):
            rng = np.random.default_rng(request.seed + k)
            clip = response.clips.add(name=f"{parent.name}~py~{k}", label=request.text,
                                      humanml3d_id=request.humanml3d_id, fps=parent.fps,
                                      body_names=parent.body_names)
            clip.root_pos.CopyFrom(parent.root_pos)  # the root is never changed
            tensors.encode(displace(rot, bodies, parent.fps, amplitude, rng), clip.local_rot)
        return response


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--port", type=int, default=50061, help="0: any free port")
    parser.add_argument("--bind", default="127.0.0.1", help="address to listen on")
    parser.add_argument("--delay_s", type=float, default=0.0, help="sleep before each answer")
    parser.add_argument("--generator_name", default="python_example", help="provenance in each reply")
    args = parser.parse_args()

    stop = threading.Event()
    server = grpc.server(futures.ThreadPoolExecutor(max_workers=4),
                         options=[("grpc.max_send_message_length", MAX_MESSAGE_BYTES),
                                  ("grpc.max_receive_message_length", MAX_MESSAGE_BYTES)])
    pb_grpc.add_MotionGeneratorServicer_to_server(Generator(args.generator_name, args.delay_s, stop), server)
    host = f"[{args.bind}]" if ":" in args.bind else args.bind
    try:
        port = server.add_insecure_port(f"{host}:{args.port}")
    except RuntimeError as error:  # newer grpcio raises instead of returning 0
        sys.exit(f"cannot listen on {host}:{args.port}: {error}")
    if port == 0:
        sys.exit(f"cannot listen on {host}:{args.port}")
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    server.start()
    print(f"motion generator listening on {host}:{port}", flush=True)
    while not stop.wait(0.5):  # a timed wait keeps the main thread responsive to signals
        pass
    server.stop(grace=1).wait()


if __name__ == "__main__":
    main()
