#!/usr/bin/env python3
"""Writes deepmimic_stand.txt: the first frame of DeepMimic's humanoid3d_punch.txt (MIT; a guard
stance before the lunge) held for 3 s at 30 fps, a standing base motion the shipped library lacks.

    /usr/bin/python3 make_stand_clip.py ../shared/data/motions/deepmimic/humanoid3d_punch.txt OUT.txt
    build/server/modskill-motion import OUT.txt --out DIR
"""
import json
import sys

if len(sys.argv) != 3:
    sys.exit(__doc__)
with open(sys.argv[1]) as f:
    frames = json.load(f)["Frames"]
if not frames:
    sys.exit(f"error: {sys.argv[1]}: no frames")
with open(sys.argv[2], "w") as f:
    json.dump({"Loop": "wrap", "Frames": [list(frames[0]) for _ in range(91)]}, f)
