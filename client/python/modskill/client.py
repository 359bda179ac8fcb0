"""The modskill client: one method per RPC of ``modskill.v1.Simulation``, returning numpy arrays.

Example::

    import numpy as np
    import modskill

    with modskill.Client("127.0.0.1:50051") as client:
        spec = client.describe()
        with client.session(num_envs=64, seed=1) as session:
            result = session.initial
            for _ in range(100):
                actions = np.zeros((session.num_envs, spec.action_size), np.float32)
                result = session.step(actions)
            legs = session.part_obs(result.obs, "L_Leg")

Every failed call raises :class:`modskill.ServerError` with the gRPC status code and the
server's message (which names the offending field); bad arguments caught before sending raise
``ValueError``.
"""

from __future__ import annotations

import os
import queue
import threading
import weakref
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import grpc
import numpy as np

from . import tensors
from .errors import ConnectError, ServerError
from .types import ClipRollout, EnvSpec, FamilyQuery, StepResult, message_to_dict
from .v1 import modskill_pb2 as pb
from .v1 import modskill_pb2_grpc as pb_grpc

__all__ = ["Client", "Session", "read_token_file"]

PathLike = Union[str, "os.PathLike[str]"]

_TERMINATION = {"training": pb.TRAINING, "evaluation": pb.EVALUATION, "none": pb.NONE}
_AMP_OBS = {"full": pb.FULL, "newest": pb.NEWEST, "omit": pb.OMIT}
_ACTION_MODE = {"absolute": pb.ABSOLUTE, "residual": pb.RESIDUAL}
_TERMINATION_BODIES = {"all": pb.ALL, "no_feet": pb.NO_FEET}


def _enum(value: Union[str, int], table: Mapping[str, int], what: str) -> int:
    if isinstance(value, str):
        key = value.strip().lower()
        if key not in table:
            raise ValueError(f"{what}: {value!r} is not one of {', '.join(table)}")
        return table[key]
    if int(value) not in table.values():
        raise ValueError(f"{what}: {value!r} is not one of {', '.join(table)}")
    return int(value)


def read_token_file(path: PathLike) -> str:
    """Reads a bearer token file (surrounding whitespace stripped); ValueError if it is empty."""
    with open(path, "r", encoding="utf-8") as f:
        token = f.read().strip()
    if not token:
        raise ValueError(f"token_file: {os.fspath(path)} is empty")
    return token


def _stack_poses(clip: str, rows: Sequence[pb.RolloutFrame], name: str, width: int,
                 num_bodies: int) -> Optional[np.ndarray]:
    """``RolloutFrame.<name>`` of every row as float32 [T, num_bodies, width]; None when a row
    lacks it (rotations from a server older than the viewer)."""
    poses = []
    for t, row in enumerate(rows):
        pose = tensors.decode_field(row, name)
        if pose is None:
            return None
        if pose.dtype != np.float32 or pose.shape != (num_bodies, width):
            raise ValueError(f"rollout of clip {clip!r}: frame row {t}: {name} is {pose.dtype} "
                             f"{list(pose.shape)}, expected float32 [{num_bodies}, {width}]")
        poses.append(pose)
    return np.stack(poses) if poses else np.zeros((0, num_bodies, width), np.float32)


def _set_checkpoint(request, rpc: str, checkpoint: Optional[PathLike], checkpoint_bytes: Optional[bytes],
                    server_checkpoint: Optional[str]) -> None:
    """Sets the checkpoint oneof of a Rollout or QueryFamily request from exactly one source: a
    local file (its bytes are uploaded), the archive's bytes, or a path the server reads."""
    given = [x is not None for x in (checkpoint, checkpoint_bytes, server_checkpoint)]
    if sum(given) != 1:
        raise ValueError(f"{rpc}: pass exactly one of checkpoint, checkpoint_bytes, server_checkpoint")
    if checkpoint is not None:
        with open(checkpoint, "rb") as f:
            request.checkpoint_bytes = f.read()
    elif checkpoint_bytes is not None:
        request.checkpoint_bytes = bytes(checkpoint_bytes)
    else:
        request.checkpoint_path = server_checkpoint


def _set_frames(result: ClipRollout, rows: Sequence[pb.RolloutFrame]) -> None:
    """Fills the per-row fields of ``result`` from its clip's streamed frames."""
    shape = rows[0].sim_body_pos.shape if rows else []
    num_bodies = int(shape[0]) if shape else len(result.body_error_mm)
    result.frames = np.array([row.frame for row in rows], dtype=np.int32)
    for name in ("sim_body_pos", "ref_body_pos"):
        positions = _stack_poses(result.clip, rows, name, 3, num_bodies)
        if positions is None:
            raise ValueError(f"rollout of clip {result.clip!r}: a frame has no {name}")
        setattr(result, name, positions)
    result.sim_body_rot = _stack_poses(result.clip, rows, "sim_body_rot", 4, num_bodies)
    result.ref_body_rot = _stack_poses(result.clip, rows, "ref_body_rot", 4, num_bodies)
    result.body_error_m = np.array([row.mean_body_error_m for row in rows], dtype=np.float32)
    result.done = np.array([row.done for row in rows], dtype=np.bool_)
    result.terminated = np.array([row.terminated for row in rows], dtype=np.bool_)
    z_rows = [tensors.decode_field(row, "skill_z") for row in rows]
    shapes = {z.shape for z in z_rows if z is not None and z.size > 0}
    if len(shapes) == 1:
        (shape,) = shapes
        result.skill_z = np.stack([z if z is not None and z.size > 0 else np.full(shape, np.nan, np.float32)
                                   for z in z_rows]).astype(np.float32)


class Client:
    """A connection to a modskill simulation server.

    Args:
      server: ``host:port`` of the server.
      token: bearer token, sent as ``authorization: Bearer <token>`` with every call.
      token_file: or a file holding the token (exclusive with ``token``).
      tls_ca: PEM file of root certificates: connect with TLS (the server runs with
        ``--tls_cert``/``--tls_key``). Without it the channel is plaintext.
      tls_server_name: overrides the host name checked in the server certificate.
      max_message_mb: largest message sent or received, MiB (match the server's
        ``--max_message_mb`` for big batches).
      timeout: seconds to wait for the server at construction, and the deadline of every unary
        call (``describe``, ``motions``, ``stats``, ``add_motions``, ``report_failures``).
        Sessions and rollouts have no deadline.

    Raises:
      ConnectError: no server answered within ``timeout`` seconds.

    The client is a context manager; ``close()`` ends its open sessions and the channel.
    """

    def __init__(self, server: str = "127.0.0.1:50051", token: Optional[str] = None,
                 token_file: Optional[PathLike] = None, tls_ca: Optional[PathLike] = None,
                 max_message_mb: int = 512, timeout: float = 10.0, tls_server_name: Optional[str] = None):
        if token is not None and token_file is not None:
            raise ValueError("token and token_file: pass at most one")
        if token_file is not None:
            token = read_token_file(token_file)
        if max_message_mb < 1:
            raise ValueError(f"max_message_mb: {max_message_mb} must be >= 1")
        self.server = server
        self.timeout = timeout
        self._metadata = (("authorization", f"Bearer {token}"),) if token else ()
        max_bytes = min(int(max_message_mb) << 20, 2**31 - 1)
        options = [("grpc.max_send_message_length", max_bytes), ("grpc.max_receive_message_length", max_bytes),
                   # Pings every 10 s, 20 s to answer (the C++ client's): a server behind a cut
                   # link ends a session's step with UNAVAILABLE within ~30 s instead of waiting
                   # out TCP (~15 min). The server permits a ping a second.
                   ("grpc.keepalive_time_ms", 10000), ("grpc.keepalive_timeout_ms", 20000),
                   ("grpc.keepalive_permit_without_calls", 1), ("grpc.http2.max_pings_without_data", 0)]
        if tls_ca is not None:
            with open(tls_ca, "rb") as f:
                credentials = grpc.ssl_channel_credentials(root_certificates=f.read())
            if tls_server_name:
                options.append(("grpc.ssl_target_name_override", tls_server_name))
            self._channel = grpc.secure_channel(server, credentials, options=options)
        else:
            self._channel = grpc.insecure_channel(server, options=options)
        self._sessions: "weakref.WeakSet[Session]" = weakref.WeakSet()
        try:
            grpc.channel_ready_future(self._channel).result(timeout=timeout)
        except grpc.FutureTimeoutError:
            self._channel.close()
            raise ConnectError(grpc.StatusCode.UNAVAILABLE,
                               f"no modskill server answered within {timeout:g} s"
                               f"{' (TLS)' if tls_ca is not None else ''}", server) from None
        self._stub = pb_grpc.SimulationStub(self._channel)

    # -- plumbing ------------------------------------------------------------------------------

    def _unary(self, rpc: str, request, timeout: Optional[float] = None):
        try:
            return getattr(self._stub, rpc)(request, metadata=self._metadata,
                                            timeout=self.timeout if timeout is None else timeout)
        except grpc.RpcError as e:
            raise ServerError.from_rpc_error(e, self.server, rpc) from None

    def close(self) -> None:
        """Closes the open sessions and the channel."""
        for session in list(self._sessions):
            session.close(raise_errors=False)
        self._channel.close()

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"modskill.Client({self.server!r})"

    # -- RPCs ----------------------------------------------------------------------------------

    def describe(self, part_layout: str = "") -> EnvSpec:
        """The env spec of a part layout ('' : the server's default, 5 parts)."""
        return EnvSpec.from_proto(self._unary("Describe", pb.DescribeRequest(part_layout=part_layout)))

    def motions(self) -> List[Dict[str, Any]]:
        """The server's clip library: one dict per clip with name, frames, fps, duration, label,
        humanml3d_id and source."""
        return [message_to_dict(m) for m in self._unary("ListMotions", pb.ListMotionsRequest()).motions]

    def stats(self) -> Dict[str, Any]:
        """Server counters (``ServerStats``) as a dict; ``stats()["sessions"]`` lists the open
        sessions (session_id, peer, num_envs, steps, steps_per_second, ...)."""
        return message_to_dict(self._unary("GetStats", pb.GetStatsRequest()))

    def add_motions(self, paths: Union[PathLike, Sequence[PathLike]], names: Optional[Sequence[str]] = None,
                    labels: Optional[Sequence[str]] = None, timeout: Optional[float] = None) -> List[Dict[str, Any]]:
        """Uploads clip files (.npz .bvh .txt .msclip, picked by extension) to the library.

        They are available to sessions opened afterwards. ``names`` and ``labels`` optionally
        give each file's clip name and text label. Returns the added clips as dicts (like
        ``motions()``).
        """
        if isinstance(paths, (str, os.PathLike)):
            paths = [paths]
        paths = list(paths)
        for what, values in (("names", names), ("labels", labels)):
            if values is not None and len(values) != len(paths):
                raise ValueError(f"{what}: {len(values)} values for {len(paths)} paths")
        request = pb.AddMotionsRequest()
        for i, path in enumerate(paths):
            with open(path, "rb") as f:
                data = f.read()
            request.uploads.add(file_name=os.path.basename(os.fspath(path)), data=data,
                                name=names[i] if names else "", label=labels[i] if labels else "")
        return [message_to_dict(m) for m in self._unary("AddMotions", request, timeout).added]

    def report_failures(self, session_id: str, failures: Iterable[Union[Mapping[str, Any], pb.ClipFailure]]
                        ) -> Dict[str, Any]:
        """Reports a session's failed (or, with ``terminated=False``, succeeded) clips to its sampler.

        Each failure is a ``modskill.v1.ClipFailure`` or a dict with ``clip`` and optionally
        ``frame`` (-1: unknown), ``part_errors`` (one mean body error per part, m) and
        ``terminated`` (default True). Returns the sampler state as a dict: session_id, reports
        and ``clips`` (clip, weight, probability, failures, successes, ...).
        """
        request = pb.ReportFailuresRequest(session_id=session_id)
        for i, failure in enumerate(failures):
            if isinstance(failure, pb.ClipFailure):
                request.failures.append(failure)
                continue
            unknown = set(failure) - {"clip", "frame", "part_errors", "terminated"}
            if unknown or "clip" not in failure:
                raise ValueError(f"failures[{i}]: needs 'clip' and takes frame, part_errors, terminated "
                                 f"(got {sorted(failure)})")
            request.failures.add(clip=failure["clip"], frame=int(failure.get("frame", -1)),
                                 part_errors=[float(e) for e in failure.get("part_errors", ())],
                                 terminated=bool(failure.get("terminated", True)))
        return message_to_dict(self._unary("ReportFailures", request))

    def rollout(self, checkpoint: Optional[PathLike] = None, checkpoint_bytes: Optional[bytes] = None,
                clips: Sequence[str] = (), frames: bool = False, *, server_checkpoint: Optional[str] = None,
                termination: Union[str, int] = "evaluation", termination_distance: float = 0.0,
                max_steps_per_clip: int = 0, action_mode: Optional[Union[str, int]] = None,
                timeout: Optional[float] = None, record_skills: bool = False,
                composition: Optional[pb.SkillComposition] = None,
                family_params: Optional[Mapping[str, float]] = None) -> List[ClipRollout]:
        """Runs a TorchScript policy checkpoint on clips and returns one :class:`ClipRollout` per clip.

        Give exactly one of:
          checkpoint: a local checkpoint file; the client reads it and uploads its bytes, so
            this works with remote servers.
          checkpoint_bytes: the archive itself.
          server_checkpoint: a path the *server* reads, in one of its --checkpoint_dir directories.

        Args:
          clips: clip names; empty: every clip of the library.
          frames: also return per-step simulated and reference body poses
            (``ClipRollout.sim_body_pos`` / ``ref_body_pos``, float32 [T, num_bodies, 3];
            ``sim_body_rot`` / ``ref_body_rot``, float32 [T, num_bodies, 4] w x y z), the mean
            body error and the done / terminated flags of each row; ``modskill.viewer.write_html``
            turns them into a page.
          termination: "evaluation" (default: mean body error above 0.5 m), "training" or "none".
          termination_distance: metres; 0: the mode's default.
          max_steps_per_clip: 0: the clip's length.
          action_mode: None runs the policy in the mode recorded in its checkpoint; "absolute" or
            "residual" insists on one (a checkpoint trained in the other is refused).
          timeout: deadline in seconds (default: none).
          record_skills: also return each row's z (``ClipRollout.skill_z``; implies frames).
          composition: a ``SkillComposition`` (``compose`` builds one); clips must then be empty.
          family_params: a motor-skill family's policy (``modskill-learner --family``): its task
            parameters a by name, e.g. ``{"gravity": 6.0}``; the rest run at the middle of their
            trained range. ``ClipRollout.family`` then says what a did (F, apex, flight). A value
            outside the trained range is a ServerError INVALID_ARGUMENT naming it.
        """
        if isinstance(clips, str):
            clips = [clips]
        frames = bool(frames or record_skills)
        request = pb.RolloutRequest(clips=list(clips), stream_frames=frames, record_skills=bool(record_skills),
                                    termination=_enum(termination, _TERMINATION, "termination"),
                                    termination_distance=termination_distance,
                                    max_steps_per_clip=max_steps_per_clip)
        if composition is not None:
            request.composition.CopyFrom(composition)
        for name, value in (family_params or {}).items():
            request.family_params[str(name)] = float(value)
        if action_mode is not None:
            request.action_mode = _enum(action_mode, _ACTION_MODE, "action_mode")
        _set_checkpoint(request, "rollout", checkpoint, checkpoint_bytes, server_checkpoint)
        results: List[ClipRollout] = []
        frame_rows: Dict[str, List[pb.RolloutFrame]] = {}
        try:
            for response in self._stub.Rollout(request, metadata=self._metadata, timeout=timeout):
                kind = response.WhichOneof("kind")
                if kind == "frame":
                    frame_rows.setdefault(response.frame.clip, []).append(response.frame)
                elif kind == "metrics":
                    results.append(ClipRollout.from_proto(response.metrics))
        except grpc.RpcError as e:
            raise ServerError.from_rpc_error(e, self.server, "Rollout") from None
        if frames:
            for result in results:
                _set_frames(result, frame_rows.get(result.clip, []))
        return results

    def query_family(self, checkpoint: Optional[PathLike] = None, params: Optional[Mapping[str, float]] = None,
                     nearest_elites: int = 0, *, checkpoint_bytes: Optional[bytes] = None,
                     server_checkpoint: Optional[str] = None, timeout: Optional[float] = None) -> FamilyQuery:
        """A motor-skill family's policy.pt (``modskill-learner --family``) at task parameters a
        (``params`` by name; the rest at the middle of their trained range): its ranges, P(a), the
        parameterization network's edited motion over the clip's frames, and the ``nearest_elites``
        elites nearest a (0: 5, the paper's k). Give exactly one of checkpoint (a local file,
        uploaded), checkpoint_bytes or server_checkpoint (as ``rollout``). ServerError
        FAILED_PRECONDITION for a checkpoint that is not a family's."""
        request = pb.QueryFamilyRequest(nearest_elites=int(nearest_elites))
        for name, value in (params or {}).items():
            request.params[str(name)] = float(value)
        _set_checkpoint(request, "query_family", checkpoint, checkpoint_bytes, server_checkpoint)
        return FamilyQuery.from_proto(self._unary("QueryFamily", request, timeout))

    def record_skills(self, checkpoint: PathLike, clips: Sequence[str] = (), max_steps_per_clip: int = 0,
                      timeout: Optional[float] = None) -> List[ClipRollout]:
        """A ModSkill tracker's z on clips: one :class:`ClipRollout` per clip with frames and
        ``skill_z`` float32 [T, num_parts, embed_dim] (NaN on the last row). The checkpoint must
        export skills() and act_with_z() (ServerError FAILED_PRECONDITION otherwise; older
        policies are re-exported with ``modskill-policy-upgrade``)."""
        return self.rollout(checkpoint, clips=clips, record_skills=True, max_steps_per_clip=max_steps_per_clip,
                            timeout=timeout)

    def compose(self, checkpoint: PathLike, base: str, source: str, parts: Union[str, Sequence[str]],
                interpolate: bool = False, max_steps_per_clip: int = 0,
                timeout: Optional[float] = None) -> ClipRollout:
        """Skill composition: rolls out clip ``base`` with the z of ``parts`` (names of the
        checkpoint's part layout, e.g. "R_Arm") taken from clip ``source``, step for step, or with
        ``interpolate`` blended from the base's own z (first step) to the source's (last step) and
        normalized back to the sphere. Returns the base clip's :class:`ClipRollout` with frames,
        ``skill_z`` (the composed z) and ``composition`` (the server's report)."""
        if isinstance(parts, str):
            parts = [parts]
        composition = pb.SkillComposition(base_clip=base, source_clip=source, parts=list(parts),
                                          mode=pb.INTERPOLATE if interpolate else pb.SWAP)
        results = self.rollout(checkpoint, record_skills=True, composition=composition,
                               max_steps_per_clip=max_steps_per_clip, timeout=timeout)
        if len(results) != 1:
            raise ValueError(f"compose: the server sent {len(results)} clip results, expected 1")
        return results[0]

    def session(self, num_envs: int, seed: int = 0, part_layout: str = "", motions: Sequence[str] = (),
                termination: Union[str, int] = "training", amp_obs: Union[str, int] = "full", *,
                termination_distance: float = 0.0, max_episode_steps: int = 0,
                action_mode: Optional[Union[str, int]] = None, residual_scale: float = 0.0,
                termination_bodies: Union[str, int] = "all", task: str = "",
                task_settings: Optional[Mapping[str, float]] = None, loop_clips: bool = False,
                family: Optional[Mapping[str, Union[float, Tuple[float, float]]]] = None,
                reward_parts: Sequence[str] = (), reward_relative_to_root: bool = False,
                anchor_reference: bool = False, anchor_position_only: bool = False, energy_weight: Optional[float] = None,
                imitation_kernels: Optional[Mapping[str, float]] = None, reference_frames: int = 0) -> "Session":
        """Opens a simulation session of ``num_envs`` envs and returns it once the server has
        reset them (``Session.initial`` holds the first observations).

        Args:
          num_envs: envs stepped together (rows of every array).
          seed: seeds clip and start-frame sampling.
          part_layout: '' : the server's default.
          motions: clip names the session samples from; empty: the whole library.
          termination: "training" (any body farther than 0.25 m ends the episode),
            "evaluation" (mean body error above 0.5 m) or "none" (only the clip's end).
          amp_obs: "full" (``amp_history`` frames per env, newest first), "newest" or "omit".
          termination_distance: metres; 0: the mode's default.
          max_episode_steps: 0: until the clip ends.
          action_mode: "absolute" (PD target = offset + scale * a) or "residual" (the reference
            pose of the next frame + residual_scale * scale * a: zero actions track open loop).
            Default: "residual" in a family session, "absolute" otherwise.
          residual_scale: residual mode only; 0: the server's default (0.5).
          termination_bodies: "all" or "no_feet" (training termination ignores ankles and toes).
          task: "" or "tracking", or a task env ``describe().tasks`` lists ("steer", "reach",
            "strike", "vr_tracking"): the goal ends each observation (``spec.goal_obs``).
          task_settings: e.g. {"min_speed": 1.0, "max_speed": 2.0, "min_goal_interval_s": 2,
            "max_goal_interval_s": 5}, or reach's target box {"reach_box_size": 0.5,
            "reach_center_x": 0.3, "reach_center_y": -0.3, "reach_center_z": 1.2}, or
            {"steering_rate": 60} (deg/s: the base motion turns toward the goal); a missing key
            keeps the server's default.
          loop_clips: tracking only: a clip's end does not end the episode; the reference goes on
            at frame 1, moved by the clip's own displacement, until max_episode_steps (0: 300).
          family: a motor-skill family over the session's one clip (Lee et al. 2021), e.g.
            {"gravity": (4, 14), "jump_height": 1.2}: each parameter's range (lo, hi) or a value (a
            constraint); ``describe().family_parameters`` lists them. Actions are residual
            displacements plus a time warp at ``spec.time_warp_action``; ``step(family_params=)``
            picks each env's next parameters.
          reward_parts: parts of the layout (e.g. ["R_Arm", "L_Arm"]) whose bodies alone the
            imitation reward averages over, for a part retrained alone; empty: every body.
            Termination and the errors still use every body.
          reward_relative_to_root: tracking only: the reward compares the rewarded bodies in the
            root's frame, so the root's drift stays out of a part's reward.
          anchor_reference: tracking only: each step the reference's next frame is carried onto
            the character's root and heading (as a goal task's base motion is), so the reward and
            termination ask the character to go on from where it is, not to win back drift.
          anchor_position_only: with anchor_reference: the root's position only; the reference
            keeps the clip's heading, so a heading error stays until the character wins it back.
          energy_weight: the energy penalty as a multiple of the paper's, in [0, 100]; None: 1.
            0 turns it off (its ``reward_terms`` column stays, at 0).
          imitation_kernels: tracking only: the imitation reward's k per term, e.g. {"pos": 400};
            keys pos, rot, vel, ang_vel, each in (0, 10000]; a missing key keeps PHC's default.
          reference_frames: tracking only (no loop_clips, no anchor_reference): how many
            upcoming reference frames each body observes, in [1, 8]; 0: 1. Each adds 24 features
            per body (``spec.reference_frames`` blocks after a body's self features).

        Use it as a context manager (or call ``close()``) so that the server frees the envs.
        """
        if isinstance(motions, str):
            motions = [motions]
        if action_mode is None:
            action_mode = "residual" if family else "absolute"
        config = pb.SessionConfig(num_envs=int(num_envs), seed=int(seed), part_layout=part_layout,
                                  motions=list(motions), termination=_enum(termination, _TERMINATION, "termination"),
                                  termination_distance=termination_distance,
                                  max_episode_steps=int(max_episode_steps),
                                  amp_obs=_enum(amp_obs, _AMP_OBS, "amp_obs"),
                                  action_mode=_enum(action_mode, _ACTION_MODE, "action_mode"),
                                  residual_scale=residual_scale,
                                  termination_bodies=_enum(termination_bodies, _TERMINATION_BODIES,
                                                           "termination_bodies"),
                                  task=task, task_settings=pb.TaskSettings(**dict(task_settings or {})),
                                  loop_clips=bool(loop_clips), family=_family_config(family),
                                  reward_parts=[reward_parts] if isinstance(reward_parts, str) else list(reward_parts),
                                  reward_relative_to_root=bool(reward_relative_to_root),
                                  anchor_reference=bool(anchor_reference),
                                  anchor_position_only=bool(anchor_position_only),
                                  reference_frames=int(reference_frames))
        if energy_weight is not None:
            config.energy_weight = float(energy_weight)
        if imitation_kernels:
            config.imitation_kernels.CopyFrom(pb.ImitationKernels(**{k: float(v) for k, v in imitation_kernels.items()}))
        session = Session(self, config)
        self._sessions.add(session)
        return session


def _family_config(family: Optional[Mapping[str, Union[float, Tuple[float, float]]]]) -> pb.FamilyConfig:
    """{"gravity": (4, 14), "jump_height": 1.2} -> FamilyConfig (a single value is lo = hi)."""
    config = pb.FamilyConfig()
    for name, value in (family or {}).items():
        lo, hi = (value, value) if np.isscalar(value) else tuple(value)
        config.params.add(name=str(name), lo=float(lo), hi=float(hi))
    return config


_END = object()  # ends the request stream


class Session:
    """One open ``Simulate`` stream (see :meth:`Client.session`).

    Attributes:
      session_id: the server's id (for ``report_failures`` and ``stats``).
      spec: the :class:`EnvSpec` of the session's layout (``num_motions``: the session's clips).
      clip_names: the session's clips by id; ``StepResult.clip_id`` indexes this list. Clips the
        server generates for the session (generative resampling) are appended as they are
        announced; evicted ones keep their entry (ids are never reused).
      clip_provenance: id -> provenance dict (parent, generator, part, seed) of generated clips.
      initial: the :class:`StepResult` after the first reset (step 0).
      last: the latest result (``initial`` before the first step).
      num_envs: rows of every batch.
    """

    def __init__(self, client: Client, config: pb.SessionConfig):
        self._client = client
        self._requests: "queue.Queue[object]" = queue.Queue()
        self._lock = threading.Lock()
        self._closed = False
        self._error: Optional[ServerError] = None
        self.num_envs = config.num_envs
        self._requests.put(pb.SimulateRequest(config=config))
        self._responses = client._stub.Simulate(iter(self._requests.get, _END), metadata=client._metadata)
        opened = self._receive("opened").opened
        self.session_id: str = opened.session_id
        self.spec = EnvSpec.from_proto(opened.spec)
        self.clip_names: List[str] = list(opened.clip_names)
        self.clip_provenance: Dict[int, Dict[str, Any]] = {}
        self.initial = StepResult.from_proto(opened.initial)
        self.last = self.initial
        self._action_shape = (self.num_envs, self.spec.action_size)

    def _fail(self, error: ServerError) -> ServerError:
        self._error = error
        self._closed = True
        self._requests.put(_END)
        return error

    def _receive(self, kind: str) -> pb.SimulateResponse:
        try:
            response = next(self._responses)
        except grpc.RpcError as e:
            raise self._fail(ServerError.from_rpc_error(e, self._client.server, "Simulate")) from None
        except StopIteration:
            raise self._fail(ServerError(grpc.StatusCode.INTERNAL, "the server ended the session stream",
                                         self._client.server, "Simulate")) from None
        if response.WhichOneof("kind") != kind:
            raise self._fail(ServerError(grpc.StatusCode.INTERNAL,
                                         f"expected a '{kind}' reply, got '{response.WhichOneof('kind')}'",
                                         self._client.server, "Simulate"))
        return response

    def check_actions(self, actions: np.ndarray) -> np.ndarray:
        """Returns ``actions`` as a C-contiguous little-endian float32 [num_envs, action_size] array.

        Raises ValueError on a wrong shape, a non-float dtype or non-finite values.
        """
        actions = np.asarray(actions)
        if actions.shape != self._action_shape:
            raise ValueError(f"actions: shape {list(actions.shape)}, expected [num_envs, action_size] = "
                             f"{list(self._action_shape)}")
        if actions.dtype.kind != "f":
            raise ValueError(f"actions: dtype {actions.dtype}, expected a float dtype (sent as float32)")
        actions = np.ascontiguousarray(actions, dtype="<f4")
        finite = np.isfinite(actions)
        if not finite.all():
            row, col = np.argwhere(~finite)[0]
            raise ValueError(f"actions: non-finite value {actions[row, col]} at [{row}, {col}]")
        return actions

    def step(self, actions: np.ndarray, termination_distance: float = 0.0,
             family_params: Optional[np.ndarray] = None) -> StepResult:
        """Sends a batch of actions (float [num_envs, action_size], clipped to [-1, 1] by the
        server) and returns the resulting :class:`StepResult`. A termination_distance > 0 (m)
        becomes the session's from this step on (a curriculum); 0 keeps it. In a family session,
        family_params (float [num_envs, len(spec.family)], each inside its range) are the
        parameters of each env's episodes from its next reset on."""
        actions = self.check_actions(actions)
        with self._lock:
            if self._closed:
                raise RuntimeError(f"session {self.session_id}: closed"
                                   + (f" after an error ({self._error})" if self._error else ""))
            request = pb.SimulateRequest(termination_distance=termination_distance)
            tensors.encode(actions, request.actions)
            if family_params is not None:
                tensors.encode(np.ascontiguousarray(family_params, dtype=np.float32), request.family_params)
            self._requests.put(request)
            step = self._receive("step").step
            if step.HasField("motion_set_update"):
                self._apply_motion_set_update(step.motion_set_update)
            self.last = StepResult.from_proto(step)
            return self.last

    def _apply_motion_set_update(self, update: pb.MotionSetUpdate) -> None:
        for clip in update.added:
            if clip.clip_id >= len(self.clip_names):
                self.clip_names.extend([""] * (clip.clip_id + 1 - len(self.clip_names)))
            self.clip_names[clip.clip_id] = clip.name
            p = clip.provenance
            self.clip_provenance[clip.clip_id] = {"parent": p.parent, "generator": p.generator, "part": p.part,
                                                  "seed": p.seed}

    def part_obs(self, obs: np.ndarray, part: str) -> np.ndarray:
        """The columns of ``obs`` that belong to body part ``part`` (see ``spec.parts``)."""
        return self.spec.part_obs(obs, part)

    def report_failures(self, failures) -> Dict[str, Any]:
        """``Client.report_failures`` for this session."""
        return self._client.report_failures(self.session_id, failures)

    @property
    def closed(self) -> bool:
        return self._closed

    def close(self, raise_errors: bool = True) -> None:
        """Ends the stream; the server frees the envs. Idempotent.

        With ``raise_errors`` a final error status of the server raises :class:`ServerError`.
        """
        with self._lock:
            if self._closed:
                return
            self._closed = True
            self._requests.put(_END)
            try:
                for _ in self._responses:  # drains to the final status
                    pass
            except grpc.RpcError as e:
                if e.code() == grpc.StatusCode.CANCELLED:
                    return
                self._error = ServerError.from_rpc_error(e, self._client.server, "Simulate")
                if raise_errors:
                    raise self._error from None

    def __enter__(self) -> "Session":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close(raise_errors=exc_type is None)

    def __del__(self):
        try:
            if not self._closed:
                self._requests.put(_END)
                self._responses.cancel()
        except Exception:
            pass

    def __repr__(self) -> str:
        state = "closed" if self._closed else f"step {self.last.step}"
        return f"modskill.Session({self.session_id!r}, {self.num_envs} envs, {self.spec.part_layout}, {state})"
