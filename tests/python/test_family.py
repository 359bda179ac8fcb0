"""Motor-skill families from Python (issue 14): Client.query_family and Client.rollout with
family_params against the server run_python_tests.sh starts, with the shipped jump family
(data/policies/family_jump_gravity, trained by bench/family_bench.sh over gravity 4-14 m/s^2).
"""

import os
import unittest

import grpc
import numpy as np

import modskill

REPO_DIR = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SERVER = os.environ.get("MODSKILL_SERVER", "")
AFFINE = os.environ.get("MODSKILL_TEST_CHECKPOINT", "")
JUMP = os.path.join(REPO_DIR, "data", "policies", "family_jump_gravity", "policy.pt")


@unittest.skipUnless(SERVER, "MODSKILL_SERVER is not set (run tests/python/run_python_tests.sh)")
class FamilyTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.client = modskill.Client(SERVER)

    @classmethod
    def tearDownClass(cls):
        cls.client.close()

    def test_query_gives_the_ranges_p_of_a_and_the_nearest_elites(self):
        query = self.client.query_family(JUMP, {"gravity": 6.0}, nearest_elites=3)
        self.assertEqual(query.clip, "deepmimic_jump")
        self.assertEqual(query.ranges, {"gravity": (4.0, 14.0)})
        self.assertEqual(query.params, {"gravity": 6.0})
        np.testing.assert_allclose(query.normalized_params, [0.2])
        self.assertEqual(query.parameterization_columns[-1], "tau")
        self.assertEqual(query.parameterization.shape[1], len(query.parameterization_columns))
        self.assertTrue(np.all(np.isfinite(query.parameterization)))
        self.assertGreater(query.elites, 0)
        distances = [e["distance"] for e in query.nearest_elites]
        self.assertEqual(distances, sorted(distances))
        self.assertLessEqual(len(distances), 3)
        for elite in query.nearest_elites:
            self.assertAlmostEqual(elite["distance"], abs(elite["params"]["gravity"] - 6.0) / 10.0)
        # P(a) moves with a.
        other = self.client.query_family(JUMP, {"gravity": 13.0})
        self.assertGreater(np.abs(other.parameterization - query.parameterization).max(), 0)

    def test_rollout_at_a_parameter(self):
        (low,) = self.client.rollout(JUMP, family_params={"gravity": 5.0}, frames=True)
        self.assertEqual(low.clip, "deepmimic_jump")
        self.assertEqual(low.family["params"], {"gravity": 5.0})
        self.assertGreater(low.family["apex_height_m"], 0.5)
        self.assertGreaterEqual(low.family["flight_s"], 0.0)
        self.assertEqual(low.sim_body_pos.shape[0], low.steps + 1)
        (middle,) = self.client.rollout(JUMP)
        self.assertEqual(middle.family["params"], {"gravity": 9.0})
        # The shipped policy jumps higher and flies longer under lower gravity (0.60 s of flight
        # and a 1.22 m root apex at 5 m/s^2, none and 0.97 m at 14 when it was committed).
        (high,) = self.client.rollout(JUMP, family_params={"gravity": 14.0})
        self.assertGreater(low.family["apex_height_m"], high.family["apex_height_m"] + 0.1)
        self.assertGreater(low.family["flight_s"], high.family["flight_s"] + 0.2)

    def test_bad_family_requests_are_named(self):
        with self.assertRaises(modskill.ServerError) as outside:
            self.client.rollout(JUMP, family_params={"gravity": 30.0})
        self.assertEqual(outside.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("family_params[gravity]", str(outside.exception))
        with self.assertRaises(modskill.ServerError) as unknown:
            self.client.query_family(JUMP, {"leg_length": 1.0})
        self.assertIn("leg_length", str(unknown.exception))
        if AFFINE:
            with self.assertRaises(modskill.ServerError) as tracker:
                self.client.query_family(AFFINE)
            self.assertEqual(tracker.exception.code, grpc.StatusCode.FAILED_PRECONDITION)


if __name__ == "__main__":
    unittest.main()
