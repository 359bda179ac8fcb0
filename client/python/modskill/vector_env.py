"""A Gymnasium-style vector env over one simulation session, without depending on gymnasium.

Example::

    import numpy as np
    import modskill

    with modskill.VectorEnv("127.0.0.1:50051", num_envs=16, action_mode="residual") as env:
        obs, info = env.reset(seed=0)                 # obs: float32 [16, obs_size]
        for _ in range(100):
            actions = env.action_space.sample()       # float32 [16, action_size] in [-1, 1]
            obs, reward, terminated, truncated, info = env.step(actions)
        legs = obs[:, info["parts"]["L_Leg"]]

Conventions (Gymnasium 1.x ``gymnasium.vector.VectorEnv``):

- ``reset(seed=None) -> (obs, info)`` resets every env: it opens a new server session (the server
  has no reset of a running batch). ``seed`` seeds clip and start-frame sampling; ``None`` takes
  the next seed after the previous reset's.
- ``step(actions) -> (obs, reward, terminated, truncated, info)``, arrays with one row per env.
  ``terminated``: the episode failed (a body left the reference); ``truncated``: it reached the
  clip's end or ``max_episode_steps``. Never both.
- Autoreset is Gymnasium's ``AutoresetMode.SAME_STEP``: the server resets an ended env within the
  step that ended it, so its row of ``obs`` already holds the *next* episode's first
  observation, and no extra step is needed. The ended episode's last observation is not
  available (the server does not send it), so ``info`` has no ``"final_obs"``. What the server
  does report about the ended episode is in ``info["final_info"]`` (a dict of arrays, valid
  where ``info["_final_info"]`` is True): clip_id, frame, max_body_error, mean_body_error,
  part_error and end_cause (why it ended: a ``modskill_pb2.EndCause`` value).
- ``info`` also holds, every step: ``parts`` ({part name: slice of the obs columns}),
  ``clip_id`` and ``frame`` (the reference clip and frame of each row's state), ``part_error``,
  ``max_body_error``, ``mean_body_error`` (m, before any reset), ``reward_terms``
  ([N, len(reward_terms)], names in ``env.reward_terms``), ``amp_obs`` (unless
  ``amp_obs="omit"``, the default here), ``step`` and ``clip_names`` (the session's, indexed by
  clip_id). Arrays in ``obs``/``info`` are read-only views of the reply: ``.copy()`` to modify.
- ``observation_space`` / ``action_space`` are batched :class:`Box` es (``[num_envs, ...]``);
  ``single_observation_space`` / ``single_action_space`` are one env's.
"""

from __future__ import annotations

from typing import Any, Dict, Optional, Sequence, Tuple, Union

import numpy as np

from .client import Client, Session
from .types import EnvSpec, StepResult

__all__ = ["Box", "VectorEnv"]


class Box:
    """A box of arrays: ``shape``, ``dtype`` and elementwise ``low``/``high`` bounds (like
    ``gymnasium.spaces.Box``, which it mirrors without the dependency)."""

    def __init__(self, low: Union[float, np.ndarray], high: Union[float, np.ndarray], shape: Sequence[int],
                 dtype: Union[str, np.dtype] = np.float32, seed: Optional[int] = None):
        self.shape = tuple(int(d) for d in shape)
        self.dtype = np.dtype(dtype)
        self.low = np.broadcast_to(np.asarray(low, self.dtype), self.shape).copy()
        self.high = np.broadcast_to(np.asarray(high, self.dtype), self.shape).copy()
        if np.any(self.low > self.high):
            raise ValueError("Box: low > high somewhere")
        self.np_random = np.random.default_rng(seed)

    def seed(self, seed: Optional[int] = None) -> None:
        self.np_random = np.random.default_rng(seed)

    def sample(self) -> np.ndarray:
        """A uniform sample (bounded dimensions; unbounded ones are drawn from N(0, 1))."""
        bounded = np.isfinite(self.low) & np.isfinite(self.high)
        value = self.np_random.standard_normal(self.shape)
        value[bounded] = self.np_random.uniform(self.low[bounded], self.high[bounded])
        return value.astype(self.dtype)

    def contains(self, x: Any) -> bool:
        x = np.asarray(x)
        return (x.shape == self.shape and np.can_cast(x.dtype, self.dtype)
                and bool(np.all(x >= self.low)) and bool(np.all(x <= self.high)))

    def __contains__(self, x: Any) -> bool:
        return self.contains(x)

    def __repr__(self) -> str:
        bounds = lambda a: f"{a.flat[0]:g}" if a.size and np.all(a == a.flat[0]) else "..."
        return f"Box({bounds(self.low)}, {bounds(self.high)}, {self.shape}, {self.dtype})"


class VectorEnv:
    """``num_envs`` humanoids of one server session, with Gymnasium's vector-env interface.

    Args:
      server: a ``host:port`` (the env opens and closes its own :class:`Client`; ``token_file``,
        ``tls_ca`` and ``timeout`` go to it) or an open :class:`Client` (left open on close).
      num_envs: envs stepped together.
      seed: the seed of the first ``reset()`` without one.
      **session: the other arguments of :meth:`Client.session` (part_layout, motions,
        termination, amp_obs (default "omit" here), termination_distance, max_episode_steps,
        action_mode, residual_scale, termination_bodies).

    Attributes: ``num_envs``, ``spec`` (the :class:`EnvSpec`), ``reward_terms``,
    ``observation_space``, ``action_space``, ``single_observation_space``,
    ``single_action_space``, ``session`` (the open :class:`Session`, None before ``reset``),
    ``metadata`` ({"autoreset_mode": "SAME_STEP"}).
    """

    metadata = {"autoreset_mode": "SAME_STEP"}

    def __init__(self, server: Union[str, Client] = "127.0.0.1:50051", num_envs: int = 1, seed: int = 0, *,
                 token_file: Optional[str] = None, tls_ca: Optional[str] = None, timeout: float = 10.0,
                 **session: Any):
        if int(num_envs) < 1:
            raise ValueError(f"num_envs: {num_envs} must be >= 1")
        self._owns_client = not isinstance(server, Client)
        self.client = Client(server, token_file=token_file, tls_ca=tls_ca, timeout=timeout) \
            if self._owns_client else server
        self.num_envs = int(num_envs)
        self._next_seed = int(seed)
        self._session_args = dict(session)
        self._session_args.setdefault("amp_obs", "omit")
        self.session: Optional[Session] = None
        self._closed = False
        try:
            self.spec: EnvSpec = self.client.describe(self._session_args.get("part_layout", ""))
        except BaseException:
            self.close()
            raise
        self.reward_terms = self.spec.reward_terms
        self._parts = {p.name: p.obs for p in self.spec.parts}
        self.single_observation_space = Box(-np.inf, np.inf, (self.spec.obs_size,), np.float32)
        self.single_action_space = Box(-1.0, 1.0, (self.spec.action_size,), np.float32)
        self.observation_space = Box(-np.inf, np.inf, (self.num_envs, self.spec.obs_size), np.float32)
        self.action_space = Box(-1.0, 1.0, (self.num_envs, self.spec.action_size), np.float32)

    def reset(self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None
              ) -> Tuple[np.ndarray, Dict[str, Any]]:
        """Starts a new episode in every env (a new session). ``options`` are not supported."""
        if self._closed:
            raise RuntimeError("VectorEnv: closed")
        if options:
            raise ValueError(f"reset: options are not supported (got {sorted(options)})")
        if seed is not None:
            self._next_seed = int(seed)
        if self.session is not None:
            self.session.close(raise_errors=False)
            self.session = None
        self.session = self.client.session(self.num_envs, seed=self._next_seed, **self._session_args)
        self._next_seed += 1
        result = self.session.initial
        return result.obs, self._info(result)

    def step(self, actions: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, Dict[str, Any]]:
        """Steps every env with ``actions`` (float [num_envs, action_size], clipped to [-1, 1])."""
        if self.session is None:
            raise RuntimeError("VectorEnv: call reset() before step()" if not self._closed else "VectorEnv: closed")
        result = self.session.step(actions)
        terminated = result.done & ~result.truncated
        return result.obs, result.reward, terminated, result.truncated.copy(), self._info(result)

    def _info(self, result: StepResult) -> Dict[str, Any]:
        info: Dict[str, Any] = {
            "parts": self._parts,
            "step": result.step,
            "clip_names": self.session.clip_names,
            "clip_id": result.clip_id,
            "frame": result.frame,
            "part_error": result.part_error,
            "max_body_error": result.max_body_error,
            "mean_body_error": result.mean_body_error,
            "reward_terms": result.reward_terms,
        }
        if result.amp_obs is not None:
            info["amp_obs"] = result.amp_obs
        if result.done.any():
            info["final_info"] = {
                "clip_id": result.ended_clip_id,
                "frame": result.ended_frame,
                "max_body_error": result.max_body_error,
                "mean_body_error": result.mean_body_error,
                "part_error": result.part_error,
            }
            if result.end_cause is not None:
                # Why each episode ended: a modskill_pb2.EndCause value (TIME, TRACKING, FALL, TASK, BLOW_UP).
                info["final_info"]["end_cause"] = result.end_cause
            info["_final_info"] = result.done.copy()
        return info

    def close(self) -> None:
        """Ends the session (the server frees the envs) and the client if the env opened it.
        Idempotent."""
        if self._closed:
            return
        self._closed = True
        if self.session is not None:
            self.session.close(raise_errors=False)
            self.session = None
        if self._owns_client:
            self.client.close()

    @property
    def closed(self) -> bool:
        return self._closed

    def __enter__(self) -> "VectorEnv":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def __repr__(self) -> str:
        return (f"modskill.VectorEnv({self.num_envs} envs, obs {self.spec.obs_size}, "
                f"actions {self.spec.action_size}{', closed' if self._closed else ''})")
