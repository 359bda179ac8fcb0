"""modskill: a Python client of the modskill humanoid simulation server.

The server simulates batches of MuJoCo humanoids tracking motion clips; this package talks to
it over gRPC (``modskill.v1.Simulation``, see proto/modskill/v1/modskill.proto) and returns
numpy arrays.

    import modskill
    client = modskill.Client("127.0.0.1:50051", token_file="token.txt")
    spec = client.describe()                    # sizes, body parts, joint names
    with client.session(num_envs=16) as s:      # a batch of envs on the server
        result = s.step(np.zeros((16, spec.action_size), np.float32))
        result.obs, result.reward, result.done  # numpy arrays, row i = env i
    rollouts = client.rollout("policy.pt", clips=["deepmimic_walk"], frames=True)
    modskill.viewer.write_html("walk.html", spec, rollouts)   # a page: policy beside reference

    with modskill.VectorEnv("127.0.0.1:50051", num_envs=16) as env:   # Gymnasium-style
        obs, info = env.reset(seed=0)
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

Main names:
  Client       connection; describe, motions, stats, add_motions, rollout, report_failures, session
  Session      an open simulation stream: spec, clip_names, initial, step(actions), part_obs
  VectorEnv    a session with Gymnasium's vector-env interface (reset, step, spaces; Box)
  EnvSpec, BodyPart, BodyGeometry, StepResult, ClipRollout   the results
  ServerError  a failed call (``.code``: grpc.StatusCode, ``.message``: the server's message)
  ConnectError no server at the address (a ServerError with code UNAVAILABLE)
  viewer       write_html: a self-contained HTML page of rollouts (three.js inlined)

The generated protocol modules are ``modskill.v1.modskill_pb2`` and ``modskill_pb2_grpc``.
"""

from .client import Client, Session, read_token_file
from .errors import ConnectError, ServerError
from .types import BodyGeometry, BodyPart, ClipRollout, EnvSpec, FamilyQuery, PhysicsSettings, StepResult
from . import viewer
from .vector_env import Box, VectorEnv

__version__ = "0.1.0"

__all__ = [
    "Client",
    "Session",
    "VectorEnv",
    "Box",
    "ServerError",
    "ConnectError",
    "EnvSpec",
    "BodyPart",
    "BodyGeometry",
    "PhysicsSettings",
    "StepResult",
    "ClipRollout",
    "FamilyQuery",
    "part_obs",
    "read_token_file",
    "viewer",
]


def part_obs(spec: EnvSpec, obs, part: str):
    """The columns of ``obs`` ([..., obs_size]) that belong to body part ``part`` of ``spec``."""
    return spec.part_obs(obs, part)
