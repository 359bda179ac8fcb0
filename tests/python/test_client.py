"""Tests of the Python client (client/python/modskill) and its examples against a live server.

Run by tests/python/run_python_tests.sh, which starts a server and sets:
  MODSKILL_SERVER            host:port of the server (tests that need it skip without it)
  MODSKILL_TEST_CHECKPOINT   a zero-policy checkpoint written by make_test_policy
  MODSKILL_SERVER_BINARY     the server binary (for the token test, which starts its own server)
  MODSKILL_TEST_WORK_DIR     a scratch directory removed afterwards
and PYTHONPATH=client/python.
"""

import dataclasses
import os
import socket
import subprocess
import tempfile
import time
import unittest

import grpc
import numpy as np

import modskill
from modskill import tensors
from modskill.v1 import modskill_pb2 as pb

REPO_DIR = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
EXAMPLES_DIR = os.path.join(REPO_DIR, "client", "python", "examples")
SERVER = os.environ.get("MODSKILL_SERVER", "")
CHECKPOINT = os.environ.get("MODSKILL_TEST_CHECKPOINT", "")
SERVER_BINARY = os.environ.get("MODSKILL_SERVER_BINARY", "")
PYTHON = "/usr/bin/python3"

PART_ACTION_SIZES = {"L_Leg": 12, "R_Leg": 12, "Torso": 15, "L_Arm": 15, "R_Arm": 15}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def work_dir() -> str:
    path = os.environ.get("MODSKILL_TEST_WORK_DIR") or tempfile.gettempdir()
    return tempfile.mkdtemp(prefix="test_client.", dir=path)


class TensorTest(unittest.TestCase):
    """Wire conversions; no server needed."""

    def test_round_trip(self):
        for array in (np.arange(6, dtype=np.float32).reshape(2, 3), np.array([1, -2, 3], np.int32),
                      np.array([0, 1, 255], np.uint8), np.zeros((4, 0), np.float32)):
            decoded = tensors.decode(tensors.encode(array))
            self.assertEqual(decoded.dtype, array.dtype)
            np.testing.assert_array_equal(decoded, array)

    def test_little_endian_on_the_wire(self):
        tensor = tensors.encode(np.array([1.0], dtype=">f4"))  # big-endian input is converted
        self.assertEqual(tensor.data, np.array([1.0], "<f4").tobytes())
        self.assertEqual(list(tensor.shape), [1])
        self.assertEqual(tensor.dtype, pb.FLOAT32)

    def test_step_result_has_every_proto_field(self):
        # The per-env result fields are listed in the proto and here: this fails when they drift.
        wire = {field.name for field in pb.StepResult.DESCRIPTOR.fields}
        python = {field.name for field in dataclasses.fields(modskill.StepResult)}
        self.assertEqual(wire - python - set(modskill.StepResult.SESSION_FIELDS), set())
        self.assertEqual(python - wire, set())

    def test_bad_tensors_raise(self):
        with self.assertRaisesRegex(ValueError, "needs 12"):
            tensors.decode(pb.Tensor(shape=[3], dtype=pb.FLOAT32, data=b"\0" * 8), "obs")
        with self.assertRaisesRegex(ValueError, "DTYPE_UNSPECIFIED"):
            tensors.decode(pb.Tensor(shape=[1], data=b"\0"))
        with self.assertRaisesRegex(ValueError, "float64"):
            tensors.encode(np.zeros(2))


@unittest.skipUnless(SERVER, "MODSKILL_SERVER is not set (run tests/python/run_python_tests.sh)")
class ClientTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.client = modskill.Client(SERVER, timeout=10)

    @classmethod
    def tearDownClass(cls):
        cls.client.close()

    def test_describe(self):
        spec = self.client.describe()
        self.assertEqual(spec.obs_size, 934)
        self.assertEqual(spec.action_size, 69)
        self.assertEqual(spec.part_layout, "5part")
        self.assertIn("5part", spec.part_layouts)
        self.assertEqual({p.name: p.action_size for p in spec.parts}, PART_ACTION_SIZES)
        self.assertEqual([p.action_size for p in spec.parts], [12, 12, 15, 15, 15])
        # Part slices tile the observation and the action, in order, without gaps.
        obs_end = action_end = 0
        for part in spec.parts:
            self.assertEqual(part.obs.start, obs_end, part.name)
            self.assertEqual(part.action.start, action_end, part.name)
            self.assertGreater(part.obs_size, 0)
            obs_end, action_end = part.obs.stop, part.action.stop
        self.assertEqual(obs_end, spec.obs_size)
        self.assertEqual(action_end, spec.action_size)
        self.assertEqual(spec.self_obs_size + spec.task_obs_size, spec.obs_size)
        # One proprioceptive slice per body, inside the part's columns, adding up to self_obs_size.
        for part in spec.parts:
            self.assertEqual(len(part.self_obs), len(part.bodies), part.name)
            for s in part.self_obs:
                self.assertTrue(part.obs.start <= s.start < s.stop <= part.obs.stop, part.name)
        self.assertEqual(sum(s.stop - s.start for p in spec.parts for s in p.self_obs), spec.self_obs_size)
        self.assertEqual(len(spec.body_names), 24)
        self.assertEqual(sorted(b for p in spec.parts for b in p.bodies), sorted(spec.body_names))
        self.assertEqual(len(spec.joint_names), 69)
        self.assertEqual(spec.action_offset.shape, (69,))
        self.assertEqual(spec.action_scale.shape, (69,))
        self.assertAlmostEqual(spec.control_dt, 1 / 30, places=6)
        # The server's default physics: 4 substeps of position servos at their own gains.
        self.assertAlmostEqual(spec.physics.physics_dt, 1 / 120, places=9)
        self.assertEqual(spec.physics.pd_mode, "position_implicit")
        self.assertEqual(spec.physics.pd_gain_scale, 1.0)
        self.assertFalse(spec.physics.damp_to_reference_rate)
        self.assertEqual(len(spec.reward_terms), 5)
        self.assertEqual(spec.num_motions, 20)

    def test_task_session(self):
        with self.client.session(2, seed=3, motions=["deepmimic_walk"], action_mode="residual", task="steer",
                                 task_settings={"min_speed": 1.0, "max_speed": 1.5}) as session:
            spec = session.spec
            self.assertEqual(spec.task, "steer")
            # Steer observes what tracking does (its base motion as the reference), then the goal.
            self.assertEqual(spec.obs_size, spec.self_obs_size + spec.task_obs_size)
            self.assertEqual(spec.goal_obs, slice(spec.obs_size - 3, spec.obs_size))
            self.assertEqual(session.initial.obs.shape, (2, spec.obs_size))
            speeds = session.initial.obs[:, spec.obs_size - 1]
            self.assertTrue(np.all((speeds >= 1.0) & (speeds <= 1.5)), speeds)
            result = session.step(np.zeros((2, spec.action_size), np.float32))
            self.assertEqual(result.reward_terms.shape, (2, 3))
        self.assertEqual(self.client.describe().tasks["strike"], (15, ("strike", "approach", "energy")))
        with self.assertRaises(modskill.ServerError) as caught:
            self.client.session(2, task="sterr")
        self.assertEqual(caught.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("sterr", caught.exception.message)

    def test_looping_clip_runs_past_its_end(self):
        frames = 38  # deepmimic_walk
        with self.client.session(1, seed=2, motions=["deepmimic_walk"], termination="none", action_mode="residual",
                                 loop_clips=True, max_episode_steps=60) as session:
            seen = []
            for _ in range(59):
                result = session.step(np.zeros((1, session.spec.action_size), np.float32))
                self.assertFalse(result.done[0])
                seen.append(int(result.frame[0]))
            self.assertGreater(len(seen), frames, "ran past the clip's end")
            self.assertNotIn(0, seen[seen.index(frames - 1):], "looped on at frame 1")
            self.assertTrue(session.step(np.zeros((1, session.spec.action_size), np.float32)).done[0])
        with self.assertRaises(modskill.ServerError) as caught:
            self.client.session(1, task="steer", loop_clips=True)
        self.assertEqual(caught.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("loop_clips", caught.exception.message)

    def test_family_session_varies_gravity_per_env(self):
        self.assertIn("gravity", self.client.describe().family_parameters)
        with self.client.session(2, seed=1, motions=["deepmimic_jump"], family={"gravity": (4, 14), "jump_height": 1.1}
                                 ) as session:
            spec = session.spec
            self.assertEqual(spec.family, {"gravity": (4.0, 14.0), "jump_height": (1.1, 1.1)})
            self.assertEqual(spec.time_warp_action, spec.action_size - 1)
            self.assertEqual(session.initial.family_params.shape, (2, 2))
            actions = np.zeros((2, spec.action_size), np.float32)
            actions[:, spec.time_warp_action] = -1.0  # slower than the clip: exp(-1.5) frames a step
            result = session.step(actions, family_params=np.array([[4, 1.1], [14, 1.1]], np.float32))
            np.testing.assert_allclose(result.phase_step, np.exp(-1.5), rtol=1e-5)
            self.assertEqual(result.spike_reward.shape, (2,))
            ended = np.zeros(2, bool)
            for _ in range(300):
                result = session.step(np.zeros((2, spec.action_size), np.float32))
                for i in np.flatnonzero(result.done):
                    self.assertGreater(result.fitness[i], 0.0)
                ended |= result.done
                if ended.all():
                    break
            self.assertTrue(ended.all())
            # Each env's new episode runs on the parameters it was given.
            np.testing.assert_allclose(result.family_params, [[4, 1.1], [14, 1.1]], rtol=1e-6)
            with self.assertRaises(modskill.ServerError) as caught:
                session.step(actions, family_params=np.array([[20, 1.1], [5, 1.1]], np.float32))
            self.assertEqual(caught.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
            self.assertIn("gravity", caught.exception.message)
        with self.assertRaises(modskill.ServerError) as caught:
            self.client.session(1, motions=["deepmimic_jump"], family={"no_such_param": (0, 1)})
        self.assertEqual(caught.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("no_such_param", caught.exception.message)

    def test_describe_other_layout_and_unknown_layout(self):
        spec = self.client.describe("3part")
        self.assertEqual(spec.part_layout, "3part")
        self.assertEqual(len(spec.parts), 3)
        self.assertEqual(spec.action_size, 69)
        with self.assertRaises(modskill.ServerError) as caught:
            self.client.describe("no_such_layout")
        self.assertEqual(caught.exception.code, grpc.StatusCode.NOT_FOUND)
        self.assertIn("no_such_layout", caught.exception.message)

    def test_motions(self):
        motions = self.client.motions()
        self.assertEqual(len(motions), 20)
        names = [m["name"] for m in motions]
        self.assertIn("deepmimic_walk", names)
        self.assertEqual(len(set(names)), 20)
        walk = motions[names.index("deepmimic_walk")]
        self.assertGreater(walk["frames"], 1)
        self.assertGreater(walk["fps"], 0)
        self.assertIsInstance(walk["label"], str)

    def test_session(self):
        n = 3
        with self.client.session(n, seed=7) as session:
            spec = session.spec
            self.assertEqual(session.num_envs, n)
            self.assertTrue(session.session_id)
            self.assertEqual(len(session.clip_names), 20)
            initial = session.initial
            self.assertEqual(initial.step, 0)
            self.assertEqual(initial.obs.shape, (n, 934))
            self.assertEqual(initial.obs.dtype, np.float32)
            self.assertEqual(initial.amp_obs.shape, (n, spec.amp_obs_size))
            self.assertTrue(np.isfinite(initial.obs).all())
            for step in range(1, 6):
                result = session.step(np.zeros((n, spec.action_size), np.float32))
                self.assertEqual(result.step, step)
                self.assertEqual(result.obs.shape, (n, 934))
                self.assertTrue(np.isfinite(result.obs).all())
                self.assertEqual(result.reward.shape, (n,))
                self.assertTrue(((result.reward >= -2) & (result.reward <= 1)).all(), result.reward)
                self.assertEqual(result.reward_terms.shape, (n, len(spec.reward_terms)))
                self.assertEqual(result.done.dtype, np.bool_)
                self.assertEqual(result.truncated.dtype, np.bool_)
                self.assertEqual(result.clip_id.dtype, np.int32)
                self.assertTrue(((result.clip_id >= 0) & (result.clip_id < len(session.clip_names))).all())
                self.assertTrue((result.frame >= 0).all())
                self.assertTrue((result.mean_body_error <= result.max_body_error + 1e-6).all())
                self.assertEqual(result.part_error.shape, (n, len(spec.parts)))
                self.assertTrue((result.part_error <= result.max_body_error[:, None] + 1e-6).all())
            self.assertIs(session.last, result)
            stats = self.client.stats()
            open_sessions = {s["session_id"]: s for s in stats["sessions"]}
            self.assertIn(session.session_id, open_sessions)
            self.assertEqual(open_sessions[session.session_id]["num_envs"], n)
            self.assertEqual(open_sessions[session.session_id]["steps"], 5)
            self.assertGreaterEqual(stats["active_sessions"], 1)
            # part_obs slices the observation by body part.
            legs = session.part_obs(result.obs, "L_Leg")
            self.assertEqual(legs.shape, (n, spec.part("L_Leg").obs_size))
            np.testing.assert_array_equal(legs, result.obs[:, spec.part("L_Leg").obs])
            np.testing.assert_array_equal(modskill.part_obs(spec, result.obs, "R_Arm"), result.obs[:, 739:934])
            with self.assertRaisesRegex(KeyError, "no_such_part"):
                session.part_obs(result.obs, "no_such_part")
            # Failure reports go to this session's sampler.
            state = session.report_failures([{"clip": "deepmimic_walk", "frame": 4, "part_errors": [0.1] * 5}])
            self.assertEqual(state["session_id"], session.session_id)
            walk = next(c for c in state["clips"] if c["clip"] == "deepmimic_walk")
            self.assertEqual(walk["failures"], 1)
            self.assertEqual(walk["last_failed_frame"], 4)
        self.assertTrue(session.closed)
        # The server forgets the session once the stream ends (it may take a moment).
        for _ in range(50):
            if session.session_id not in {s["session_id"] for s in self.client.stats()["sessions"]}:
                break
            time.sleep(0.05)
        else:
            self.fail(f"session {session.session_id} still listed after close")
        with self.assertRaisesRegex(RuntimeError, "closed"):
            session.step(np.zeros((n, 69), np.float32))

    def test_session_options(self):
        with self.client.session(2, motions=["deepmimic_walk", "deepmimic_run"], amp_obs="newest",
                                 part_layout="3part", termination="none", max_episode_steps=3) as session:
            self.assertEqual(session.clip_names, ["deepmimic_walk", "deepmimic_run"])
            self.assertEqual(session.spec.part_layout, "3part")
            self.assertEqual(session.initial.amp_obs.shape, (2, session.spec.amp_obs_per_frame))
            done = np.zeros(2, bool)
            for _ in range(3):
                done |= session.step(np.zeros((2, 69), np.float32)).done
            self.assertTrue(done.all())  # max_episode_steps=3 ends every episode
        with self.client.session(1, amp_obs="omit") as session:
            self.assertIsNone(session.initial.amp_obs)
        with self.assertRaisesRegex(ValueError, "amp_obs"):
            self.client.session(1, amp_obs="sometimes")
        with self.assertRaisesRegex(ValueError, "termination"):
            self.client.session(1, termination="never")
        # energy_weight=0: the energy column is 0 and the rest of the reward unchanged.
        zeros = np.zeros((2, 69), np.float32)
        kwargs = dict(seed=3, termination="none")  # no resets: every row is past the energy-free steps
        with self.client.session(2, energy_weight=0.0, **kwargs) as off, self.client.session(2, **kwargs) as paper:
            for _ in range(5):
                unpaid, paid = off.step(zeros), paper.step(zeros)
            self.assertTrue((unpaid.reward_terms[:, -1] == 0).all())
            self.assertTrue((paid.reward_terms[:, -1] < 0).all())
            np.testing.assert_allclose(unpaid.reward, paid.reward - paid.reward_terms[:, -1], atol=1e-5)
        with self.assertRaises(modskill.ServerError) as caught:
            with self.client.session(1, energy_weight=-1.0) as session:
                session.step(np.zeros((1, 69), np.float32))
        self.assertIn("energy_weight", caught.exception.message)
        # imitation_kernels={"pos": 400}: the position term is w (term / w)^4, the others unchanged.
        with self.client.session(2, imitation_kernels={"pos": 400}, **kwargs) as steep, \
                self.client.session(2, **kwargs) as phc:
            for _ in range(5):
                sharp, soft = steep.step(zeros), phc.step(zeros)
            w_pos = 0.5
            np.testing.assert_allclose(sharp.reward_terms[:, 0], w_pos * (soft.reward_terms[:, 0] / w_pos) ** 4, atol=1e-5)
            np.testing.assert_array_equal(sharp.reward_terms[:, 1:], soft.reward_terms[:, 1:])
        with self.assertRaises(modskill.ServerError) as caught:
            with self.client.session(1, imitation_kernels={"rot": -2.0}) as session:
                session.step(np.zeros((1, 69), np.float32))
        self.assertIn("imitation_kernels.rot", caught.exception.message)
        # reference_frames=3: three task blocks per body, the first the one-frame session's.
        with self.client.session(1, reference_frames=3, **kwargs) as ahead, \
                self.client.session(1, **kwargs) as next_only:
            self.assertEqual(ahead.spec.reference_frames, 3)
            self.assertEqual(ahead.spec.obs_size, 358 + 3 * 576)
            first_body = ahead.spec.parts[0].self_obs[0]  # its self features, then its task blocks
            block0 = slice(first_body.start, first_body.stop + 24)
            np.testing.assert_array_equal(ahead.initial.obs[0, block0], next_only.initial.obs[0, block0])
        with self.assertRaises(modskill.ServerError) as caught:
            with self.client.session(1, reference_frames=2, loop_clips=True) as session:
                session.step(np.zeros((1, 69), np.float32))
        self.assertIn("reference_frames", caught.exception.message)

    def test_action_modes_and_termination_distance(self):
        self.assertEqual(list(self.client.describe().action_modes), ["absolute", "residual"])
        zeros = np.zeros((2, 69), np.float32)
        kwargs = dict(motions=["deepmimic_walk"], seed=4, termination_distance=100.0)
        # Zero residual actions track the reference open loop; zero absolute ones fall.
        with self.client.session(2, action_mode="residual", termination_bodies="no_feet", **kwargs) as residual, \
                self.client.session(2, **kwargs) as absolute:
            for _ in range(6):
                tracked = residual.step(zeros).mean_body_error
                fell = absolute.step(zeros).mean_body_error
            self.assertLess(tracked.mean(), 0.5 * fell.mean())
            # A tighter distance from this step on: the next steps terminate.
            ended = np.zeros(2, bool)
            for _ in range(3):
                result = absolute.step(zeros, termination_distance=0.001)
                ended |= result.done & ~result.truncated
            self.assertTrue(ended.all())
        with self.assertRaises(modskill.ServerError) as caught:
            with self.client.session(1, action_mode="residual", residual_scale=-1.0) as session:
                session.step(np.zeros((1, 69), np.float32))
        self.assertIn("residual_scale", caught.exception.message)
        with self.assertRaisesRegex(ValueError, "action_mode"):
            self.client.session(1, action_mode="sideways")
        # The zero-policy checkpoint was made in absolute mode: insisting on residual is refused.
        with self.assertRaises(modskill.ServerError) as caught:
            self.client.rollout(CHECKPOINT, clips=["deepmimic_walk"], action_mode="residual")
        self.assertEqual(caught.exception.code, grpc.StatusCode.FAILED_PRECONDITION)
        self.assertIn("action_mode", caught.exception.message)

    def test_reward_parts(self):
        # The same seed and actions: the arms' reward differs from the whole body's, the errors do not.
        actions = np.random.default_rng(3).uniform(-1, 1, (4, 69)).astype(np.float32)
        kwargs = dict(motions=["deepmimic_walk"], seed=9, termination="none", action_mode="residual")
        with self.client.session(4, **kwargs) as whole, \
                self.client.session(4, reward_parts=["R_Arm", "L_Arm"], **kwargs) as arms, \
                self.client.session(4, reward_parts=["R_Arm", "L_Arm"], reward_relative_to_root=True,
                                    **kwargs) as arms_in_root:
            for _ in range(3):
                a, b, c = whole.step(actions), arms.step(actions), arms_in_root.step(actions)
            np.testing.assert_allclose(a.mean_body_error, b.mean_body_error)
            np.testing.assert_allclose(a.mean_body_error, c.mean_body_error)
            self.assertFalse(np.allclose(a.reward, b.reward))
            self.assertFalse(np.allclose(b.reward, c.reward))
        with self.assertRaises(modskill.ServerError) as caught:
            self.client.session(1, task="steer", reward_relative_to_root=True)
        self.assertEqual(caught.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("reward_relative_to_root", caught.exception.message)
        with self.assertRaises(modskill.ServerError) as caught:
            self.client.session(1, reward_parts=["R_Arm", "Tail"])
        self.assertEqual(caught.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("reward_parts[1]: 'Tail'", caught.exception.message)

    def test_wrong_actions_raise_value_error(self):
        with self.client.session(2) as session:
            with self.assertRaises(ValueError) as caught:
                session.step(np.zeros((3, 69), np.float32))
            self.assertIn("[3, 69]", str(caught.exception))
            self.assertIn("[2, 69]", str(caught.exception))
            with self.assertRaisesRegex(ValueError, r"\[2, 68\]"):
                session.step(np.zeros((2, 68), np.float32))
            with self.assertRaisesRegex(ValueError, "dtype"):
                session.step(np.zeros((2, 69), np.int32))
            bad = np.zeros((2, 69), np.float32)
            bad[1, 5] = np.nan
            with self.assertRaisesRegex(ValueError, r"\[1, 5\]"):
                session.step(bad)
            # Nothing was sent: the session still steps, and float64 is converted.
            self.assertEqual(session.step(np.zeros((2, 69))).step, 1)

    def test_unknown_clip_raises_server_error(self):
        with self.assertRaises(modskill.ServerError) as caught:
            self.client.session(2, motions=["deepmimic_walk", "no_such_clip_xyz"])
        error = caught.exception
        self.assertEqual(error.code, grpc.StatusCode.NOT_FOUND)
        self.assertIn("no_such_clip_xyz", error.message)
        self.assertIn("no_such_clip_xyz", str(error))
        self.assertIn("NOT_FOUND", str(error))

    def test_server_errors_keep_code_and_message(self):
        with self.assertRaises(modskill.ServerError) as caught:
            self.client.session(0)
        self.assertEqual(caught.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("num_envs", caught.exception.message)
        with self.assertRaises(modskill.ServerError) as caught:
            self.client.report_failures("no_such_session", [{"clip": "deepmimic_walk"}])
        self.assertEqual(caught.exception.code, grpc.StatusCode.NOT_FOUND)
        self.assertIn("no_such_session", caught.exception.message)

    @unittest.skipUnless(CHECKPOINT, "MODSKILL_TEST_CHECKPOINT is not set")
    def test_rollout_with_frames(self):
        results = self.client.rollout(CHECKPOINT, clips=["deepmimic_walk"], frames=True)
        self.assertEqual(len(results), 1)
        walk = results[0]
        self.assertEqual(walk.clip, "deepmimic_walk")
        self.assertGreater(walk.steps, 0)
        for value in (walk.g_mpjpe_mm, walk.mpjpe_mm, walk.acc_error_mm, walk.vel_error_mm):
            self.assertTrue(np.isfinite(value) and value >= 0, value)
        self.assertEqual(walk.body_error_mm.shape, (24,))
        self.assertEqual(walk.part_error_mm.shape, (5,))
        T = walk.sim_body_pos.shape[0]
        self.assertIn(T, (walk.steps, walk.steps + 1))
        self.assertEqual(walk.sim_body_pos.shape, (T, 24, 3))
        self.assertEqual(walk.ref_body_pos.shape, (T, 24, 3))
        self.assertEqual(walk.sim_body_pos.dtype, np.float32)
        self.assertEqual(walk.frames.shape, (T,))
        self.assertTrue((np.diff(walk.frames) >= 0).all())
        self.assertTrue(np.isfinite(walk.sim_body_pos).all() and np.isfinite(walk.ref_body_pos).all())
        errors = walk.body_errors()
        self.assertEqual(errors.shape, (T, 24))
        # The streamed positions agree with the server's global error (mean over steps and bodies).
        self.assertLess(abs(errors.mean() * 1000 - walk.g_mpjpe_mm), 0.25 * walk.g_mpjpe_mm + 5)

    @unittest.skipUnless(CHECKPOINT, "MODSKILL_TEST_CHECKPOINT is not set")
    def test_rollout_from_bytes_and_errors(self):
        with open(CHECKPOINT, "rb") as f:
            data = f.read()
        results = self.client.rollout(checkpoint_bytes=data, clips=["deepmimic_run", "deepmimic_walk"])
        self.assertEqual([r.clip for r in results], ["deepmimic_run", "deepmimic_walk"])
        self.assertIsNone(results[0].sim_body_pos)
        by_path = self.client.rollout(server_checkpoint=CHECKPOINT, clips=["deepmimic_run"])
        self.assertAlmostEqual(by_path[0].g_mpjpe_mm, results[0].g_mpjpe_mm, places=3)
        with self.assertRaises(modskill.ServerError) as caught:
            self.client.rollout(CHECKPOINT, clips=["no_such_clip_xyz"])
        self.assertEqual(caught.exception.code, grpc.StatusCode.NOT_FOUND)
        self.assertIn("no_such_clip_xyz", caught.exception.message)
        with self.assertRaises(modskill.ServerError):
            self.client.rollout(checkpoint_bytes=b"not a checkpoint", clips=["deepmimic_walk"])
        with self.assertRaisesRegex(ValueError, "exactly one"):
            self.client.rollout(CHECKPOINT, checkpoint_bytes=data)

    def test_connect_error(self):
        start = time.monotonic()
        with self.assertRaises(modskill.ConnectError) as caught:
            modskill.Client(f"127.0.0.1:{free_port()}", timeout=0.5)
        self.assertLess(time.monotonic() - start, 5)
        self.assertEqual(caught.exception.code, grpc.StatusCode.UNAVAILABLE)
        self.assertIsInstance(caught.exception, modskill.ServerError)


@unittest.skipUnless(SERVER_BINARY and os.path.exists(SERVER_BINARY), "MODSKILL_SERVER_BINARY is not set")
class TokenTest(unittest.TestCase):
    """A second server with --auth_token_file: the client sends the bearer token."""

    def test_token(self):
        directory = work_dir()
        token_file = os.path.join(directory, "token")
        with open(token_file, "w") as f:
            f.write("s3cret-token\n")
        port = free_port()
        log = open(os.path.join(directory, "server.log"), "wb")
        server = subprocess.Popen([SERVER_BINARY, f"--port={port}", f"--auth_token_file={token_file}"],
                                  stdout=log, stderr=subprocess.STDOUT)
        try:
            address = f"127.0.0.1:{port}"
            client = None
            for _ in range(40):
                try:
                    client = modskill.Client(address, token_file=token_file, timeout=0.25)
                    break
                except modskill.ConnectError:
                    self.assertIsNone(server.poll(), "the server exited")
            self.assertIsNotNone(client, "the token server did not start")
            with client:
                self.assertEqual(client.describe().obs_size, 934)
            for token in (None, "wrong"):
                with modskill.Client(address, token=token) as anonymous:
                    with self.assertRaises(modskill.ServerError) as caught:
                        anonymous.motions()
                    self.assertEqual(caught.exception.code, grpc.StatusCode.UNAUTHENTICATED)
            with self.assertRaisesRegex(ValueError, "at most one"):
                modskill.Client(address, token="a", token_file=token_file)
        finally:
            server.terminate()
            try:
                server.wait(timeout=10)
            except subprocess.TimeoutExpired:
                server.kill()
                server.wait()
            log.close()


@unittest.skipUnless(SERVER, "MODSKILL_SERVER is not set (run tests/python/run_python_tests.sh)")
class ExamplesTest(unittest.TestCase):
    def run_example(self, name, *args):
        # As documented, from a fresh clone: no PYTHONPATH (examples/_path.py finds client/python).
        env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
        env["MPLBACKEND"] = "Agg"
        process = subprocess.run([PYTHON, os.path.join(EXAMPLES_DIR, name), "--server", SERVER, *args],
                                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env, timeout=60)
        output = process.stdout.decode("utf-8", "replace")
        self.assertEqual(process.returncode, 0, f"{name} failed:\n{output}")
        return output

    def test_print_spec(self):
        output = self.run_example("print_spec.py")
        self.assertIn("934", output)
        self.assertIn("L_Leg", output)
        self.assertIn("deepmimic_walk", output)
        self.assertIn("20 motions", output)

    @unittest.skipUnless(CHECKPOINT, "MODSKILL_TEST_CHECKPOINT is not set")
    def test_rollout_plot(self):
        out = os.path.join(work_dir(), "error.png")
        output = self.run_example("rollout_plot.py", "--checkpoint", CHECKPOINT, "--clip", "deepmimic_walk",
                                  "--out", out)
        self.assertIn("deepmimic_walk", output)
        self.assertTrue(os.path.exists(out), output)
        self.assertGreater(os.path.getsize(out), 1000)
        with open(out, "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")

    def test_random_actions(self):
        output = self.run_example("random_actions.py", "--num_envs", "4", "--steps", "5")
        self.assertIn("steps/s", output)

    def test_train_numpy(self):
        output = self.run_example("train_numpy.py", "--iterations", "2", "--directions", "1",
                                  "--envs_per_candidate", "2", "--horizon", "5")
        self.assertIn("iteration 2: return", output)
        self.assertRegex(output, r"final return -?[0-9.]+ over 6 envs x 5 steps")


if __name__ == "__main__":
    unittest.main()
