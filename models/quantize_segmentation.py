#!/usr/bin/env python3
"""Quantizes cablecell's float cable segmentation network to 8-bit integers.

The 8-bit model is the one the Rust side runs: on 2 CPU cores with VNNI
(AVX-512 or AVX-VNNI) it runs 1.2 to 1.6 times as fast as the float one,
and its masks match the float ones' (models/history.md, "Quantization
measured", has the figures).
Weights are quantized per output channel to 7 bits of the 8 (see
`quantize`); activations to 8 bits, with the ranges
(min/max) they take on the training photographs of cables-dev, at the two
input sizes the Rust side uses. The 8-bit model then takes the image's
bytes as they are (`bytes_in`): its first layer reads them without the
float conversion, normalisation and quantization in front of it.

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


def conv_weights(model) -> dict[str, tuple[np.ndarray, np.ndarray | None]]:
    """Each convolution's float weights and bias (None where it has none)
    in a loaded ONNX model, by its node's name, which the export takes from
    the module's path and quantization keeps. An 8-bit model's are
    dequantized, `(q - zero point) * scale` per channel, so that a network
    whose float weights were not kept can still be averaged and trained on."""
    from onnx import numpy_helper

    graph = model.graph
    tensors = {i.name: numpy_helper.to_array(i) for i in graph.initializer}
    for node in graph.node:
        if node.op_type == "DequantizeLinear" and all(i in tensors for i in node.input):
            q, scale, zero = (tensors[i] for i in node.input)
            axis = next((a.i for a in node.attribute if a.name == "axis"), 1)
            shape = [-1 if k == axis else 1 for k in range(q.ndim)] if scale.ndim else []
            tensors[node.output[0]] = ((q.astype(np.float32) - np.reshape(zero, shape).astype(np.float32))
                                       * np.reshape(scale, shape))
    return {n.name: (tensors[n.input[1]], tensors[n.input[2]] if len(n.input) > 2 else None)
            for n in graph.node if n.op_type == "Conv"}


def bytes_in(path: Path) -> None:
    """Rewrites the 8-bit model at `path` to take the image's bytes (uint8,
    NHWC) in place of float32 0..255. Between its input and the first
    convolution's DequantizeLinear the model ran Transpose, Sub (the mean),
    Div (the spread) and QuantizeLinear; without them that DequantizeLinear
    reads the transposed bytes themselves, with scale 1 / spread and zero
    point the mean rounded to a whole byte, and the convolution's bias
    takes up the rounding. Each pixel's normalised value is then exact,
    where the calibrated quantization rounded it to about a grey level."""
    import onnx
    from onnx import TensorProto, numpy_helper

    model = onnx.load(path)
    graph = model.graph
    values = {i.name: i for i in graph.initializer}
    # Some ONNX Runtime versions keep the exporter's Constant nodes.
    values.update({node.output[0]: attr.t for node in graph.node if node.op_type == "Constant"
                   for attr in node.attribute if attr.name == "value"})
    array = lambda name: numpy_helper.to_array(values[name]).astype(np.float64)
    producer = {out: node for node in graph.node for out in node.output}

    def only_consumer(tensor: str, op_type: str):
        users = [node for node in graph.node if tensor in node.input]
        if len(users) != 1 or users[0].op_type != op_type:
            raise ValueError(f"{path}: expected {tensor} to feed one {op_type}, found "
                             f"{[u.op_type for u in users]}")
        return users[0]

    transpose = only_consumer(graph.input[0].name, "Transpose")
    sub = only_consumer(transpose.output[0], "Sub")
    div = only_consumer(sub.output[0], "Div")
    quantize_input = only_consumer(div.output[0], "QuantizeLinear")
    dequantize = only_consumer(quantize_input.output[0], "DequantizeLinear")
    conv = only_consumer(dequantize.output[0], "Conv")
    mean, spread = array(sub.input[1]), array(div.input[1])
    if mean.min() != mean.max() or spread.min() != spread.max():
        raise ValueError(f"{path}: the input normalisation differs between channels")
    mean, spread = float(mean.flat[0]), float(spread.flat[0])
    zero_point = int(round(mean))
    # (byte - zero_point) / spread is the normalised value less `shift`.
    shift = (zero_point - mean) / spread

    weights_dq, bias_dq = producer[conv.input[1]], producer[conv.input[2]]
    weight_scale = array(weights_dq.input[1])
    weights = (array(weights_dq.input[0]) - array(weights_dq.input[2]).reshape(-1, 1, 1, 1)) \
        * weight_scale.reshape(-1, 1, 1, 1)
    bias = array(bias_dq.input[0]) * array(bias_dq.input[1]) + shift * weights.sum(axis=(1, 2, 3))
    bias_scale = (weight_scale / spread).astype(np.float32)
    values[bias_dq.input[0]].CopyFrom(numpy_helper.from_array(
        np.round(bias / bias_scale).astype(np.int32), bias_dq.input[0]))
    values[bias_dq.input[1]].CopyFrom(numpy_helper.from_array(bias_scale, bias_dq.input[1]))
    graph.initializer.extend([
        numpy_helper.from_array(np.array(1.0 / spread, np.float32), "bgr_scale"),
        numpy_helper.from_array(np.array(zero_point, np.uint8), "bgr_zero_point")])
    dequantize.input[:] = [transpose.output[0], "bgr_scale", "bgr_zero_point"]
    for node in (sub, div, quantize_input):
        graph.node.remove(node)
    graph.input[0].type.tensor_type.elem_type = TensorProto.UINT8
    gone = {sub.output[0], div.output[0], quantize_input.output[0]}
    for info in list(graph.value_info):
        if info.name == transpose.output[0]:
            info.type.tensor_type.elem_type = TensorProto.UINT8
        elif info.name in gone:
            graph.value_info.remove(info)
    used = {name for node in graph.node for name in node.input}
    for value in list(graph.initializer):
        if value.name not in used:
            graph.initializer.remove(value)
    for node in list(graph.node):
        if node.op_type == "Constant" and node.output[0] not in used:
            graph.node.remove(node)
    onnx.checker.check_model(model)
    onnx.save(model, path)


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
    bytes_in(out)
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
