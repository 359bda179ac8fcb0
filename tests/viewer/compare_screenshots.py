#!/usr/bin/python3
"""Checks two screenshots of the viewer page: neither blank, the character visible in both, and
its pixels moved between the two frames. With --simulated (a rollout page) the simulated
character, drawn in orange, must be visible in both too.

  compare_screenshots.py [--simulated] FRAME_A.png FRAME_B.png

The reference character is drawn in blue (COLORS.reference in viewer_page.html); its pixels are
those clearly bluer than red, which neither the sky, the ground nor the grid are.
"""
import sys

import matplotlib.image
import numpy


def character_mask(image):
    rgb = image[..., :3].astype(numpy.float64)
    return (rgb[..., 2] - rgb[..., 0] > 0.3) & (rgb[..., 2] - rgb[..., 1] > 0.15)


def simulated_mask(image):
    rgb = image[..., :3].astype(numpy.float64)
    return (rgb[..., 0] - rgb[..., 2] > 0.3) & (rgb[..., 0] - rgb[..., 1] > 0.1)


def main(a_path, b_path, simulated=False):
    failures = []
    masks = []
    for path in (a_path, b_path):
        image = matplotlib.image.imread(path)
        rgb = image[..., :3]
        spread = float(rgb.reshape(-1, 3).std(axis=0).max())
        mask = character_mask(image)
        print(f"{path}: {image.shape[1]}x{image.shape[0]}, colour spread {spread:.3f}, "
              f"character pixels {int(mask.sum())}")
        if spread < 0.02:
            failures.append(f"{path}: blank (colour spread {spread:.3f})")
        if mask.sum() < 300:
            failures.append(f"{path}: no character drawn ({int(mask.sum())} blue pixels)")
        if simulated:
            orange = int(simulated_mask(image).sum())
            print(f"{path}: simulated character pixels {orange}")
            if orange < 300:
                failures.append(f"{path}: no simulated character drawn ({orange} orange pixels)")
        masks.append(mask)
    if masks[0].shape != masks[1].shape:
        failures.append("screenshots differ in size")
    else:
        union = int((masks[0] | masks[1]).sum())
        moved = int((masks[0] ^ masks[1]).sum())
        print(f"character pixels that changed between the frames: {moved} of {union}")
        if union == 0 or moved < 0.05 * union:
            failures.append(f"the character did not move between the frames ({moved} of {union} pixels)")
    for failure in failures:
        print("FAIL:", failure)
    return 1 if failures else 0


if __name__ == "__main__":
    args = sys.argv[1:]
    with_simulated = "--simulated" in args
    args = [a for a in args if a != "--simulated"]
    if len(args) != 2:
        sys.exit(__doc__)
    sys.exit(main(args[0], args[1], with_simulated))
