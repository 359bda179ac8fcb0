#!/usr/bin/env python3
"""Where do the hands go when a part's z comes from another clip? For each compose.json
(`modskill-client compose ... --parts R_Arm,L_Arm`), the mean distance, over the frames, of each
hand's pelvis-relative position in the composed rollout from the source clip's rollout and from the
base clip's, beside the base-source distance itself. A controller whose z alone sets the arm puts
the composed hand near the source's; one that only corrects its base motion keeps it at the base's.

    /usr/bin/python3 compose_probe.py DIR/compose.json [...]
"""
import json
import sys

import numpy as np

if len(sys.argv) < 2:
    sys.exit(__doc__)
for path in sys.argv[1:]:
    with open(path) as f:
        doc = json.load(f)
    names = doc["body_names"]
    pelvis = names.index("Pelvis")

    def relative(rollout, body):
        frames = doc["rollouts"][rollout]["frames"]
        positions = np.array([frame["sim_body_pos"] for frame in frames]).reshape(len(frames), len(names), 3)
        return positions[:, body] - positions[:, pelvis]

    cells = []
    for hand in ("R_Hand", "L_Hand"):
        body = names.index(hand)
        composed, base, source = (relative(r, body) for r in ("composed", "base", "source"))
        n = min(len(composed), len(base), len(source))

        def mm(a, b):
            return 1000 * np.linalg.norm(a[:n] - b[:n], axis=1).mean()

        cells.append(f"{hand}: composed-source {mm(composed, source):.0f} mm, composed-base {mm(composed, base):.0f} mm, "
                     f"base-source {mm(base, source):.0f} mm")
    print(f"{path} ({doc['source']} onto {doc['base']}) | " + "; ".join(cells))
