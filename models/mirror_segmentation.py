#!/usr/bin/env python3
"""Wraps a cable segmentation network so that it also sees the image mirrored.

The wrapped network runs the network twice, on the image and on its mirror
image (left for right), mirrors the second probability map back, and gives
the mean of the two. Its contract is the network's own (models/README.md,
"Contract"), so the pipeline runs it as it runs any other model: it takes
twice the network's time and, on busy scenes, counts more cables right
(models/README.md, "The mirrored network"). The weights are shared, not
copied. Run from the project's root, e.g.
    .venv-train/bin/python models/mirror_segmentation.py models/cable_segmentation.onnx \
        --out models/cable_segmentation_mirrored.onnx
"""

from __future__ import annotations

import argparse
import copy
import sys
from pathlib import Path

import numpy as np
import onnx
from onnx import helper, numpy_helper

INPUT = "bgr"
OUTPUT = "cable_probability"


def flip_width(name: str, out: str, width_axis: str) -> onnx.NodeProto:
    """A Slice that reverses `name` along the axis named by the initializer `width_axis`."""
    return helper.make_node("Slice", [name, "mirror_start", "mirror_end", width_axis, "mirror_step"], [out],
                            name=f"mirror_{out}")


def mirrored(model: onnx.ModelProto) -> onnx.ModelProto:
    """`model` run on its input and on the input mirrored along its width,
    the second output mirrored back, and the two averaged."""
    graph = model.graph
    if [i.name for i in graph.input] != [INPUT] or [o.name for o in graph.output] != [OUTPUT]:
        raise ValueError(f"expected one input {INPUT!r} and one output {OUTPUT!r}")
    shared = {w.name for w in graph.initializer}
    constants = [numpy_helper.from_array(np.array([v], dtype=np.int64), name) for name, v in [
        ("mirror_start", -1), ("mirror_end", np.iinfo(np.int64).min), ("mirror_step", -1),
        ("mirror_input_width_axis", 2),    # [1, h, w, 3]
        ("mirror_output_width_axis", 3),   # [1, 1, h, w]
    ]]
    nodes = [flip_width(INPUT, "mirror_bgr", "mirror_input_width_axis")]
    for prefix, source in [("plain_", INPUT), ("mirror_", "mirror_bgr")]:
        def rename(name: str) -> str:
            if name == "" or name in shared:
                return name
            return source if name == INPUT else prefix + name
        for node in graph.node:
            copied = copy.deepcopy(node)
            copied.name = prefix + node.name
            copied.input[:] = [rename(n) for n in node.input]
            copied.output[:] = [rename(n) for n in node.output]
            nodes.append(copied)
    nodes.append(flip_width("mirror_" + OUTPUT, "mirror_back", "mirror_output_width_axis"))
    nodes.append(helper.make_node("Mean", ["plain_" + OUTPUT, "mirror_back"], [OUTPUT], name="mirror_mean"))
    out_graph = helper.make_graph(nodes, graph.name, graph.input, graph.output,
                                  list(graph.initializer) + constants)
    out = helper.make_model(out_graph, opset_imports=model.opset_import, ir_version=model.ir_version)
    out.doc_string = "the network on the image and on its mirror image, averaged (models/mirror_segmentation.py)"
    onnx.checker.check_model(out)
    return out


def main() -> int:
    here = Path(__file__).resolve().parent
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("model", type=Path, nargs="?", default=here / "cable_segmentation.onnx",
                        help="the network to wrap (default: models/cable_segmentation.onnx)")
    parser.add_argument("--out", type=Path, default=here / "cable_segmentation_mirrored.onnx",
                        help="the wrapped network (default: models/cable_segmentation_mirrored.onnx)")
    args = parser.parse_args()
    if not args.model.is_file():
        print(f"no network at {args.model}", file=sys.stderr)
        return 2
    try:
        out = mirrored(onnx.load(str(args.model)))
    except ValueError as e:
        print(f"{args.model}: {e}", file=sys.stderr)
        return 2
    args.out.parent.mkdir(parents=True, exist_ok=True)
    onnx.save(out, str(args.out))
    print(f"wrote {args.out}: {args.model.name} on the image and its mirror image, averaged")
    return 0


if __name__ == "__main__":
    sys.exit(main())
