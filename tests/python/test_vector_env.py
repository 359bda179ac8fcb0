"""Tests of modskill.VectorEnv (Gymnasium's vector-env conventions) against a live server.

Run by tests/python/run_python_tests.sh (MODSKILL_SERVER: host:port of the server it started).
"""

import os
import unittest

import numpy as np

import modskill
from modskill.v1 import modskill_pb2

SERVER = os.environ.get("MODSKILL_SERVER", "")


class BoxTest(unittest.TestCase):
    """The space class; no server needed."""

    def test_bounds_sample_contains(self):
        box = modskill.Box(-1.0, 1.0, (3, 5), np.float32, seed=0)
        self.assertEqual((box.shape, box.dtype), ((3, 5), np.dtype(np.float32)))
        self.assertEqual((box.low.shape, box.high.shape), ((3, 5), (3, 5)))
        sample = box.sample()
        self.assertEqual((sample.shape, sample.dtype), ((3, 5), np.dtype(np.float32)))
        self.assertTrue(box.contains(sample))
        self.assertIn(np.zeros((3, 5), np.float32), box)
        self.assertNotIn(np.full((3, 5), 2.0, np.float32), box)
        self.assertNotIn(np.zeros((5, 3), np.float32), box)
        unbounded = modskill.Box(-np.inf, np.inf, (4,))
        self.assertTrue(np.isfinite(unbounded.sample()).all())
        with self.assertRaisesRegex(ValueError, "low > high"):
            modskill.Box(1.0, -1.0, (2,))


@unittest.skipUnless(SERVER, "MODSKILL_SERVER is not set (run tests/python/run_python_tests.sh)")
class VectorEnvTest(unittest.TestCase):
    NUM_ENVS = 4

    def make(self, **kwargs):
        env = modskill.VectorEnv(SERVER, num_envs=self.NUM_ENVS, **kwargs)
        self.addCleanup(env.close)
        return env

    def test_spaces(self):
        env = self.make()
        self.assertEqual(env.num_envs, self.NUM_ENVS)
        self.assertEqual(env.single_observation_space.shape, (934,))
        self.assertEqual(env.single_action_space.shape, (69,))
        self.assertEqual(env.observation_space.shape, (self.NUM_ENVS, 934))
        self.assertEqual(env.action_space.shape, (self.NUM_ENVS, 69))
        for space in (env.observation_space, env.action_space, env.single_observation_space):
            self.assertEqual(space.dtype, np.float32)
        self.assertTrue(np.all(env.action_space.low == -1.0) and np.all(env.action_space.high == 1.0))
        self.assertTrue(np.all(np.isinf(env.observation_space.low)))
        self.assertEqual(env.metadata["autoreset_mode"], "SAME_STEP")

    def test_reset_and_step_contract(self):
        env = self.make(action_mode="residual")
        with self.assertRaisesRegex(RuntimeError, "reset"):
            env.step(np.zeros(env.action_space.shape, np.float32))
        obs, info = env.reset(seed=1)
        self.assertEqual((obs.shape, obs.dtype), ((self.NUM_ENVS, 934), np.dtype(np.float32)))
        self.assertIn(obs, env.observation_space)
        self.assertEqual(info["step"], 0)
        self.assertEqual(list(info["parts"]), ["L_Leg", "R_Leg", "Torso", "L_Arm", "R_Arm"])
        covered = np.zeros(934, bool)
        for part, columns in info["parts"].items():
            self.assertIsInstance(columns, slice)
            covered[columns] = True
        self.assertTrue(covered.all())
        actions = env.action_space.sample()
        obs, reward, terminated, truncated, info = env.step(actions)
        self.assertEqual((obs.shape, obs.dtype), ((self.NUM_ENVS, 934), np.dtype(np.float32)))
        self.assertEqual((reward.shape, reward.dtype), ((self.NUM_ENVS,), np.dtype(np.float32)))
        for flags in (terminated, truncated):
            self.assertEqual((flags.shape, flags.dtype), ((self.NUM_ENVS,), np.dtype(np.bool_)))
        self.assertFalse(np.any(terminated & truncated))
        self.assertEqual(info["step"], 1)
        self.assertEqual(info["clip_id"].shape, (self.NUM_ENVS,))
        self.assertEqual(info["frame"].shape, (self.NUM_ENVS,))
        self.assertEqual(info["part_error"].shape, (self.NUM_ENVS, 5))
        self.assertEqual(info["max_body_error"].shape, (self.NUM_ENVS,))
        self.assertEqual(info["mean_body_error"].shape, (self.NUM_ENVS,))
        self.assertEqual(info["reward_terms"].shape, (self.NUM_ENVS, len(env.reward_terms)))
        self.assertNotIn("amp_obs", info)  # amp_obs="omit" by default
        self.assertTrue(all(0 <= c < len(info["clip_names"]) for c in info["clip_id"]))
        with self.assertRaisesRegex(ValueError, "shape"):
            env.step(np.zeros((self.NUM_ENVS + 1, 69), np.float32))

    def test_reset_seed_is_reproducible(self):
        env = self.make(motions=["deepmimic_walk", "deepmimic_run"])
        obs_a, info_a = env.reset(seed=7)
        obs_a, frame_a = obs_a.copy(), info_a["frame"].copy()
        env.reset(seed=8)
        obs_b, info_b = env.reset(seed=7)
        np.testing.assert_array_equal(obs_a, obs_b)
        np.testing.assert_array_equal(frame_a, info_b["frame"])

    def test_same_step_autoreset(self):
        # Episodes of 3 steps end by truncation at steps 3, 6, ...; the ended env's row already
        # holds the next episode's first observation, and final_info describes the ended one.
        env = self.make(max_episode_steps=3, termination="none", action_mode="residual",
                        motions=["deepmimic_walk"])
        _, info = env.reset(seed=0)
        start_frames = info["frame"].copy()
        zeros = np.zeros(env.action_space.shape, np.float32)
        for step in range(1, 7):
            obs, reward, terminated, truncated, info = env.step(zeros)
            self.assertFalse(terminated.any())
            if step % 3:
                self.assertFalse(truncated.any(), f"step {step}")
                self.assertNotIn("final_info", info)
                if step == 1:
                    np.testing.assert_array_equal(info["frame"], start_frames + 1)
                continue
            self.assertTrue(truncated.all(), f"step {step}")
            np.testing.assert_array_equal(info["_final_info"], truncated)
            final = info["final_info"]
            self.assertEqual(set(final), {"clip_id", "frame", "max_body_error", "mean_body_error", "part_error",
                                          "end_cause"})
            np.testing.assert_array_equal(final["end_cause"], np.full(env.num_envs, modskill_pb2.END_CAUSE_TIME))
            self.assertNotIn("final_obs", info)  # the server does not send the ended episode's last obs
            if step == 3:
                np.testing.assert_array_equal(final["frame"], start_frames + 3)
            self.assertTrue(np.isfinite(obs).all())
        self.assertEqual(info["step"], 6)

    def test_close_and_context_manager(self):
        with modskill.VectorEnv(SERVER, num_envs=2) as env:
            env.reset()
            session = env.session
        self.assertTrue(env.closed)
        self.assertTrue(session.closed)
        env.close()  # idempotent
        with self.assertRaisesRegex(RuntimeError, "closed"):
            env.step(np.zeros((2, 69), np.float32))
        with self.assertRaisesRegex(RuntimeError, "closed"):
            env.reset()

    def test_shares_a_client(self):
        with modskill.Client(SERVER) as client:
            with modskill.VectorEnv(client, num_envs=2, part_layout="2part") as env:
                _, info = env.reset()
                self.assertEqual(len(info["parts"]), 2)
            client.describe()  # the env left the client open

    def test_bad_arguments(self):
        with self.assertRaisesRegex(ValueError, "num_envs"):
            modskill.VectorEnv(SERVER, num_envs=0)
        env = self.make()
        with self.assertRaisesRegex(ValueError, "options"):
            env.reset(options={"x": 1})


if __name__ == "__main__":
    unittest.main()
