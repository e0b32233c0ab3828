"""Where a rig's offset is best interpolated from a proxy (issue 50): in the add-on, which maps it to
every fine vertex and writes the fine offset attribute (what playback does, frame_display.offset_mesh),
or in the display's node group, which would read the proxy's offsets and interpolate them per fine
vertex (three Sample Index by stored proxy vertex indices, weighted), so that the add-on writes the
proxy's alone. Measured in bpy without the add-on: a point mesh of 1.6M vertices (the twice
subdivided dragon's count) and one of 50k (its proxy's), each fine vertex tied to three neighbouring
proxy vertices in order (as a proxy's are: the gathers stay coherent), a frame's new offsets written
(foreach_set) and the depsgraph evaluated. Per display the median and least over the frames of the
write and of the evaluation.

    .venv/bpy-4.5/bin/python bench/rig_display.py -- --output bench/results/rig_display.json
    .venv/bpy-5.3/bin/python bench/rig_display.py -- --output bench/results/rig_display.json
"""

import argparse
import json
import os
import sys
import time

import bpy
import numpy as np

FINE, PROXY = 1_606_964, 50_000


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--output", required=True)
    parser.add_argument("--frames", type=int, default=60)
    return parser.parse_args(argv)


def point_mesh(name, count, rng):
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(count)
    mesh.vertices.foreach_set("co", rng.random(3 * count, np.float32))
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def geometry_tree(name):
    tree = bpy.data.node_groups.new(name, "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    return tree, tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")


def named(tree, data_type, name):
    node = tree.nodes.new("GeometryNodeInputNamedAttribute")
    node.data_type = data_type
    node.inputs["Name"].default_value = name
    return node.outputs["Attribute"]


def offset_tree():
    """The add-on's display on a rig: Set Position, Offset from the fine attribute."""
    tree, group_in, group_out = geometry_tree("fine offset")
    set_position = tree.nodes.new("GeometryNodeSetPosition")
    tree.links.new(group_in.outputs[0], set_position.inputs["Geometry"])
    tree.links.new(named(tree, "FLOAT_VECTOR", "offset"), set_position.inputs["Offset"])
    tree.links.new(set_position.outputs[0], group_out.inputs[0])
    return tree


def interpolating_tree(proxy):
    """Set Position, Offset = Σ_k w_k × (the proxy's position at index i_k)."""
    tree, group_in, group_out = geometry_tree("proxy offsets interpolated")
    info = tree.nodes.new("GeometryNodeObjectInfo")
    info.transform_space = "ORIGINAL"
    info.inputs["Object"].default_value = proxy
    position = tree.nodes.new("GeometryNodeInputPosition")
    total = None
    for k in range(3):
        sample = tree.nodes.new("GeometryNodeSampleIndex")
        sample.data_type, sample.domain = "FLOAT_VECTOR", "POINT"
        tree.links.new(info.outputs["Geometry"], sample.inputs["Geometry"])
        tree.links.new(position.outputs[0], sample.inputs["Value"])
        tree.links.new(named(tree, "INT", f"index{k}"), sample.inputs["Index"])
        scaled = tree.nodes.new("ShaderNodeVectorMath")
        scaled.operation = "SCALE"
        tree.links.new(sample.outputs[0], scaled.inputs[0])
        tree.links.new(named(tree, "FLOAT", f"weight{k}"), scaled.inputs["Scale"])
        if total is None:
            total = scaled.outputs[0]
        else:
            add = tree.nodes.new("ShaderNodeVectorMath")
            add.operation = "ADD"
            tree.links.new(total, add.inputs[0])
            tree.links.new(scaled.outputs[0], add.inputs[1])
            total = add.outputs[0]
    set_position = tree.nodes.new("GeometryNodeSetPosition")
    tree.links.new(group_in.outputs[0], set_position.inputs["Geometry"])
    tree.links.new(total, set_position.inputs["Offset"])
    tree.links.new(set_position.outputs[0], group_out.inputs[0])
    return tree


def timed(fine, write, frames):
    """Per frame: write(frame), then the depsgraph evaluated; (write, evaluate) ms, median and least."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    depsgraph.update()
    writes, evaluations = [], []
    for frame in range(frames):
        start = time.perf_counter()
        write(frame)
        written = time.perf_counter()
        depsgraph.update()
        fine.evaluated_get(depsgraph).data.vertices[0].co  # the evaluated mesh, read
        writes.append(written - start)
        evaluations.append(time.perf_counter() - written)
    return {
        f"{name}_ms": {
            "median": 1e3 * float(np.median(t)),
            "least": 1e3 * float(np.min(t)),
            "quartiles": [1e3 * float(x) for x in np.percentile(t, [25, 75])],
        }
        for name, t in (("write", writes), ("evaluate", evaluations))
    }


def main():
    args = arguments()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    rng = np.random.default_rng(1)
    fine, proxy = point_mesh("Fine", FINE, rng), point_mesh("Proxy", PROXY, rng)
    attributes = fine.data.attributes
    indices = np.minimum(np.arange(FINE)[:, None] * PROXY // FINE + np.arange(3), PROXY - 1)
    weights = rng.random((FINE, 3), np.float32)
    weights /= weights.sum(axis=1, keepdims=True)
    for k in range(3):
        attributes.new(f"index{k}", "INT", "POINT").data.foreach_set(
            "value", indices[:, k].astype(np.int32)
        )
        attributes.new(f"weight{k}", "FLOAT", "POINT").data.foreach_set("value", weights[:, k])
    offset = attributes.new("offset", "FLOAT_VECTOR", "POINT")
    modifier = fine.modifiers.new("display", "NODES")
    fine_offsets = [1e-3 * rng.random(3 * FINE, np.float32) for _ in range(2)]
    proxy_offsets = [1e-3 * rng.random(3 * PROXY, np.float32) for _ in range(2)]

    def write_fine(frame):
        offset.data.foreach_set("vector", fine_offsets[frame % 2])
        fine.data.update()

    def write_proxy(frame):
        proxy.data.vertices.foreach_set("co", proxy_offsets[frame % 2])
        proxy.data.update()

    load_before = os.getloadavg()
    modifier.node_group = offset_tree()
    fine_figures = timed(fine, write_fine, args.frames)
    modifier.node_group = interpolating_tree(proxy)
    proxy_figures = timed(fine, write_proxy, args.frames)
    result = {
        "blender": bpy.app.version_string,
        "fine_vertices": FINE,
        "proxy_vertices": PROXY,
        "frames": args.frames,
        "fine_offset_attribute": fine_figures,
        "proxy_offsets_interpolated": proxy_figures,
        "load_average": {"before": load_before, "after": os.getloadavg()},
    }
    # One record, a run per Blender: this Blender's replaces its earlier run.
    runs = []
    if os.path.exists(args.output):
        with open(args.output) as found:
            runs = [r for r in json.load(found)["runs"] if r["blender"] != result["blender"]]
    with open(args.output, "w") as out:
        out.write(
            json.dumps(
                {"command": __doc__.split("\n\n")[-1].strip(), "runs": runs + [result]}, indent=1
            )
            + "\n"
        )
    print(json.dumps(result, indent=1))


main()
