"""Plain Python views of the server's messages: the env spec, step results and rollouts.

Sizes are never hard-coded on the client: everything here is built from what the server sends
(``Describe``, ``SessionOpened``), so a client keeps working when the observation or the part
layout changes.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

from . import tensors
from .v1 import modskill_pb2 as pb

__all__ = ["BodyPart", "BodyGeometry", "EnvSpec", "StepResult", "ClipRollout", "message_to_dict"]


@dataclasses.dataclass(frozen=True)
class BodyPart:
    """One body part of a layout.

    ``obs`` and ``action`` are Python ``slice`` objects, so ``obs[:, part.obs]`` is this part's
    observation columns and ``actions[:, part.action]`` its action columns. ``self_obs`` holds one
    slice per body: the part's proprioceptive columns (without the reference features), what a
    reusable low-level controller reads beside its skill embedding.
    """

    name: str
    bodies: Tuple[str, ...]  # in observation order
    obs: slice
    action: slice
    self_obs: Tuple[slice, ...] = ()

    @property
    def obs_size(self) -> int:
        return self.obs.stop - self.obs.start

    @property
    def action_size(self) -> int:
        return self.action.stop - self.action.start


_SHAPES = {pb.BodyGeometry.SPHERE: "sphere", pb.BodyGeometry.CAPSULE: "capsule", pb.BodyGeometry.BOX: "box"}


@dataclasses.dataclass(frozen=True)
class PhysicsSettings:
    """How the session simulates beyond its control step (the server's --substeps, --pd_mode,
    --pd_gain_scale, --damp_to_reference_rate). A policy runs only under the physics it was
    trained in; ``physics_dt`` is 0 from a server older than the field."""

    physics_dt: float = 0.0  # seconds per physics step (control_dt / substeps)
    pd_mode: str = ""  # "position_implicit" or "stable_pd"
    pd_gain_scale: float = 0.0
    damp_to_reference_rate: bool = False

    @classmethod
    def from_proto(cls, physics: pb.PhysicsSettings) -> "PhysicsSettings":
        return cls(physics_dt=physics.physics_dt, pd_mode=physics.pd_mode, pd_gain_scale=physics.pd_gain_scale,
                   damp_to_reference_rate=physics.damp_to_reference_rate)


@dataclasses.dataclass(frozen=True)
class BodyGeometry:
    """A body's collision geometry in its own frame (one geom per body), for viewers.

    Lengths are metres. A 3-vector the shape does not use may be empty (read as zero).
    """

    parent: int  # index into EnvSpec.body_names; -1 for the root
    shape: str  # "sphere", "capsule" or "box" ("unspecified" for a shape this client does not know)
    radius: float  # sphere and capsule
    half_extents: Tuple[float, ...]  # box: x, y, z, axis-aligned in the body frame
    segment_from: Tuple[float, ...]  # capsule: the segment's ends
    segment_to: Tuple[float, ...]
    center: Tuple[float, ...]  # sphere and box

    @classmethod
    def from_proto(cls, geometry: pb.BodyGeometry) -> "BodyGeometry":
        return cls(parent=geometry.parent, shape=_SHAPES.get(geometry.shape, "unspecified"),
                   radius=geometry.radius, half_extents=tuple(geometry.half_extents),
                   segment_from=tuple(geometry.segment_from), segment_to=tuple(geometry.segment_to),
                   center=tuple(geometry.center))


@dataclasses.dataclass(frozen=True)
class EnvSpec:
    """The observation and action layout of a part layout (``Describe`` / ``Session.spec``)."""

    part_layout: str
    parts: Tuple[BodyPart, ...]
    obs_size: int
    self_obs_size: int
    task_obs_size: int
    action_size: int
    amp_obs_per_frame: int
    amp_history: int  # frames in a full AMP observation, newest first
    body_names: Tuple[str, ...]  # MuJoCo order (the order of rollout body positions)
    joint_names: Tuple[str, ...]  # hinges in action order
    control_dt: float  # seconds per step
    part_layouts: Tuple[str, ...]  # layouts the server offers (Describe only)
    reward_terms: Tuple[str, ...]  # columns of StepResult.reward_terms
    num_motions: int
    action_modes: Tuple[str, ...]  # "absolute", "residual" (Describe only)
    termination_bodies: Tuple[str, ...]  # "all", "no_feet" (Describe only)
    action_offset: np.ndarray = dataclasses.field(repr=False, compare=False)  # PD target = offset + scale * a
    action_scale: np.ndarray = dataclasses.field(repr=False, compare=False)
    # One per body (body_names order), for viewers (modskill.viewer); empty from a server older
    # than the viewer.
    body_geometry: Tuple[BodyGeometry, ...] = dataclasses.field(repr=False, compare=False)
    # The session's task ("tracking", "steer", ...); in a task env the goal ends obs, obs[goal_obs]
    # (steer, reach, strike: after tracking's features of the anchored base motion; vr_tracking:
    # after the self features). ``tasks``: what Describe offers, name -> (goal size, reward terms).
    task: str = "tracking"
    goal_obs: slice = dataclasses.field(default_factory=lambda: slice(0, 0))
    tasks: Dict[str, Tuple[int, Tuple[str, ...]]] = dataclasses.field(default_factory=dict, compare=False)
    # Motor-skill families: the parameters Describe offers (name -> (unit, description)); a family
    # session's ranges (name -> (lo, hi), in a's order) and its time warp's action index (-1: none).
    family_parameters: Dict[str, Tuple[str, str]] = dataclasses.field(default_factory=dict, compare=False)
    family: Dict[str, Tuple[float, float]] = dataclasses.field(default_factory=dict)
    time_warp_action: int = -1
    # Tracking: the upcoming reference frames each body observes (SessionConfig.reference_frames);
    # its task features are that many blocks of 24 after its self features, the next frame's first.
    reference_frames: int = 1
    physics: PhysicsSettings = PhysicsSettings()

    @classmethod
    def from_proto(cls, spec: pb.EnvSpec) -> "EnvSpec":
        parts = tuple(
            BodyPart(
                name=p.name,
                bodies=tuple(p.bodies),
                obs=slice(p.obs.start, p.obs.start + p.obs.size),
                action=slice(p.action.start, p.action.start + p.action.size),
                self_obs=tuple(slice(q.start, q.start + q.size) for q in p.self_obs),
            )
            for p in spec.parts)
        return cls(
            part_layout=spec.part_layout,
            parts=parts,
            obs_size=spec.obs_size,
            self_obs_size=spec.self_obs_size,
            task_obs_size=spec.task_obs_size,
            action_size=spec.action_size,
            amp_obs_per_frame=spec.amp_obs_per_frame,
            amp_history=spec.amp_history,
            body_names=tuple(spec.body_names),
            joint_names=tuple(spec.joint_names),
            control_dt=spec.control_dt,
            part_layouts=tuple(spec.part_layouts),
            reward_terms=tuple(spec.reward_terms),
            num_motions=spec.num_motions,
            action_modes=tuple(spec.action_modes),
            termination_bodies=tuple(spec.termination_bodies),
            action_offset=np.array(spec.action_offset, dtype=np.float32),
            action_scale=np.array(spec.action_scale, dtype=np.float32),
            body_geometry=tuple(BodyGeometry.from_proto(g) for g in spec.body_geometry),
            task=spec.task or "tracking",
            goal_obs=slice(spec.goal_obs.start, spec.goal_obs.start + spec.goal_obs.size),
            tasks={t.name: (t.goal_size, tuple(t.reward_terms)) for t in spec.tasks},
            family_parameters={p.name: (p.unit, p.description) for p in spec.family_parameters},
            family={r.name: (r.lo, r.hi) for r in spec.family},
            time_warp_action=spec.time_warp_action if spec.family else -1,
            reference_frames=max(1, spec.reference_frames),  # 0 from a server older than the field
            physics=PhysicsSettings.from_proto(spec.physics),
        )

    @property
    def part_names(self) -> Tuple[str, ...]:
        return tuple(p.name for p in self.parts)

    @property
    def amp_obs_size(self) -> int:
        """Columns of a full AMP observation (``amp_obs="full"``)."""
        return self.amp_obs_per_frame * self.amp_history

    def part(self, name: str) -> BodyPart:
        """The part called ``name``; KeyError listing the layout's parts otherwise."""
        for p in self.parts:
            if p.name == name:
                return p
        raise KeyError(f"part {name!r} is not in layout {self.part_layout!r} (parts: {', '.join(self.part_names)})")

    def part_obs(self, obs: np.ndarray, part: str) -> np.ndarray:
        """The columns of ``obs`` (``[..., obs_size]``) that belong to ``part`` (a view)."""
        obs = np.asarray(obs)
        if obs.shape[-1:] != (self.obs_size,):
            raise ValueError(f"obs: shape {list(obs.shape)}, expected [..., {self.obs_size}]")
        return obs[..., self.part(part).obs]

    def part_action(self, actions: np.ndarray, part: str) -> np.ndarray:
        """The columns of ``actions`` (``[..., action_size]``) that belong to ``part`` (a view)."""
        actions = np.asarray(actions)
        if actions.shape[-1:] != (self.action_size,):
            raise ValueError(f"actions: shape {list(actions.shape)}, expected [..., {self.action_size}]")
        return actions[..., self.part(part).action]

    def pd_targets(self, actions: np.ndarray) -> np.ndarray:
        """Joint PD targets (rad) for actions in [-1, 1]: offset + scale * clip(actions)."""
        return self.action_offset + self.action_scale * np.clip(actions, -1.0, 1.0)


@dataclasses.dataclass(frozen=True)
class StepResult:
    """A batch of env results; row i is env i. Arrays are read-only views of the reply.

    After an episode ends (``done``), the row already holds the next episode's observation;
    ``ended_clip_id`` / ``ended_frame`` say which clip and frame the finished episode reached.
    """

    step: int  # steps taken in this session (0 for the initial result)
    obs: np.ndarray  # float32 [N, obs_size]
    amp_obs: Optional[np.ndarray]  # float32 [N, frames * amp_obs_per_frame]; None with amp_obs="omit"
    reward: np.ndarray  # float32 [N]
    reward_terms: np.ndarray  # float32 [N, len(spec.reward_terms)]
    done: np.ndarray  # bool [N]
    truncated: np.ndarray  # bool [N]: ended by the clip's end or the step limit
    clip_id: np.ndarray  # int32 [N], index into Session.clip_names
    frame: np.ndarray  # int32 [N], reference frame of the row's state
    ended_clip_id: np.ndarray  # int32 [N], valid where done
    ended_frame: np.ndarray  # int32 [N]
    max_body_error: np.ndarray  # float32 [N], m, before any reset
    mean_body_error: np.ndarray  # float32 [N], m
    # float32 [N, num_parts], m: mean body distance per part (EnvSpec.parts order) before any reset,
    # which parts a failing env lost; None where the server sent none
    part_error: Optional[np.ndarray] = None
    # Family sessions only (``Client.session(family=...)``), None otherwise:
    family_params: Optional[np.ndarray] = None  # float32 [N, P]: the parameters a of each row's episode
    ended_family_params: Optional[np.ndarray] = None  # float32 [N, P]: a of the episode that ended (where done)
    phase_step: Optional[np.ndarray] = None  # float32 [N]: frames the phase advanced (1: the clip's pace)
    spike_reward: Optional[np.ndarray] = None  # float32 [N]: the one-off part of reward (a peak's)
    fitness: Optional[np.ndarray] = None  # float32 [N]: the ended episode's fitness F (where done)
    # uint8 [N]: why each ended episode ended (where done), a modskill_pb2.EndCause value (TIME,
    # TRACKING, FALL, TASK, BLOW_UP); None where the server sent none
    end_cause: Optional[np.ndarray] = None

    # Proto fields the session consumes itself rather than handing to the caller.
    SESSION_FIELDS = ("motion_set_update",)

    @classmethod
    def from_proto(cls, result: pb.StepResult) -> "StepResult":
        def get(name):
            return tensors.decode(getattr(result, name), name)

        def flag(name):
            return get(name).view(np.bool_)  # 0/1 bytes: a zero-copy bool view

        return cls(
            step=int(result.step),
            obs=get("obs"),
            amp_obs=tensors.decode_field(result, "amp_obs"),
            reward=get("reward"),
            reward_terms=get("reward_terms"),
            done=flag("done"),
            truncated=flag("truncated"),
            clip_id=get("clip_id"),
            frame=get("frame"),
            ended_clip_id=get("ended_clip_id"),
            ended_frame=get("ended_frame"),
            max_body_error=get("max_body_error"),
            mean_body_error=get("mean_body_error"),
            part_error=tensors.decode_field(result, "part_error"),
            family_params=tensors.decode_field(result, "family_params"),
            ended_family_params=tensors.decode_field(result, "ended_family_params"),
            phase_step=tensors.decode_field(result, "phase_step"),
            spike_reward=tensors.decode_field(result, "spike_reward"),
            fitness=tensors.decode_field(result, "fitness"),
            end_cause=tensors.decode_field(result, "end_cause"),
        )

    @property
    def num_envs(self) -> int:
        return self.obs.shape[0]


@dataclasses.dataclass
class ClipRollout:
    """The result of a policy on one clip (``Client.rollout``).

    Errors are in millimetres. With ``frames=True`` the body poses of every step are kept:
    ``sim_body_pos`` and ``ref_body_pos`` are float32 ``[T, num_bodies, 3]`` in metres (world
    frame, z up, bodies in ``EnvSpec.body_names`` order), ``sim_body_rot`` and ``ref_body_rot``
    float32 ``[T, num_bodies, 4]`` world orientations as w, x, y, z (MuJoCo's order),
    ``body_error_m`` float32 ``[T]`` the mean distance between simulated and reference bodies,
    ``frames`` the reference frame of each row, and ``done`` / ``terminated`` bool ``[T]``: the
    clip's last row, and whether it ended there by termination rather than at the clip's end.
    T counts the start state too, so it is normally ``steps + 1``. ``modskill.viewer.write_html``
    draws them as a page. Without ``frames=True`` these are None.
    """

    clip: str
    success: bool  # never terminated
    steps: int
    g_mpjpe_mm: float  # global body position error
    mpjpe_mm: float  # root-relative
    acc_error_mm: float  # mm / frame^2
    vel_error_mm: float  # mm / frame
    body_error_mm: np.ndarray  # [num_bodies], body_names order
    part_error_mm: np.ndarray  # [num_parts] of the checkpoint's layout
    frames: Optional[np.ndarray] = None  # int32 [T]
    sim_body_pos: Optional[np.ndarray] = None  # float32 [T, num_bodies, 3]
    ref_body_pos: Optional[np.ndarray] = None  # float32 [T, num_bodies, 3]
    sim_body_rot: Optional[np.ndarray] = None  # float32 [T, num_bodies, 4], w x y z
    ref_body_rot: Optional[np.ndarray] = None  # float32 [T, num_bodies, 4]
    body_error_m: Optional[np.ndarray] = None  # float32 [T], mean body error per row
    done: Optional[np.ndarray] = None  # bool [T], the clip's last row
    terminated: Optional[np.ndarray] = None  # bool [T], ... ended by termination
    # With record_skills (Client.record_skills, Client.compose): float32 [T, num_parts, embed_dim],
    # the z the policy acted on from each row (unit norm per part); NaN on the last row, from
    # which no action is taken.
    skill_z: Optional[np.ndarray] = None
    # A composed rollout's report (Client.compose): source_clip, parts, mode, source_steps,
    # source_terminated, held_steps (base steps that used the source's last z).
    composition: Optional[Dict[str, Any]] = None
    # A motor-skill family's rollout (Client.rollout with family_params): params (a by name),
    # fitness (F), apex_height_m, highest_effector_m, flight_s, reached_end, final_phase.
    family: Optional[Dict[str, Any]] = None

    @classmethod
    def from_proto(cls, metrics: pb.ClipMetrics) -> "ClipRollout":
        return cls(
            clip=metrics.clip,
            success=metrics.success,
            steps=metrics.steps,
            g_mpjpe_mm=metrics.g_mpjpe_mm,
            mpjpe_mm=metrics.mpjpe_mm,
            acc_error_mm=metrics.acc_error_mm,
            vel_error_mm=metrics.vel_error_mm,
            body_error_mm=np.array(metrics.body_error_mm, dtype=np.float64),
            part_error_mm=np.array(metrics.part_error_mm, dtype=np.float64),
            composition=None if not metrics.HasField("composition") else {
                "source_clip": metrics.composition.source_clip,
                "parts": list(metrics.composition.parts),
                "mode": pb.CompositionMode.Name(metrics.composition.mode),
                "source_steps": metrics.composition.source_steps,
                "source_terminated": metrics.composition.source_terminated,
                "held_steps": metrics.composition.held_steps,
            },
            family=None if not metrics.HasField("family") else {
                "params": dict(metrics.family.params),
                "fitness": metrics.family.fitness,
                "apex_height_m": metrics.family.apex_height_m,
                "highest_effector_m": metrics.family.highest_effector_m,
                "flight_s": metrics.family.flight_s,
                "reached_end": metrics.family.reached_end,
                "final_phase": metrics.family.final_phase,
            },
        )

    def body_errors(self) -> np.ndarray:
        """Per-step distance between simulated and reference body, m, ``[T, num_bodies]``
        (needs ``frames=True``)."""
        if self.sim_body_pos is None or self.ref_body_pos is None:
            raise ValueError(f"clip {self.clip!r}: no frames (call rollout with frames=True)")
        return np.linalg.norm(self.sim_body_pos - self.ref_body_pos, axis=-1)

    def metrics(self) -> Dict[str, object]:
        """The scalar metrics as a dict (for logging and tables)."""
        return {k: getattr(self, k) for k in ("clip", "success", "steps", "g_mpjpe_mm", "mpjpe_mm",
                                              "acc_error_mm", "vel_error_mm")}


@dataclasses.dataclass
class FamilyQuery:
    """A motor-skill family's policy at task parameters a (``Client.query_family``).

    ``parameterization`` is P(a), float32 ``[clip frames, len(parameterization_columns)]``: per
    frame of the clip, each hinge's displacement (in the policy's action units) and tau, the log
    of the phase step there; None while the run has fitted no parameterization network.
    ``nearest_elites`` lists dicts with ``params``, ``fitness`` and ``distance`` (over the ranges
    normalized to [0, 1]), nearest first.
    """

    clip: str
    ranges: Dict[str, Tuple[float, float]]
    params: Dict[str, float]
    normalized_params: np.ndarray
    parameterization: Optional[np.ndarray]
    parameterization_columns: List[str]
    elites: int
    nearest_elites: List[Dict[str, Any]]

    @classmethod
    def from_proto(cls, response: pb.QueryFamilyResponse) -> "FamilyQuery":
        trajectory = tensors.decode_field(response, "parameterization")
        return cls(
            clip=response.clip,
            ranges={r.name: (r.lo, r.hi) for r in response.ranges},
            params=dict(response.params),
            normalized_params=np.array(response.normalized_params, dtype=np.float64),
            parameterization=None if trajectory is None or trajectory.size == 0 else trajectory,
            parameterization_columns=list(response.parameterization_columns),
            elites=response.elites,
            nearest_elites=[{"params": dict(e.params), "fitness": e.fitness, "distance": e.distance}
                            for e in response.nearest_elites],
        )


def message_to_dict(message) -> Dict[str, object]:
    """A protobuf message as a dict of Python values: every field (defaults included), nested
    messages as dicts, repeated fields as lists, enums as their names, integers as ints."""
    out: Dict[str, object] = {}
    for field in message.DESCRIPTOR.fields:
        value = getattr(message, field.name)
        if field.type == field.TYPE_MESSAGE:
            if field.label == field.LABEL_REPEATED:
                value = [message_to_dict(v) for v in value]
            elif message.HasField(field.name):
                value = message_to_dict(value)
            else:
                value = None
        elif field.type == field.TYPE_ENUM:
            name = lambda v: field.enum_type.values_by_number[v].name if v in field.enum_type.values_by_number else v
            value = [name(v) for v in value] if field.label == field.LABEL_REPEATED else name(value)
        elif field.label == field.LABEL_REPEATED:
            value = list(value)
        out[field.name] = value
    return out


def motions_to_dicts(response: pb.ListMotionsResponse) -> List[Dict[str, object]]:
    return [message_to_dict(m) for m in response.motions]
