#!/usr/bin/python3
"""Checks a filmstrip PNG (tools/filmstrip.sh): not blank, the reference (blue) and the simulated
(orange) character both drawn, and the poses spread over most of the image's width (N poses
side by side, not one).

  check_filmstrip.py STRIP.png
"""
import sys

import matplotlib.image
import numpy

from compare_screenshots import character_mask, simulated_mask


def main(path):
    image = matplotlib.image.imread(path)
    failures = []
    spread = float(image[..., :3].reshape(-1, 3).std(axis=0).max())
    blue, orange = character_mask(image), simulated_mask(image)
    columns = numpy.flatnonzero((blue | orange).any(axis=0))
    covered = (columns[-1] - columns[0] + 1) / image.shape[1] if columns.size else 0.0
    print(f"{path}: {image.shape[1]}x{image.shape[0]}, colour spread {spread:.3f}, "
          f"reference pixels {int(blue.sum())}, simulated pixels {int(orange.sum())}, width covered {covered:.2f}")
    if spread < 0.02:
        failures.append("blank")
    if blue.sum() < 1000 or orange.sum() < 1000:
        failures.append("a character is missing")
    if covered < 0.6:
        failures.append(f"the poses cover {covered:.2f} of the width (expected a row of poses)")
    for failure in failures:
        print("FAIL:", failure)
    return 1 if failures else 0


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1]))
