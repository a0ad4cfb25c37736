"""flapper's policies as ONNX (docs/deploy.md), written with the `onnx` library.

The graph is the deterministic action exactly as flapper flies it, as explicit nodes: the observation
normalizer (Sub the mean, Mul by 1 / (std + epsilon), Clip to +-10), the actor's dense layers (Gemm) with
their activation (Elu) between them, and the environment's Clip of the action to [-1, 1]. Input `obs`
float32 [batch, 540], output `actions` float32 [batch, 5]; the facts a robot needs (observation layout,
joints and their ranges, rates, filter cutoff, training steps) are the model's metadata.

    flapper.Policy.load("policies/final/policy.safetensors").export_onnx("policy.onnx")
    python -m flapper.onnx_export --policy policies/final/policy.safetensors --out policy.onnx
"""

import argparse
import os
import sys

import numpy as np

OPSET = 17
# The IR version of opset 17 (onnx 1.12): read by every onnxruntime since 1.12.
IR_VERSION = 8

ACTIVATIONS = {"elu": ("Elu", {"alpha": 1.0}), "tanh": ("Tanh", {})}


def build_model(policy, metadata):
    """The ONNX model of `policy` (a flapper.Policy) with `metadata` ((key, value) string pairs)."""
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    arrays = policy.arrays()
    layers = arrays["layers"]
    observation_size, action_size = len(arrays["normalizer_mean"]), len(layers[-1][1])
    clip = float(arrays["normalizer_clip"])
    initializers = [
        numpy_helper.from_array(np.asarray(arrays["normalizer_mean"], np.float32), "normalizer_mean"),
        numpy_helper.from_array(np.asarray(arrays["normalizer_scale"], np.float32), "normalizer_scale"),
        numpy_helper.from_array(np.float32(-clip), "normalizer_clip_low"),
        numpy_helper.from_array(np.float32(clip), "normalizer_clip_high"),
        numpy_helper.from_array(np.float32(-1.0), "action_low"),
        numpy_helper.from_array(np.float32(1.0), "action_high"),
    ]
    nodes = [
        helper.make_node("Sub", ["obs", "normalizer_mean"], ["obs_centred"], name="normalizer_subtract_mean"),
        helper.make_node("Mul", ["obs_centred", "normalizer_scale"], ["obs_scaled"], name="normalizer_divide_by_std"),
        helper.make_node(
            "Clip", ["obs_scaled", "normalizer_clip_low", "normalizer_clip_high"], ["obs_normalized"],
            name="normalizer_clip",
        ),
    ]
    activation, attributes = ACTIVATIONS[arrays["activation"]]
    hidden = "obs_normalized"
    for k, (weight, bias) in enumerate(layers, start=1):
        initializers += [
            numpy_helper.from_array(np.asarray(weight, np.float32), f"actor.layer{k}.weight"),
            numpy_helper.from_array(np.asarray(bias, np.float32), f"actor.layer{k}.bias"),
        ]
        dense = f"layer{k}" if k < len(layers) else "action_mean"
        nodes.append(
            helper.make_node(
                "Gemm", [hidden, f"actor.layer{k}.weight", f"actor.layer{k}.bias"], [dense], name=f"actor_layer{k}",
                transB=1,
            )
        )
        hidden = dense
        if k < len(layers):
            hidden = f"hidden{k}"
            nodes.append(helper.make_node(activation, [dense], [hidden], name=f"actor_{activation.lower()}{k}", **attributes))
    nodes.append(helper.make_node("Clip", [hidden, "action_low", "action_high"], ["actions"], name="action_clip"))
    graph = helper.make_graph(
        nodes,
        "flapper_policy",
        [helper.make_tensor_value_info("obs", TensorProto.FLOAT, ["batch", observation_size])],
        [helper.make_tensor_value_info("actions", TensorProto.FLOAT, ["batch", action_size])],
        initializers,
    )
    model = helper.make_model(
        graph, opset_imports=[helper.make_opsetid("", OPSET)], producer_name="flapper", ir_version=IR_VERSION
    )
    model.doc_string = (
        "A flapper flight policy's deterministic action: obs (raw observations, the layout in the metadata) -> "
        "normalizer (clip((obs - mean) * scale, -10, 10)) -> actor MLP -> actions clipped to [-1, 1]; joint "
        "target (rad) = action x action_half_range_rad, through the filter_cutoff_hz low-pass into PD servos "
        "(docs/deploy.md in flapper)."
    )
    helper.set_model_props(model, dict(metadata))
    onnx.checker.check_model(model, full_check=True)
    return model


def write_onnx(policy, path, metadata):
    """Writes `build_model(policy, metadata)` to `path` whole or not at all (a temporary file, renamed)."""
    data = build_model(policy, metadata).SerializeToString()
    temporary = f"{path}.tmp-{os.getpid()}"
    try:
        with open(temporary, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.remove(temporary)


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m flapper.onnx_export", description=__doc__.split("\n\n")[0])
    parser.add_argument("--policy", required=True, help="a policy file or checkpoint (.safetensors)")
    parser.add_argument("--out", required=True, help="the ONNX file to write (must not exist)")
    parser.add_argument("--model", help="the robot's MJCF, for the joint ranges (default: the shipped robot)")
    args = parser.parse_args(argv)
    from flapper import Policy

    try:
        Policy.load(args.policy).export_onnx(args.out, args.model)
    except ValueError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
