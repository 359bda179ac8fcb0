#!/usr/bin/python3
"""Checks two screenshots of the viewer page: neither blank, the character visible in both, and
its pixels moved between the two frames.

  compare_screenshots.py FRAME_A.png FRAME_B.png

The reference character is drawn in blue (COLORS.reference in viewer_page.html); its pixels are
those clearly bluer than red, which neither the sky, the ground nor the grid are.
"""
import sys

import matplotlib.image
import numpy


def character_mask(image):
    rgb = image[..., :3].astype(numpy.float64)
    return (rgb[..., 2] - rgb[..., 0] > 0.3) & (rgb[..., 2] - rgb[..., 1] > 0.15)


def main(a_path, b_path):
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
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1], sys.argv[2]))
