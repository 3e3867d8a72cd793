#!/usr/bin/env python3
"""Averages the weights of float cable segmentation networks, then quantizes the average.

Networks fine-tuned from one another lie close enough in weight space that
their average is a network too, and often a better one than any of them
(models/README.md says which shipped networks were made so). The networks
must have the same layers; train_segmentation.py writes them as
NAME_float.onnx. One may be 8-bit (a shipped network whose float weights
were not kept): its weights are dequantized; the graph is the first float
one's. Run from the project's root, e.g.
    .venv-train/bin/python models/average_segmentation.py A_float.onnx B_float.onnx \
        --out models/cable_segmentation.onnx
It writes the float average beside OUT, as OUT_STEM_float.onnx, and the
8-bit network, quantized as quantize_segmentation.py does, to OUT.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import onnx
from onnx import numpy_helper

from quantize_segmentation import conv_weights, quantize


def average(paths: list[Path]) -> onnx.ModelProto:
    """The first float model with each convolution's weights and bias
    replaced by their mean over all the models (an 8-bit one's
    dequantized: `conv_weights`), matched by the convolution's name."""
    models = [onnx.load(str(p)) for p in paths]
    floats = [i for i, m in enumerate(models) if not any(n.op_type == "DequantizeLinear" for n in m.graph.node)]
    if not floats:
        raise ValueError("give at least one float network: its graph is the average's")
    weights = [conv_weights(m) for m in models]
    out, first = models[floats[0]], weights[floats[0]]
    initializers = {w.name: w for w in out.graph.initializer}
    for node in out.graph.node:
        if node.op_type != "Conv":
            continue
        for k, tensor in enumerate(node.input[1:]):
            values = []
            for path, named in zip(paths, weights):
                own = named.get(node.name, (None, None))[k]
                if own is None or own.shape != first[node.name][k].shape:
                    raise ValueError(f"{path}: no convolution {node.name} of the same shape: "
                                     f"not the same layers as the first float network")
                values.append(own)
            mean = sum(v.astype("float64") for v in values) / len(values)
            dtype = numpy_helper.to_array(initializers[tensor]).dtype
            initializers[tensor].CopyFrom(numpy_helper.from_array(mean.astype(dtype), tensor))
    return out


def main() -> int:
    here = Path(__file__).resolve().parent
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("models", type=Path, nargs="+", help="ONNX networks with the same layers, one of them float at least")
    parser.add_argument("--data", type=Path, default=here.parent.parent / "shared" / "data" / "cables-dev",
                        help="the cables-dev folder, for quantization's calibration "
                             "(default: ../shared/data/cables-dev from the project's root)")
    parser.add_argument("--out", type=Path, default=here / "cable_segmentation.onnx",
                        help="the 8-bit average; the float one is written beside it as OUT_STEM_float.onnx")
    args = parser.parse_args()
    if len(args.models) < 2:
        print("give two or more networks to average", file=sys.stderr)
        return 2
    for path in args.models:
        if not path.is_file():
            print(f"no network at {path}", file=sys.stderr)
            return 2
    if not args.data.is_dir():
        print(f"no data at {args.data}", file=sys.stderr)
        return 2
    try:
        mean = average(args.models)
    except ValueError as e:
        print(e, file=sys.stderr)
        return 2
    args.out.parent.mkdir(parents=True, exist_ok=True)
    float_out = args.out.with_name(f"{args.out.stem}_float.onnx")
    onnx.save(mean, str(float_out))
    print(f"averaged {len(args.models)} networks into {float_out}", flush=True)
    quantize(float_out, args.out, args.data)
    return 0


if __name__ == "__main__":
    sys.exit(main())
