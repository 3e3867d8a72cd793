#!/usr/bin/env python3
"""Wraps a cable segmentation network so that it also sees the image mirrored.

The wrapped network runs the network on the image and on its mirror
images, mirrors each probability map back, and gives their mean. With two
looks (the default) the mirror image is left for right; with four, also
top for bottom and both ways; with eight, also each of those four with rows
for columns. Its contract is the network's own (models/README.md,
"Contract"), so the pipeline runs it as it runs any other model: it takes
as many times the network's time as it has looks and, on busy scenes,
counts more cables right (models/history.md, "The mirrored network", "The
busy network seen four ways"). The weights are shared, not copied. Run
from the project's root, e.g.
    .venv-train/bin/python models/mirror_segmentation.py models/cable_segmentation.onnx \
        --out models/cable_segmentation_mirrored.onnx
    .venv-train/bin/python models/mirror_segmentation.py models/cable_segmentation_busy.onnx \
        --looks 4 --out models/cable_segmentation_busy_mirrored.onnx
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

# Each look: its name's prefix, whether rows and columns are swapped, and
# the axes mirrored after that ("h": top for bottom, "w": left for right).
LOOKS = [
    ("plain_", False, ()),
    ("mirror_", False, ("w",)),
    ("flip_", False, ("h",)),
    ("turn_", False, ("h", "w")),
    ("swap_", True, ()),
    ("swap_mirror_", True, ("w",)),
    ("swap_flip_", True, ("h",)),
    ("swap_turn_", True, ("h", "w")),
]


def flip(name: str, out: str, axis: str) -> onnx.NodeProto:
    """A Slice that reverses `name` along the axis named by the initializer `axis`."""
    return helper.make_node("Slice", [name, "mirror_start", "mirror_end", axis, "mirror_step"], [out],
                            name=f"mirror_{out}")


def steps(source: str, out: str, swap: bool, axes: tuple[str, ...], side: str, perm: list[int]) -> list[onnx.NodeProto]:
    """Nodes from `source` to `out`: rows and columns swapped (by `perm`)
    where `swap`, each of `axes` reversed, in that order on the input side
    and the reverse order on the output side (`side`)."""
    ops = [("swap", None)] if swap else []
    ops += [("flip", f"mirror_{side}_{'width' if a == 'w' else 'height'}_axis") for a in axes]
    if side == "output":
        ops.reverse()
    nodes, name = [], source
    for k, (op, axis) in enumerate(ops):
        to = out if k == len(ops) - 1 else f"{out}_{k}"
        if op == "swap":
            nodes.append(helper.make_node("Transpose", [name], [to], name=f"swap_{to}", perm=perm))
        else:
            nodes.append(flip(name, to, axis))
        name = to
    return nodes


def mirrored(model: onnx.ModelProto, looks: int = 2) -> onnx.ModelProto:
    """`model` run on its input and on the input's first `looks` - 1 mirror
    images (2, 4 or 8 looks), each output mirrored back, and all averaged."""
    graph = model.graph
    if [i.name for i in graph.input] != [INPUT] or [o.name for o in graph.output] != [OUTPUT]:
        raise ValueError(f"expected one input {INPUT!r} and one output {OUTPUT!r}")
    if looks not in (2, 4, 8):
        raise ValueError(f"looks must be 2, 4 or 8, not {looks}")
    chosen = LOOKS[:looks]
    shared = {w.name for w in graph.initializer}
    axes = [("mirror_input_width_axis", 2), ("mirror_output_width_axis", 3)]   # [1, h, w, 3], [1, 1, h, w]
    if looks > 2:
        axes += [("mirror_input_height_axis", 1), ("mirror_output_height_axis", 2)]
    constants = [numpy_helper.from_array(np.array([v], dtype=np.int64), name) for name, v in [
        ("mirror_start", -1), ("mirror_end", np.iinfo(np.int64).min), ("mirror_step", -1), *axes,
    ]]
    nodes = []
    for prefix, swap, flips in chosen[1:]:
        nodes += steps(INPUT, prefix + INPUT, swap, flips, "input", [0, 2, 1, 3])
    for prefix, _, _ in chosen:
        source = INPUT if prefix == "plain_" else prefix + INPUT

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
    for prefix, swap, flips in chosen[1:]:
        nodes += steps(prefix + OUTPUT, prefix + "back", swap, flips, "output", [0, 1, 3, 2])
    backs = [prefix + "back" for prefix, _, _ in chosen[1:]]
    nodes.append(helper.make_node("Mean", ["plain_" + OUTPUT, *backs], [OUTPUT], name="mirror_mean"))
    out_graph = helper.make_graph(nodes, graph.name, graph.input, graph.output,
                                  list(graph.initializer) + constants)
    out = helper.make_model(out_graph, opset_imports=model.opset_import, ir_version=model.ir_version)
    out.doc_string = ("the network on the image and on its mirror image, averaged" if looks == 2 else
                      f"the network on the image and on {looks - 1} mirror images of it, averaged") + \
        " (models/mirror_segmentation.py)"
    onnx.checker.check_model(out)
    return out


def main() -> int:
    here = Path(__file__).resolve().parent
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("model", type=Path, nargs="?", default=here / "cable_segmentation.onnx",
                        help="the network to wrap (default: models/cable_segmentation.onnx)")
    parser.add_argument("--looks", type=int, choices=(2, 4, 8), default=2,
                        help="the image and its mirror images seen: 2 (left for right), 4 (also top for "
                             "bottom, and both), 8 (also each with rows for columns) (default: 2)")
    parser.add_argument("--out", type=Path, default=here / "cable_segmentation_mirrored.onnx",
                        help="the wrapped network (default: models/cable_segmentation_mirrored.onnx)")
    args = parser.parse_args()
    if not args.model.is_file():
        print(f"no network at {args.model}", file=sys.stderr)
        return 2
    try:
        out = mirrored(onnx.load(str(args.model)), args.looks)
    except ValueError as e:
        print(f"{args.model}: {e}", file=sys.stderr)
        return 2
    args.out.parent.mkdir(parents=True, exist_ok=True)
    onnx.save(out, str(args.out))
    print(f"wrote {args.out}: {args.model.name} on the image and {args.looks - 1} mirror image(s) of it, averaged")
    return 0


if __name__ == "__main__":
    sys.exit(main())
