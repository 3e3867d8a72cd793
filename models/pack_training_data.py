#!/usr/bin/env python3
"""Packs train_segmentation.py's data into one folder small enough to be
carried to a GPU machine (models/README.md, "Training on a GPU"): the
cables-dev folder as it is, and the first COUNT images of each rendered
folder at the size the training reads them at (the network's, 320 x 240),
as JPEG with their union masks. A rendered busy scene shrinks from about
110 KiB to about 27 KiB. The training script reads the packed folders as
it reads the rendered ones.

Run (from the project's root):
    .venv-train/bin/python models/pack_training_data.py --out target/gpu-pack \\
        target/render-train:800 target/render-busy4:1200 ...
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

import cv2
import numpy as np

from train_segmentation import NET_H, NET_W

JPEG_QUALITY = 85


def pack_folder(source: Path, out: Path, count: int) -> int:
    """The first `count` images of a rendered folder into `out`, shrunk;
    returns the bytes written."""
    stems = sorted(p.stem for p in source.glob("*.jpg"))[:count]
    if len(stems) < count:
        raise FileNotFoundError(f"{source}: {len(stems)} rendered images, {count} asked for")
    out.mkdir(parents=True, exist_ok=True)
    written = 0
    for stem in stems:
        img = cv2.imread(str(source / f"{stem}.jpg"), cv2.IMREAD_COLOR)
        mask = cv2.imread(str(source / f"{stem}_mask_all.png"), cv2.IMREAD_GRAYSCALE)
        if img is None or mask is None:
            raise FileNotFoundError(f"{source}: image or mask {stem} missing")
        img = cv2.resize(img, (NET_W, NET_H), interpolation=cv2.INTER_AREA)
        # The training thresholds its targets at half anyway.
        mask = cv2.resize((mask > 127).astype(np.float32), (NET_W, NET_H), interpolation=cv2.INTER_AREA)
        cv2.imwrite(str(out / f"{stem}.jpg"), img, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
        cv2.imwrite(str(out / f"{stem}_mask_all.png"), (mask > 0.5).astype(np.uint8) * 255)
        written += (out / f"{stem}.jpg").stat().st_size + (out / f"{stem}_mask_all.png").stat().st_size
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
