"""Self-contained HTML viewer pages of rollouts: the policy's character beside its reference.

The page is the one ``modskill-client rollout --html`` writes (common/viewer/viewer_html.cc):
three.js and the scene are inlined, so it opens from disk, offline, in any browser. Example::

    import modskill, modskill.viewer

    with modskill.Client("127.0.0.1:50051") as client:
        spec = client.describe()
        rollouts = client.rollout("policy.pt", clips=["deepmimic_walk"], frames=True)
        modskill.viewer.write_html("walk.html", spec, rollouts, title="policy.pt",
                                   labels=client.motions())

``write_clips_html`` draws :class:`ViewerClip` s built from numpy arrays instead (a reference
alone, or your own simulated poses beside it).

A motor-skill family's rollouts at ``leg_scale`` or ``arm_scale`` are drawn with their limbs at
that scale, as ``modskill-client rollout --html`` draws them (the rule of
common/policy/family_parameters.cc, ``FamilyLimbScale``: bodies named Hip, Knee, Ankle or Toe
follow the legs, Shoulder, Elbow, Wrist or Hand the arms). A page has one skeleton, so the
rollouts of one page must share their scales.

three.js is read from ``$MODSKILL_THREE_JS`` or Debian's libjs-three
(/usr/share/javascript/three/three.min.js). The page template is package data
(``viewer_page.html``, a copy of common/viewer/viewer_page.html; tests/python/test_viewer.py
fails when they differ). The scene JSON has the C++ writer's schema (version 1): bodies with
their geometry, and per clip the reference and simulated tracks as base64 little-endian float32,
the mean body error per frame and the done / terminated / truncated flags per frame.
"""

from __future__ import annotations

import base64
import dataclasses
import errno
import importlib.resources
import json
import math
import os
import re
import tempfile
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from .types import BodyGeometry, ClipRollout, EnvSpec

__all__ = ["ViewerClip", "write_html", "write_clips_html", "clip_from_rollout", "load_three_js",
           "three_js_path", "page_template", "rollout_limb_scale", "limb_scale_of", "DEFAULT_THREE_JS", "FLAG_DONE", "FLAG_TERMINATED", "FLAG_TRUNCATED"]

PathLike = Union[str, "os.PathLike[str]"]

DEFAULT_THREE_JS = "/usr/share/javascript/three/three.min.js"  # Debian's libjs-three
MAX_THREE_JS_BYTES = 16 << 20

# Per-frame flag bits (viewer_scene.h: ViewerFrameFlag).
FLAG_DONE, FLAG_TERMINATED, FLAG_TRUNCATED = 1, 2, 4

# The template's placeholders, replaced in one pass (as absl::StrReplaceAll does), so that text
# put in for one is never searched for another.
_PLACEHOLDERS = re.compile(rb"/\*MODSKILL_THREE_JS\*/|MODSKILL_SCENE_JSON|MODSKILL_PAGE_TITLE")


@dataclasses.dataclass
class ViewerClip:
    """One clip of a page: the reference's world body poses and optionally the simulated ones.

    Poses are ``[T, num_bodies, 3]`` positions (m, world, z up) and ``[T, num_bodies, 4]``
    orientations (w, x, y, z), bodies in ``EnvSpec.body_names`` order; any real dtype (written as
    float32).
    """

    name: str
    ref_pos: np.ndarray
    ref_rot: np.ndarray
    sim_pos: Optional[np.ndarray] = None
    sim_rot: Optional[np.ndarray] = None
    body_error: Optional[np.ndarray] = None  # [T] m, shown per frame
    flags: Optional[np.ndarray] = None  # [T] FLAG_* bits
    label: str = ""  # caption under the name
    fps: Optional[float] = None  # None: 1 / spec.control_dt


def clip_from_rollout(rollout: ClipRollout, label: str = "") -> ViewerClip:
    """The page's clip of a ``Client.rollout(..., frames=True)`` result; ValueError naming the
    clip when it has no frames."""
    where = f"clip {rollout.clip!r}"
    if rollout.sim_body_pos is None or rollout.ref_body_pos is None:
        raise ValueError(f"{where}: the rollout has no frames (call client.rollout(..., frames=True))")
    missing = [name for name in ("sim_body_rot", "ref_body_rot", "body_error_m", "done", "terminated")
               if getattr(rollout, name) is None]
    if missing:
        raise ValueError(f"{where}: the rollout has no {', '.join(missing)} (a server older than the viewer?)")
    done = np.asarray(rollout.done, dtype=np.bool_)
    terminated = np.asarray(rollout.terminated, dtype=np.bool_)
    if done.shape != terminated.shape:
        raise ValueError(f"{where}: done {list(done.shape)} and terminated {list(terminated.shape)} differ")
    flags = (done * FLAG_DONE | terminated * FLAG_TERMINATED | (done & ~terminated) * FLAG_TRUNCATED)
    return ViewerClip(name=rollout.clip, ref_pos=rollout.ref_body_pos, ref_rot=rollout.ref_body_rot,
                      sim_pos=rollout.sim_body_pos, sim_rot=rollout.sim_body_rot,
                      body_error=rollout.body_error_m, flags=flags.astype(np.uint8), label=label)


def write_html(path: PathLike, spec: EnvSpec, rollouts: Sequence[ClipRollout], title: str = "",
               labels: Optional[Union[Mapping[str, str], Iterable[Mapping[str, Any]]]] = None) -> None:
    """Writes the viewer page of rollouts: per clip, the simulated character beside its reference.

    Args:
      path: the HTML file, written atomically (no partial file on any error).
      spec: ``client.describe()`` (its ``body_geometry``, ``body_names`` and ``control_dt``).
      rollouts: ``client.rollout(..., frames=True)``, one clip each, shown in this order.
      title: the page's title.
      labels: captions by clip name, or ``client.motions()`` itself (its name and label).

    Raises:
      ValueError: a rollout without frames, poses of the wrong shape or not finite (naming the
        clip), a spec without geometry, family rollouts at different limb scales, or an unusable
        three.js.
      OSError: three.js is missing, or ``path`` cannot be written (naming the path).
    """
    captions = _captions(labels)
    clips = [clip_from_rollout(r, captions.get(r.clip, "")) for r in rollouts]
    write_clips_html(path, spec, clips, title, limb_scale=rollout_limb_scale(rollouts))


def write_clips_html(path: PathLike, spec: EnvSpec, clips: Sequence[ViewerClip], title: str = "",
                     limb_scale: Tuple[float, float] = (1.0, 1.0)) -> None:
    """Writes a page of :class:`ViewerClip` s, the limbs drawn at ``limb_scale`` = (leg_scale,
    arm_scale); errors as :func:`write_html`."""
    scene = _scene(spec, clips, title, limb_scale)
    page = _render(scene, title, load_three_js())
    _write_atomically(path, page)


def three_js_path() -> str:
    """Where three.js is read from: ``$MODSKILL_THREE_JS`` when set, else ``DEFAULT_THREE_JS``."""
    return os.environ.get("MODSKILL_THREE_JS") or DEFAULT_THREE_JS


def load_three_js() -> bytes:
    """three.js to inline; the error names the file and what to install."""
    path = three_js_path()
    hint = "install Debian's libjs-three, or set MODSKILL_THREE_JS to a three.min.js"
    if not os.path.isfile(path):
        raise FileNotFoundError(errno.ENOENT, f"three.js for the HTML viewer: no such file ({hint})", path)
    size = os.path.getsize(path)
    if size > MAX_THREE_JS_BYTES:
        raise ValueError(f"three.js for the HTML viewer: {path}: {size} bytes exceeds the limit of "
                         f"{MAX_THREE_JS_BYTES} ({hint})")
    with open(path, "rb") as f:
        text = f.read()
    if b"</script" in text.lower():
        raise ValueError(f"three.js for the HTML viewer: {path}: contains '</script', cannot be inlined")
    return text


def rollout_limb_scale(rollouts: Sequence[ClipRollout]) -> Tuple[float, float]:
    """(leg_scale, arm_scale) the rollouts ran at: 1 where a rollout is no family's or leaves the
    parameter out. ValueError naming each clip's scales when they differ (one page, one skeleton)."""
    scales = {}
    for r in rollouts:
        params = (r.family or {}).get("params", {})
        scales[r.clip] = (float(params.get("leg_scale", 1.0)), float(params.get("arm_scale", 1.0)))
    distinct = set(scales.values())
    if len(distinct) > 1:
        listed = ", ".join(f"{clip} {leg}/{arm}" for clip, (leg, arm) in scales.items())
        raise ValueError(f"rollouts: family rollouts at different leg_scale/arm_scale ({listed}): "
                         "write one page per scale")
    return distinct.pop() if distinct else (1.0, 1.0)


def limb_scale_of(body_name: str, leg_scale: float, arm_scale: float) -> float:
    """The scale a body's geometry takes in a family at (leg_scale, arm_scale): FamilyLimbScale's rule."""
    if any(part in body_name for part in ("Hip", "Knee", "Ankle", "Toe")):
        return leg_scale
    if any(part in body_name for part in ("Shoulder", "Elbow", "Wrist", "Hand")):
        return arm_scale
    return 1.0


def _captions(labels) -> Dict[str, str]:
    if labels is None:
        return {}
    if isinstance(labels, Mapping):
        return {str(k): str(v) for k, v in labels.items()}
    return {str(m["name"]): str(m.get("label", "")) for m in labels}


def _vec3(values: Sequence[float], where: str) -> List[float]:
    """A geometry 3-vector: empty reads as zero (a sphere has no segment), else 3 finite values."""
    if len(values) == 0:
        return [0.0, 0.0, 0.0]
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise ValueError(f"{where}: {list(values)} is not 3 finite values")
    return [float(v) for v in values]


def _geom(geometry: BodyGeometry, where: str) -> Dict[str, Any]:
    if not (math.isfinite(geometry.radius) and geometry.radius >= 0):
        raise ValueError(f"{where}.radius: {geometry.radius} is not a finite non-negative length")
    vec = lambda name: _vec3(getattr(geometry, name), f"{where}.{name}")
    if geometry.shape == "sphere":
        return {"type": "sphere", "radius": float(geometry.radius), "center": vec("center")}
    if geometry.shape == "capsule":
        return {"type": "capsule", "radius": float(geometry.radius), "from": vec("segment_from"),
                "to": vec("segment_to")}
    if geometry.shape == "box":
        return {"type": "box", "half_extents": vec("half_extents"), "center": vec("center")}
    raise ValueError(f"{where}.shape: {geometry.shape!r} is not sphere, capsule or box")


def _scaled(geom: Dict[str, Any], scale: float) -> Dict[str, Any]:
    """A body's geometry grown by ``scale`` about its frame, as RolloutViewerRecorder::ScaleFamilyLimbs."""
    if scale == 1.0:
        return geom
    grown = {}
    for key, value in geom.items():
        if key == "radius":
            grown[key] = value * scale
        elif isinstance(value, list):
            grown[key] = [v * scale for v in value]
        else:
            grown[key] = value
    return grown


def _bodies(spec: EnvSpec, limb_scale: Tuple[float, float] = (1.0, 1.0)) -> List[Dict[str, Any]]:
    geometry = getattr(spec, "body_geometry", ())
    if not geometry:
        raise ValueError("spec: no body_geometry (a spec from a server older than the viewer?)")
    if len(geometry) != len(spec.body_names):
        raise ValueError(f"spec.body_geometry: {len(geometry)} entries for {len(spec.body_names)} body_names")
    bodies = []
    for b, (name, g) in enumerate(zip(spec.body_names, geometry)):
        where = f"spec.body_geometry[{b}] ({name})"
        if g.parent >= b or g.parent < (-1 if b == 0 else 0):
            raise ValueError(f"{where}.parent: {g.parent} is not an earlier body")
        geom = _scaled(_geom(g, where), limb_scale_of(name, *limb_scale))
        bodies.append({"name": name, "parent": int(g.parent), "geom": geom})
    return bodies


def _float32(array, shape, where: str) -> np.ndarray:
    """``array`` as C-contiguous little-endian float32 of ``shape``, every value finite."""
    array = np.asarray(array)
    if array.dtype.kind not in "fiu":
        raise ValueError(f"{where}: dtype {array.dtype}, expected real numbers")
    if array.shape != shape:
        raise ValueError(f"{where}: shape {list(array.shape)}, expected {list(shape)}")
    array = np.ascontiguousarray(array, dtype="<f4")
    if not np.isfinite(array).all():
        raise ValueError(f"{where}: not finite at {np.argwhere(~np.isfinite(array))[0].tolist()}")
    return array


def _base64(array: np.ndarray) -> str:
    return base64.b64encode(array.tobytes()).decode("ascii")


def _clip(clip: ViewerClip, index: int, spec: EnvSpec) -> Dict[str, Any]:
    where = f"clip {index} {clip.name!r}"
    num_bodies = len(spec.body_names)
    ref_pos = np.asarray(clip.ref_pos)
    if ref_pos.ndim == 0 or ref_pos.shape[0] == 0:
        raise ValueError(f"{where}: no frames")
    frames = ref_pos.shape[0]
    fps = float(clip.fps) if clip.fps is not None else (1.0 / spec.control_dt if spec.control_dt > 0 else 0.0)
    if not (math.isfinite(fps) and fps > 0):
        raise ValueError(f"{where}: fps {fps} is not positive (spec.control_dt: {spec.control_dt})")
    if (clip.sim_pos is None) != (clip.sim_rot is None):
        raise ValueError(f"{where}: sim_pos and sim_rot: give both or neither")
    tracks = [("reference", clip.ref_pos, clip.ref_rot, "ref")]
    if clip.sim_pos is not None:
        tracks.append(("simulated", clip.sim_pos, clip.sim_rot, "sim"))
    json_tracks = []
    for role, pos, rot, prefix in tracks:
        pos = _float32(pos, (frames, num_bodies, 3), f"{where}: {prefix}_pos")
        rot = _float32(rot, (frames, num_bodies, 4), f"{where}: {prefix}_rot")
        json_tracks.append({"role": role, "pos": _base64(pos), "rot": _base64(rot)})
    body_error = None
    if clip.body_error is not None:
        body_error = _base64(_float32(clip.body_error, (frames,), f"{where}: body_error"))
    flags = None
    if clip.flags is not None:
        values = np.asarray(clip.flags)
        if values.shape != (frames,) or values.dtype.kind not in "biu" or ((values < 0) | (values > 255)).any():
            raise ValueError(f"{where}: flags {values.dtype} {list(values.shape)}, expected [{frames}] bytes")
        flags = _base64(values.astype(np.uint8))
    return {"name": clip.name, "label": clip.label, "fps": fps, "frames": int(frames),
            "tracks": json_tracks, "body_error": body_error, "flags": flags}


def _scene(spec: EnvSpec, clips: Sequence[ViewerClip], title: str,
           limb_scale: Tuple[float, float] = (1.0, 1.0)) -> Dict[str, Any]:
    leg, arm = (float(s) for s in limb_scale)
    if not all(math.isfinite(s) and s > 0 for s in (leg, arm)):
        raise ValueError(f"limb_scale: {list(limb_scale)} is not two finite positive scales")
    bodies = _bodies(spec, (leg, arm))
    if not clips:
        raise ValueError("viewer page: no clips")
    return {"version": 1, "title": title, "bodies": bodies,
            "clips": [_clip(clip, i, spec) for i, clip in enumerate(clips)]}


def page_template() -> bytes:
    """The page template (package data ``viewer_page.html``) with its three placeholders."""
    return importlib.resources.files(__package__).joinpath("viewer_page.html").read_bytes()


def _render(scene: Dict[str, Any], title: str, three_js: bytes) -> bytes:
    template = page_template()
    # Sorted keys and no spaces: the C++ writer's (nlohmann::json) text. '<' occurs only inside
    # JSON strings: as \u003c it can neither close the script element nor open a comment.
    text = json.dumps(scene, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False)
    values = {
        b"/*MODSKILL_THREE_JS*/": three_js,
        b"MODSKILL_SCENE_JSON": text.replace("<", "\\u003c").encode("utf-8", "replace"),
        b"MODSKILL_PAGE_TITLE": title.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
                                     .encode("utf-8", "replace"),
    }
    return _PLACEHOLDERS.sub(lambda m: values[m.group(0)], template)


def _write_atomically(path: PathLike, data: bytes) -> None:
    """Writes a temporary file beside ``path`` and renames it; errors name ``path``."""
    path = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(directory):
        raise FileNotFoundError(errno.ENOENT, f"viewer page: the directory {directory} does not exist", path)
    try:
        fd, temp = tempfile.mkstemp(prefix=os.path.basename(path) + ".", suffix=".tmp", dir=directory)
    except OSError as e:
        raise OSError(e.errno, f"viewer page: cannot create a file in {directory}: {e.strerror}", path) from None
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(temp, 0o644)
        os.replace(temp, path)
    except BaseException as e:
        try:
            os.unlink(temp)
        except OSError:
            pass
        if isinstance(e, OSError):
            raise OSError(e.errno, f"viewer page: cannot write: {e.strerror}", path) from None
        raise
