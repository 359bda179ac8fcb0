"""Tests of modskill.viewer: the HTML viewer page written from Python.

Run by tests/python/run_python_tests.sh, which starts a server and sets (besides what
test_client.py reads) MODSKILL_BUILD_DIR, where the C++ CLI client/modskill-client is built: the
page Python writes for a rollout must hold the same scene as the one `modskill-client rollout
--html` writes for the same policy and clips. Tests without a server use a small hand-made spec.
"""

import base64
import contextlib
import filecmp
import json
import os
import re
import shutil
import subprocess
import tempfile
import unittest
from unittest import mock

import numpy as np

import modskill
import modskill.viewer
from modskill.v1 import modskill_pb2 as pb

REPO_DIR = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SERVER = os.environ.get("MODSKILL_SERVER", "")
CHECKPOINT = os.environ.get("MODSKILL_TEST_CHECKPOINT", "")
BUILD_DIR = os.environ.get("MODSKILL_BUILD_DIR", "")
CLIENT_BINARY = os.path.join(BUILD_DIR, "client", "modskill-client") if BUILD_DIR else ""
CLIPS = ["deepmimic_walk", "deepmimic_run"]
FAKE_THREE_JS = b"window.THREE = {};  // a stand-in for three.min.js\n"
SCENE_RE = re.compile(rb'<script id="modskill-scene" type="application/json">(.*?)</script>', re.S)


def scratch_dir(test: unittest.TestCase) -> str:
    path = tempfile.mkdtemp(prefix="test_viewer.", dir=os.environ.get("MODSKILL_TEST_WORK_DIR"))
    test.addCleanup(shutil.rmtree, path, True)
    return path


@contextlib.contextmanager
def three_js(path):
    with mock.patch.dict(os.environ, {"MODSKILL_THREE_JS": path}):
        yield


def fake_three_js(directory: str) -> str:
    path = os.path.join(directory, "three.min.js")
    with open(path, "wb") as f:
        f.write(FAKE_THREE_JS)
    return path


def read_scene(path: str) -> dict:
    with open(path, "rb") as f:
        match = SCENE_RE.search(f.read())
    assert match, f"{path}: no modskill-scene script element"
    return json.loads(match.group(1).decode("utf-8"))


def floats(text, shape) -> np.ndarray:
    return np.frombuffer(base64.b64decode(text), dtype="<f4").reshape(shape)


def tracks(clip: dict, num_bodies: int) -> dict:
    """role -> (pos [T, B, 3], rot [T, B, 4]) of a page clip."""
    T = clip["frames"]
    return {t["role"]: (floats(t["pos"], (T, num_bodies, 3)), floats(t["rot"], (T, num_bodies, 4)))
            for t in clip["tracks"]}


def expected_geom(g: modskill.BodyGeometry) -> dict:
    zero = lambda v: list(v) if v else [0.0, 0.0, 0.0]
    if g.shape == "sphere":
        return {"type": "sphere", "radius": g.radius, "center": zero(g.center)}
    if g.shape == "capsule":
        return {"type": "capsule", "radius": g.radius, "from": zero(g.segment_from), "to": zero(g.segment_to)}
    return {"type": "box", "half_extents": zero(g.half_extents), "center": zero(g.center)}


def small_spec() -> modskill.EnvSpec:
    """Three bodies, one of each shape."""
    geometry = [
        pb.BodyGeometry(parent=-1, shape=pb.BodyGeometry.SPHERE, radius=0.1, center=[0, 0, 0.05]),
        pb.BodyGeometry(parent=0, shape=pb.BodyGeometry.CAPSULE, radius=0.04, segment_from=[0, 0, 0],
                        segment_to=[0, 0, -0.3]),
        pb.BodyGeometry(parent=1, shape=pb.BodyGeometry.BOX, half_extents=[0.1, 0.05, 0.02], center=[0.05, 0, 0]),
    ]
    return modskill.EnvSpec.from_proto(pb.EnvSpec(body_names=["Pelvis", "L_Hip", "L_Ankle"], control_dt=0.05,
                                                  body_geometry=geometry))


def small_clip(name="walk", frames=4, **kwargs) -> modskill.viewer.ViewerClip:
    rng = np.random.default_rng(0)
    rot = np.zeros((frames, 3, 4), np.float32)
    rot[..., 0] = 1
    return modskill.viewer.ViewerClip(name=name, ref_pos=rng.normal(size=(frames, 3, 3)).astype(np.float32),
                                      ref_rot=rot, **kwargs)


def rollout_without_frames(clip="deepmimic_walk") -> modskill.ClipRollout:
    return modskill.ClipRollout(clip=clip, success=True, steps=3, g_mpjpe_mm=0, mpjpe_mm=0, acc_error_mm=0,
                                vel_error_mm=0, body_error_mm=np.zeros(3), part_error_mm=np.zeros(1))


class TemplateTest(unittest.TestCase):
    def test_package_template_is_a_copy_of_common(self):
        source = os.path.join(REPO_DIR, "common", "viewer", "viewer_page.html")
        copy = os.path.join(REPO_DIR, "client", "python", "modskill", "viewer_page.html")
        self.assertTrue(filecmp.cmp(source, copy, shallow=False),
                        f"{copy} differs from {source}: the Python package ships its own copy of the page "
                        "template (an installed package cannot reach common/); run "
                        "cp common/viewer/viewer_page.html client/python/modskill/viewer_page.html")


class OfflineViewerTest(unittest.TestCase):
    """write_clips_html / write_html on a hand-made spec; no server."""

    def setUp(self):
        self.dir = scratch_dir(self)
        self.fake = fake_three_js(self.dir)
        self.spec = small_spec()

    def test_reference_only_clip_and_escaping(self):
        path = os.path.join(self.dir, "page.html")
        clip = small_clip(name="a</script><!--b", label="x < y & z")
        with three_js(self.fake):
            modskill.viewer.write_clips_html(path, self.spec, [clip], title="<b>A & B</b>")
        with open(path, "rb") as f:
            page = f.read()
        self.assertIn(FAKE_THREE_JS, page)
        self.assertIn(b"<title>&lt;b&gt;A &amp; B&lt;/b&gt;</title>", page)
        template = modskill.viewer.page_template()
        for placeholder in (b"/*MODSKILL_THREE_JS*/", b"MODSKILL_SCENE_JSON", b"MODSKILL_PAGE_TITLE"):
            self.assertIn(placeholder, template)
            self.assertNotIn(placeholder, page)
        # Only the template's own script elements end: names cannot close one.
        self.assertEqual(page.count(b"</script"), template.count(b"</script"))
        self.assertNotIn(b"<!--b", page)
        scene = read_scene(path)
        self.assertEqual(scene["version"], 1)
        self.assertEqual(scene["title"], "<b>A & B</b>")
        self.assertEqual([b["name"] for b in scene["bodies"]], ["Pelvis", "L_Hip", "L_Ankle"])
        self.assertEqual([b["parent"] for b in scene["bodies"]], [-1, 0, 1])
        self.assertEqual([b["geom"] for b in scene["bodies"]], [expected_geom(g) for g in self.spec.body_geometry])
        [page_clip] = scene["clips"]
        self.assertEqual((page_clip["name"], page_clip["label"]), (clip.name, clip.label))
        self.assertEqual((page_clip["fps"], page_clip["frames"]), (20.0, 4))
        self.assertIsNone(page_clip["body_error"])
        self.assertIsNone(page_clip["flags"])
        [(role, (pos, rot))] = tracks(page_clip, 3).items()
        self.assertEqual(role, "reference")
        np.testing.assert_array_equal(pos, clip.ref_pos)
        np.testing.assert_array_equal(rot, clip.ref_rot)

    def test_real_three_js_is_inlined(self):
        real = modskill.viewer.DEFAULT_THREE_JS
        if not os.path.isfile(real):
            self.skipTest(f"no {real} (apt install libjs-three)")
        path = os.path.join(self.dir, "page.html")
        with mock.patch.dict(os.environ, {"MODSKILL_THREE_JS": ""}):
            self.assertEqual(modskill.viewer.three_js_path(), real)
            modskill.viewer.write_clips_html(path, self.spec, [small_clip()])
        with open(real, "rb") as f:
            real_js = f.read()
        with open(path, "rb") as f:
            self.assertIn(real_js, f.read())
        self.assertEqual(read_scene(path)["clips"][0]["name"], "walk")

    def test_missing_three_js_names_it(self):
        missing = os.path.join(self.dir, "no_such_three.min.js")
        path = os.path.join(self.dir, "page.html")
        with three_js(missing), self.assertRaises(OSError) as caught:
            modskill.viewer.write_clips_html(path, self.spec, [small_clip()])
        self.assertIn(missing, str(caught.exception))
        self.assertIn("libjs-three", str(caught.exception))
        self.assertFalse(os.path.exists(path))

    def test_three_js_that_closes_the_script_is_refused(self):
        bad = os.path.join(self.dir, "bad.js")
        with open(bad, "wb") as f:
            f.write(b"var s = '</SCRIPT>';")
        with three_js(bad), self.assertRaisesRegex(ValueError, "</script"):
            modskill.viewer.write_clips_html(os.path.join(self.dir, "page.html"), self.spec, [small_clip()])

    def test_unwritable_path_names_it_and_leaves_no_file(self):
        missing_dir = os.path.join(self.dir, "no_such_dir")
        path = os.path.join(missing_dir, "page.html")
        with three_js(self.fake), self.assertRaises(OSError) as caught:
            modskill.viewer.write_clips_html(path, self.spec, [small_clip()])
        self.assertIn(path, str(caught.exception))
        self.assertFalse(os.path.exists(missing_dir))
        # A path that is a directory: the rename fails; the temporary file is removed.
        taken = os.path.join(self.dir, "taken.html")
        os.mkdir(taken)
        before = sorted(os.listdir(self.dir))
        with three_js(self.fake), self.assertRaises(OSError) as caught:
            modskill.viewer.write_clips_html(taken, self.spec, [small_clip()])
        self.assertIn(taken, str(caught.exception))
        self.assertEqual(sorted(os.listdir(self.dir)), before)
        self.assertEqual(os.listdir(taken), [])

    def test_family_limbs_are_drawn_at_their_scale(self):
        def family_rollout(clip, **params):
            r = rollout_without_frames(clip)
            frames = small_clip(frames=3)
            r.ref_body_pos = r.sim_body_pos = frames.ref_pos
            r.ref_body_rot = r.sim_body_rot = frames.ref_rot
            r.body_error_m = np.zeros(3, np.float32)
            r.done = np.array([False, False, True])
            r.terminated = np.zeros(3, np.bool_)
            r.family = {"params": params}
            return r

        plain = [expected_geom(g) for g in self.spec.body_geometry]
        path = os.path.join(self.dir, "legs.html")
        with three_js(self.fake):
            modskill.viewer.write_html(path, self.spec, [family_rollout("a", leg_scale=1.2, gravity=9.0),
                                                         family_rollout("b", leg_scale=1.2)])
        pelvis, hip, ankle = (b["geom"] for b in read_scene(path)["bodies"])
        self.assertEqual(pelvis, plain[0])  # neither a leg nor an arm
        self.assertAlmostEqual(hip["radius"], 1.2 * plain[1]["radius"])
        np.testing.assert_allclose(hip["to"], 1.2 * np.array(plain[1]["to"]))
        np.testing.assert_allclose(ankle["half_extents"], 1.2 * np.array(plain[2]["half_extents"]))
        np.testing.assert_allclose(ankle["center"], 1.2 * np.array(plain[2]["center"]))
        with three_js(self.fake):
            modskill.viewer.write_html(path, self.spec, [family_rollout("a", arm_scale=0.8)])
        self.assertEqual([b["geom"] for b in read_scene(path)["bodies"]], plain)  # no arms here
        self.assertEqual(modskill.viewer.limb_scale_of("R_Elbow", 1.2, 0.8), 0.8)
        with three_js(self.fake), self.assertRaisesRegex(ValueError, "a 1.2/1.0, b 0.8/1.0.*one page per scale"):
            modskill.viewer.write_html(os.path.join(self.dir, "mixed.html"), self.spec,
                                       [family_rollout("a", leg_scale=1.2), family_rollout("b", leg_scale=0.8)])
        self.assertFalse(os.path.exists(os.path.join(self.dir, "mixed.html")))

    def test_bad_clips_name_the_clip_and_leave_no_file(self):
        path = os.path.join(self.dir, "page.html")
        nan = small_clip(name="nan_clip")
        nan.ref_pos[2, 1, 0] = np.nan
        wrong_shape = small_clip(name="short_rot")
        wrong_shape.ref_rot = wrong_shape.ref_rot[:, :2]
        cases = [
            ([small_clip(), nan], r"clip 1 'nan_clip': ref_pos: not finite at \[2, 1, 0\]"),
            ([wrong_shape], r"clip 0 'short_rot': ref_rot: shape \[4, 2, 4\], expected \[4, 3, 4\]"),
            ([small_clip(name="empty", frames=0)], "clip 0 'empty': no frames"),
            ([small_clip(name="bad_flags", flags=np.zeros(3, np.uint8))], "clip 0 'bad_flags': flags"),
            ([small_clip(name="half_sim", sim_pos=np.zeros((4, 3, 3)))], "clip 0 'half_sim': sim_pos and sim_rot"),
            ([], "no clips"),
        ]
        with three_js(self.fake):
            for clips, message in cases:
                with self.subTest(message), self.assertRaisesRegex(ValueError, message):
                    modskill.viewer.write_clips_html(path, self.spec, clips)
            with self.assertRaisesRegex(ValueError, "clip 'deepmimic_walk'.*frames=True"):
                modskill.viewer.write_html(path, self.spec, [rollout_without_frames()])
            no_geometry = modskill.EnvSpec.from_proto(pb.EnvSpec(body_names=["Pelvis"], control_dt=0.05))
            with self.assertRaisesRegex(ValueError, "body_geometry"):
                modskill.viewer.write_clips_html(path, no_geometry, [small_clip()])
        self.assertEqual(sorted(os.listdir(self.dir)), ["three.min.js"])


@unittest.skipUnless(SERVER and CHECKPOINT, "MODSKILL_SERVER / MODSKILL_TEST_CHECKPOINT are not set "
                     "(run tests/python/run_python_tests.sh)")
class RolloutViewerTest(unittest.TestCase):
    """Pages of a live server's rollouts of the zero policy (which falls: clips end terminated)."""

    @classmethod
    def setUpClass(cls):
        cls.client = modskill.Client(SERVER, timeout=10)
        cls.spec = cls.client.describe()
        cls.motions = cls.client.motions()
        cls.rollouts = cls.client.rollout(CHECKPOINT, clips=CLIPS, frames=True)

    @classmethod
    def tearDownClass(cls):
        cls.client.close()

    def setUp(self):
        self.dir = scratch_dir(self)
        self.fake = fake_three_js(self.dir)

    def test_rollout_frames(self):
        num_bodies = len(self.spec.body_names)
        self.assertEqual(len(self.spec.body_geometry), num_bodies)
        self.assertEqual(self.spec.body_geometry[0].parent, -1)
        for r in self.rollouts:
            T = r.sim_body_pos.shape[0]
            self.assertGreater(T, 1, r.clip)
            for name in ("sim_body_rot", "ref_body_rot"):
                rot = getattr(r, name)
                self.assertEqual((rot.shape, rot.dtype), ((T, num_bodies, 4), np.float32), name)
                np.testing.assert_allclose(np.linalg.norm(rot, axis=-1), 1, atol=1e-5, err_msg=name)
            self.assertEqual((r.body_error_m.shape, r.body_error_m.dtype), ((T,), np.float32))
            np.testing.assert_allclose(r.body_error_m, r.body_errors().mean(axis=1), atol=1e-5)
            self.assertEqual((r.done.dtype, r.terminated.dtype), (np.bool_, np.bool_))
            self.assertEqual(np.flatnonzero(r.done).tolist(), [T - 1], r.clip)  # only the last row
            self.assertFalse(r.terminated[:-1].any())
            self.assertEqual(bool(r.terminated[-1]), not r.success, r.clip)

    def test_page_holds_the_rollout(self):
        path = os.path.join(self.dir, "rollout.html")
        with three_js(self.fake):
            modskill.viewer.write_html(path, self.spec, self.rollouts, title="zero policy", labels=self.motions)
        scene = read_scene(path)
        num_bodies = len(self.spec.body_names)
        self.assertEqual((scene["version"], scene["title"]), (1, "zero policy"))
        self.assertEqual([b["name"] for b in scene["bodies"]], list(self.spec.body_names))
        self.assertEqual([b["parent"] for b in scene["bodies"]], [g.parent for g in self.spec.body_geometry])
        self.assertEqual([b["geom"] for b in scene["bodies"]], [expected_geom(g) for g in self.spec.body_geometry])
        labels = {m["name"]: m["label"] for m in self.motions}
        self.assertEqual([c["name"] for c in scene["clips"]], CLIPS)
        for clip, r in zip(scene["clips"], self.rollouts):
            with self.subTest(clip=r.clip):
                T = r.sim_body_pos.shape[0]
                self.assertEqual((clip["label"], clip["frames"], clip["fps"]),
                                 (labels[r.clip], T, 1 / self.spec.control_dt))
                self.assertEqual([t["role"] for t in clip["tracks"]], ["reference", "simulated"])
                page_tracks = tracks(clip, num_bodies)
                for role, pos, rot in (("reference", r.ref_body_pos, r.ref_body_rot),
                                       ("simulated", r.sim_body_pos, r.sim_body_rot)):
                    np.testing.assert_array_equal(page_tracks[role][0], pos, err_msg=role)
                    np.testing.assert_array_equal(page_tracks[role][1], rot, err_msg=role)
                np.testing.assert_array_equal(floats(clip["body_error"], (T,)), r.body_error_m)
                flags = np.frombuffer(base64.b64decode(clip["flags"]), np.uint8)
                expected = np.zeros(T, np.uint8)
                expected[-1] = modskill.viewer.FLAG_DONE | (
                    modskill.viewer.FLAG_TERMINATED if r.terminated[-1] else modskill.viewer.FLAG_TRUNCATED)
                np.testing.assert_array_equal(flags, expected)

    def test_same_scene_as_the_cli_page(self):
        if not (CLIENT_BINARY and os.path.exists(CLIENT_BINARY)):
            self.skipTest(f"no C++ CLI at {CLIENT_BINARY or 'MODSKILL_BUILD_DIR/client/modskill-client'} "
                          "(build modskill-client; run_python_tests.sh sets MODSKILL_BUILD_DIR)")
        cli_path = os.path.join(self.dir, "cli.html")
        env = dict(os.environ, MODSKILL_THREE_JS=self.fake)
        process = subprocess.run([CLIENT_BINARY, "rollout", f"--server={SERVER}", f"--checkpoint={CHECKPOINT}",
                                  f"--clip={','.join(CLIPS)}", f"--html={cli_path}"],
                                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env, timeout=120)
        self.assertEqual(process.returncode, 0, process.stdout.decode("utf-8", "replace"))
        cli = read_scene(cli_path)
        python_path = os.path.join(self.dir, "python.html")
        with three_js(self.fake):
            modskill.viewer.write_html(python_path, self.spec, self.rollouts, title=cli["title"],
                                       labels=self.motions)
        python = read_scene(python_path)
        num_bodies = len(self.spec.body_names)
        self.assertEqual(python["bodies"], cli["bodies"])
        self.assertEqual([c["name"] for c in python["clips"]], [c["name"] for c in cli["clips"]])
        for ours, theirs in zip(python["clips"], cli["clips"]):
            with self.subTest(clip=ours["name"]):
                for key in ("label", "fps", "frames"):
                    self.assertEqual(ours[key], theirs[key], key)
                T = ours["frames"]
                ours_tracks, theirs_tracks = tracks(ours, num_bodies), tracks(theirs, num_bodies)
                self.assertEqual(list(ours_tracks), list(theirs_tracks))
                for role in ours_tracks:
                    np.testing.assert_array_equal(ours_tracks[role][0], theirs_tracks[role][0], err_msg=role)
                    np.testing.assert_array_equal(ours_tracks[role][1], theirs_tracks[role][1], err_msg=role)
                np.testing.assert_array_equal(floats(ours["body_error"], (T,)), floats(theirs["body_error"], (T,)))
                np.testing.assert_array_equal(base64.b64decode(ours["flags"]), base64.b64decode(theirs["flags"]))
        self.assertEqual(python, cli)  # and nothing else differs either

    def test_bad_rollouts_name_the_clip(self):
        path = os.path.join(self.dir, "page.html")
        no_frames = self.client.rollout(CHECKPOINT, clips=["deepmimic_run"])
        with three_js(self.fake):
            with self.assertRaisesRegex(ValueError, "clip 'deepmimic_run'.*frames=True"):
                modskill.viewer.write_html(path, self.spec, no_frames)
            bad = self.client.rollout(CHECKPOINT, clips=["deepmimic_walk"], frames=True)[0]
            bad.sim_body_rot = bad.sim_body_rot.copy()
            bad.sim_body_rot[1, 0, 0] = np.inf
            with self.assertRaisesRegex(ValueError, "clip 0 'deepmimic_walk': sim_rot: not finite"):
                modskill.viewer.write_html(path, self.spec, [bad])
        self.assertFalse(os.path.exists(path))


if __name__ == "__main__":
    unittest.main()
