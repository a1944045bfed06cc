"""Writing an ONNX graph node by node, and a policy network's layers as nodes (float32, as trained)."""

from __future__ import annotations

import numpy as np

OPSET = 17
FLOAT, DOUBLE = 1, 11  # onnx.TensorProto.FLOAT, DOUBLE


class Graph:
    """A few helpers to write an ONNX graph node by node."""

    def __init__(self) -> None:
        self.nodes: list = []
        self.constants: list = []

    def constant(self, name: str, value: np.ndarray | float, dtype=np.float64) -> str:
        from onnx import numpy_helper

        self.constants.append(numpy_helper.from_array(np.asarray(value, dtype=dtype), name))
        return name

    def node(self, op: str, inputs: list[str], output: str, **attributes) -> str:
        from onnx import helper

        self.nodes.append(helper.make_node(op, inputs, [output], name=output, **attributes))
        return output

    def columns(self, source: str, start: int, stop: int, output: str) -> str:
        starts = self.constant(f"{output}_start", [start], np.int64)
        stops = self.constant(f"{output}_stop", [stop], np.int64)
        axes = self.constant(f"{output}_axis", [1], np.int64)
        return self.node("Slice", [source, starts, stops, axes], output)

    def affine(self, source: str, matrix: np.ndarray, output: str) -> str:
        """source @ matrix.T"""
        return self.node("MatMul", [source, self.constant(f"{output}_matrix", matrix.T)], output)

    def clip(self, source: str, low: float, high: float, *, output: str, dtype=np.float64) -> str:
        low_name = self.constant(f"{output}_low", low, dtype)
        high_name = self.constant(f"{output}_high", high, dtype)
        return self.node("Clip", [source, low_name, high_name], output)


def network(g: Graph, actor, x: str, prefix: str) -> str:
    """The actor's layers on `x` (float32), node names starting with `prefix`; its tanh is `squashed`'s."""
    for index, layer in enumerate(actor.layers):
        weight = (
            g.constant(f"layer{index}_weight", layer.weight, np.float32)
            if not prefix
            else f"layer{index}_weight"
        )
        bias = (
            g.constant(f"layer{index}_bias", layer.bias, np.float32) if not prefix else f"layer{index}_bias"
        )
        x = g.node("Gemm", [x, weight, bias], f"{prefix}layer{index}", transB=1)
        if layer.activation is not None:
            x = activation(g, layer.activation, x, f"{prefix}layer{index}_{layer.activation.lower()}")
    return x


def squashed(g: Graph, actor, x: str) -> str:
    """tanh on the actor's output if it squashes (after the odd combination)."""
    return g.node("Tanh", [x], "squashed") if actor.squash else x


def activation(g: Graph, name: str, x: str, output: str) -> str:
    if name == "ReLU":
        return g.node("Relu", [x], output)
    if name == "Tanh":
        return g.node("Tanh", [x], output)
    if name == "ELU":
        return g.node("Elu", [x], output, alpha=1.0)
    if name == "LeakyReLU":
        return g.node("LeakyRelu", [x], output, alpha=0.01)
    half = g.node("Div", [x, g.constant(f"{output}_sqrt2", np.sqrt(2.0), np.float32)], f"{output}_scaled")
    erf = g.node(
        "Add",
        [g.node("Erf", [half], f"{output}_erf"), g.constant(f"{output}_one", 1.0, np.float32)],
        f"{output}_1erf",
    )
    return g.node(
        "Mul",
        [g.node("Mul", [x, erf], f"{output}_x1erf"), g.constant(f"{output}_half", 0.5, np.float32)],
        output,
    )
