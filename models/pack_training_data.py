#!/usr/bin/env python3
"""Packs train_segmentation.py's data into one folder small enough to be
carried to a GPU machine (models/README.md, "Training on a GPU"): the
cables-dev folder as it is, and the first COUNT images of each rendered
folder at the size the training reads them at (the network's, 320 x 240),
as JPEG with their union masks. A rendered busy scene shrinks from about
110 KiB to about 24 KiB with its mask. The training script reads the
packed folders as it reads the rendered ones.

Run (from the project's root):
    .venv-train/bin/python models/pack_training_data.py --out target/gpu-pack \\
        target/render-train:600 target/render-busy4:700 ...
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

import cv2
import numpy as np

from train_segmentation import load_synthetic

JPEG_QUALITY = 85


def pack_folder(source: Path, out: Path, count: int) -> int:
    """The first `count` images of a rendered folder into `out`, as the
    training reads them; returns the bytes written."""
    images, masks = load_synthetic(source, count)
    if len(images) < count:
        raise FileNotFoundError(f"{source}: {len(images)} rendered images, {count} asked for")
    out.mkdir(parents=True, exist_ok=True)
    written = 0
    for i, (img, mask) in enumerate(zip(images, masks)):
        jpg, png = out / f"{i:05d}.jpg", out / f"{i:05d}_mask_all.png"
        cv2.imwrite(str(jpg), img, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
        # The training thresholds its targets at half anyway.
        cv2.imwrite(str(png), (mask > 0.5).astype(np.uint8) * 255)
        written += jpg.stat().st_size + png.stat().st_size
    return written


def folder_and_count(text: str) -> tuple[Path, int]:
    folder, _, count = text.rpartition(":")
    if not folder or not count.isdigit():
        raise argparse.ArgumentTypeError(f"{text}: expected FOLDER:COUNT, e.g. target/render-busy4:1200")
    return Path(folder), int(count)


def main() -> int:
    here = Path(__file__).resolve().parent
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=here.parent.parent / "shared" / "data" / "cables-dev",
                        help="the cables-dev folder (default: ../shared/data/cables-dev from the project's root)")
    parser.add_argument("--out", type=Path, required=True,
                        help="the pack: OUT/cables-dev and one folder per rendered folder, by its name")
    parser.add_argument("folders", type=folder_and_count, nargs="+", metavar="FOLDER:COUNT",
                        help="a folder written by `cablecell render-dataset` and how many of its images to take")
    args = parser.parse_args()
    if not args.data.is_dir():
        print(f"no data at {args.data}", file=sys.stderr)
        return 2
    shutil.rmtree(args.out, ignore_errors=True)
    shutil.copytree(args.data, args.out / "cables-dev")
    total = sum(p.stat().st_size for p in (args.out / "cables-dev").iterdir())
    for folder, count in args.folders:
        written = pack_folder(folder, args.out / folder.name, count)
        print(f"{folder}: {count} images, {written / 2**20:.1f} MiB", flush=True)
        total += written
    print(f"{args.out}: {total / 2**20:.1f} MiB in all")
    return 0


if __name__ == "__main__":
    sys.exit(main())
