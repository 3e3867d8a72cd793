#!/usr/bin/env python3
"""How often the pipeline misses pale cables against the others, from an eval-vision score.

A labelled cable counts as pale where the mean brightness (HSV value) of
its mask's pixels is at least 150 and their mean saturation under 60:
white and light grey insulation. The held-out photographs hold such
cables about three times as often as the training ones, and over light
paint the network missed them most (models/history.md, "Pale cables").
Run from the project's root, e.g.
    target/release/cablecell eval-vision target/vision-sets/pheld --json > pheld.json
    .venv-train/bin/python models/pale_labels.py pheld.json target/vision-sets/pheld
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import cv2
import numpy as np

PALE_MIN_VALUE = 150
PALE_MAX_SATURATION = 60


def is_pale(hsv: np.ndarray, mask: np.ndarray) -> bool:
    return bool(hsv[..., 2][mask].mean() >= PALE_MIN_VALUE and hsv[..., 1][mask].mean() < PALE_MAX_SATURATION)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scores", type=Path, help="the output of `cablecell eval-vision DIR --json`")
    parser.add_argument("folder", type=Path, help="the labelled folder DIR it scored")
    args = parser.parse_args()
    scores = json.loads(args.scores.read_text())
    # [pale, other] × [labels, missed]
    counts = np.zeros((2, 2), dtype=int)
    for name, image in scores["per_image"]:
        bgr = cv2.imread(str(args.folder / f"{name}.jpg"), cv2.IMREAD_COLOR)
        if bgr is None:
            print(f"{args.folder}: image {name}.jpg missing", file=sys.stderr)
            return 2
        hsv = cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV)
        missed = {m["index"] for m in image["missed"]}
        # The labels as eval-vision reads them: NAME_mask_0.png, _1, ... while they exist.
        index = 0
        while (path := args.folder / f"{name}_mask_{index}.png").exists():
            mask = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE) > 127
            if mask.any():
                counts[0 if is_pale(hsv, mask) else 1] += (1, index in missed)
            index += 1
    for kind, (labels, missed) in zip(("pale", "other"), counts):
        share = 100 * missed / labels if labels else 0.0
        print(f"{kind}: {labels} labels, {missed} missed ({share:.1f} %)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
