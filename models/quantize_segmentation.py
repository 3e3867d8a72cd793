#!/usr/bin/env python3
"""Quantizes cablecell's float cable segmentation network to 8-bit integers.

The 8-bit model is the one the Rust side runs: on 2 CPU cores with VNNI
(AVX-512 or AVX-VNNI) it runs 1.2 to 1.6 times as fast as the float one,
and its masks match the float ones' (models/README.md has the figures).
Weights are quantized per output channel to 7 bits of the 8 (see
`quantize`); activations to 8 bits, with the ranges
(min/max) they take on the training photographs of cables-dev, at the two
input sizes the Rust side uses. The model's inputs and outputs stay float,
so its contract (models/README.md) is unchanged.

train_segmentation.py calls this after training; run it alone (it needs
onnxruntime, onnx, numpy and OpenCV, not torch) to quantize the float model
again, from the project's root:
    .venv-train/bin/python models/quantize_segmentation.py
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

# The photographs of cables-dev the network was trained on (00000..00029);
# the held-out ones are not used here either.
CALIBRATION_IDS = range(0, 30)

# The network's input sizes for a 640x480 image at the Rust side's default
# input scale (0.375) and at 0.5, the scale it was trained at, so that
# either scale finds its activations in range.
CALIBRATION_SIZES = ((240, 176), (320, 240))


def quantize(float_path: Path, out: Path, data: Path) -> None:
    """Writes `float_path` quantized to 8-bit integers to `out`, calibrated
    on the training photographs in `data` (a cables-dev folder).

    Weights keep to 7 bits (`reduce_range`): CPUs without VNNI multiply
    8-bit pairs into 16-bit sums, which full-range weights can overflow;
    with VNNI the 7 bits cost nothing, and on cables-dev they score as 8."""
    from onnxruntime.quantization import (CalibrationDataReader, QuantFormat, QuantType,
                                          quant_pre_process, quantize_static)

    feeds = []
    for i in CALIBRATION_IDS:
        path = data / f"{i:05d}.jpg"
        image = cv2.imread(str(path), cv2.IMREAD_COLOR)
        if image is None:
            raise FileNotFoundError(f"{path}: calibration photograph missing or unreadable")
        for size in CALIBRATION_SIZES:
            small = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
            feeds.append({"bgr": small.astype(np.float32)[None]})

    class Photographs(CalibrationDataReader):
        def __init__(self) -> None:
            self.feeds = iter(feeds)

        def get_next(self) -> dict | None:
            return next(self.feeds, None)

    prepared = out.with_suffix(".prepared.onnx")
    quant_pre_process(str(float_path), str(prepared), skip_symbolic_shape=True)
    quantize_static(str(prepared), str(out), Photographs(), quant_format=QuantFormat.QDQ,
                    activation_type=QuantType.QUInt8, weight_type=QuantType.QInt8, per_channel=True,
                    reduce_range=True)
    prepared.unlink()
    print(f"quantized {float_path} to {out}: {out.stat().st_size} bytes", flush=True)


def main() -> int:
    here = Path(__file__).resolve().parent
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=here.parent.parent / "shared" / "data" / "cables-dev",
                        help="the cables-dev folder (default: ../shared/data/cables-dev from the project's root)")
    parser.add_argument("--float", dest="float_path", type=Path, default=here / "cable_segmentation_float.onnx",
                        help="the float model train_segmentation.py wrote")
    parser.add_argument("--out", type=Path, default=here / "cable_segmentation.onnx")
    args = parser.parse_args()
    if not args.float_path.is_file():
        print(f"no float model at {args.float_path}: train one with train_segmentation.py", file=sys.stderr)
        return 2
    if not args.data.is_dir():
        print(f"no data at {args.data}", file=sys.stderr)
        return 2
    quantize(args.float_path, args.out, args.data)
    return 0


if __name__ == "__main__":
    sys.exit(main())
