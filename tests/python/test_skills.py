"""Skill composition from Python (issue 13): Client.record_skills and Client.compose against the
server run_python_tests.sh starts, with the shipped walk tracker (data/policies/walk_small,
exported with skills() and act_with_z()) and the zero affine policy (which has no skills).
"""

import os
import unittest

import numpy as np

import modskill

REPO_DIR = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SERVER = os.environ.get("MODSKILL_SERVER", "")
AFFINE = os.environ.get("MODSKILL_TEST_CHECKPOINT", "")
WALK = os.path.join(REPO_DIR, "data", "policies", "walk_small", "policy.pt")
STEPS = 12


@unittest.skipUnless(SERVER, "MODSKILL_SERVER is not set (run tests/python/run_python_tests.sh)")
class SkillsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.client = modskill.Client(SERVER)

    @classmethod
    def tearDownClass(cls):
        cls.client.close()

    def test_recorded_z_is_on_the_sphere(self):
        (walk,) = self.client.record_skills(WALK, ["deepmimic_walk"], max_steps_per_clip=STEPS)
        self.assertEqual(walk.skill_z.shape[0], walk.steps + 1)
        self.assertEqual(walk.skill_z.shape[1], 5)
        self.assertTrue(np.all(np.isnan(walk.skill_z[-1])))
        norms = np.linalg.norm(walk.skill_z[:-1], axis=-1)
        np.testing.assert_allclose(norms, 1.0, atol=1e-5)

    def test_composing_a_clip_with_itself_is_the_plain_rollout(self):
        (plain,) = self.client.rollout(WALK, clips=["deepmimic_walk"], frames=True, max_steps_per_clip=STEPS)
        composed = self.client.compose(WALK, "deepmimic_walk", "deepmimic_walk", "R_Arm", max_steps_per_clip=STEPS)
        self.assertEqual(composed.steps, plain.steps)
        self.assertEqual(composed.g_mpjpe_mm, plain.g_mpjpe_mm)
        np.testing.assert_array_equal(composed.sim_body_pos, plain.sim_body_pos)
        self.assertEqual(composed.composition["source_clip"], "deepmimic_walk")
        self.assertEqual(composed.composition["parts"], ["R_Arm"])
        self.assertEqual(composed.composition["held_steps"], 0)

    def test_swap_takes_the_source_z(self):
        (punch,) = self.client.record_skills(WALK, ["deepmimic_punch"], max_steps_per_clip=STEPS)
        swapped = self.client.compose(WALK, "deepmimic_walk", "deepmimic_punch", ["R_Arm", "L_Arm"],
                                      max_steps_per_clip=STEPS)
        rows = min(swapped.steps, punch.steps)
        np.testing.assert_array_equal(swapped.skill_z[:rows, 3:], punch.skill_z[:rows, 3:])
        blended = self.client.compose(WALK, "deepmimic_walk", "deepmimic_punch", "R_Arm", interpolate=True,
                                      max_steps_per_clip=STEPS)
        self.assertEqual(blended.composition["mode"], "INTERPOLATE")
        np.testing.assert_allclose(np.linalg.norm(blended.skill_z[:-1], axis=-1), 1.0, atol=1e-5)

    def test_bad_requests_name_the_field(self):
        with self.assertRaisesRegex(modskill.ServerError, r"composition\.parts\[0\]"):
            self.client.compose(WALK, "deepmimic_walk", "deepmimic_punch", "Tail", max_steps_per_clip=STEPS)
        with self.assertRaisesRegex(modskill.ServerError, r"composition\.source_clip"):
            self.client.compose(WALK, "deepmimic_walk", "no_such_clip", "R_Arm", max_steps_per_clip=STEPS)
        if AFFINE:
            with self.assertRaisesRegex(modskill.ServerError, "record_skills") as raised:
                self.client.record_skills(AFFINE, ["deepmimic_walk"], max_steps_per_clip=STEPS)
            self.assertEqual(raised.exception.code.name, "FAILED_PRECONDITION")


if __name__ == "__main__":
    unittest.main()
