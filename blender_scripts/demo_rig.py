"""The demo's secondary motion on a rig (issue 50): a character (Suzanne on a round body) skinned by
an Armature modifier to two bones, Body and Head. The armature object is keyed to jump and land,
and the head to tilt fast and stop; with Dynamics > Follow Rig (its Attach group filled by Fill
Attach from Armature) the ears and the top of the head lag, overshoot and settle back onto what
the Armature modifier makes of the pose. Rendered as a strip of frames: Follow Rig above, the
same frames with the Armature modifier alone below.

Called by demo.py after its stage (camera, light, Cycles) is set up; run inside Blender.
"""

import math

import bpy
import numpy as np
from headless import evaluated_positions
from mathutils import Quaternion, Vector
from rendering import render, side_by_side

#: Catmull-Clark levels of Suzanne (1: about 2k vertices, with the body 2.5k: renders in seconds).
LEVELS = 1
#: The body: a sphere of these radii centred below Suzanne's chin, and the bones: Body through it
#: from its bottom up to the chin, Head from there up through the head.
BODY_CENTRE, BODY_RADII = (0.0, 0.0, -1.85), (0.8, 0.65, 0.75)
BODY_BONE, HEAD_BONE = ((0, 0, -2.4), (0, 0, -1.0)), ((0, 0, -1.0), (0, 0, 0.6))
#: The height of the body's top blended from Body to Head.
NECK = 0.2
#: The jump: up by JUMP between the frames TAKE_OFF and TOP, down again to land on LAND; the head
#: tilts by TILT degrees about the camera's axis between TILT_START and LAND.
JUMP, TAKE_OFF, TOP, LAND = 0.7, 1, 4, 7
TILT, TILT_START = 20, 4
#: Dynamics: the lowest mode's period (frames) and damping ratio.
PERIOD, DAMPING = 7.0, 0.15
#: The frames of the strip, from rest through the landing to the settling; the settle error is read
#: at SETTLED.
STRIP = (1, 3, 5, 6, 8, 9, 11, 15, 40)
SETTLED = 90


def character(levels):
    """Suzanne subdivided `levels` times on a sphere, one mesh object at the origin; returns it and
    how many of its vertices are Suzanne's (they come first)."""
    bpy.ops.mesh.primitive_monkey_add()
    head = bpy.context.object
    modifier = head.modifiers.new("Subdivision", "SUBSURF")
    modifier.levels = levels
    bpy.ops.object.modifier_apply(modifier=modifier.name)
    num_head = len(head.data.vertices)
    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, location=BODY_CENTRE)
    body = bpy.context.object
    body.scale = BODY_RADII
    for obj in bpy.context.view_layer.objects:
        obj.select_set(obj in (head, body))
    bpy.context.view_layer.objects.active = head
    bpy.ops.object.join()
    bpy.ops.object.shade_smooth()
    head.name = "Character"
    return head, num_head


def armature(obj, num_head):
    """The Body and Head bones, the character weighted to them (Suzanne to Head, the body to Body,
    blended across the neck) and skinned by an Armature modifier; obj parented to the armature
    object, so that the character moves with it."""
    rig = bpy.data.objects.new("Character Rig", bpy.data.armatures.new("Character Rig"))
    bpy.context.scene.collection.objects.link(rig)
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="EDIT")
    body = rig.data.edit_bones.new("Body")
    body.head, body.tail = BODY_BONE
    head = rig.data.edit_bones.new("Head")
    head.head, head.tail = HEAD_BONE
    head.parent, head.use_connect = body, True
    bpy.ops.object.mode_set(mode="OBJECT")
    V = np.empty(3 * len(obj.data.vertices))
    obj.data.vertices.foreach_get("co", V)
    z = V.reshape(-1, 3)[:, 2]
    # Suzanne follows Head; the body Body, blended to Head over its top (the neck).
    neck = np.clip((z - HEAD_BONE[0][2]) / NECK + 1.0, 0.0, 1.0)
    neck[:num_head] = 1.0
    for name, weights in (("Head", neck), ("Body", 1.0 - neck)):
        group = obj.vertex_groups.new(name=name)
        for w in np.unique(weights[weights > 0]):
            group.add(np.flatnonzero(weights == w).tolist(), float(w), "REPLACE")
    obj.modifiers.new("Armature", "ARMATURE").object = rig
    obj.parent = rig
    bpy.context.view_layer.objects.active = obj
    return rig


def keyed(rig):
    """The jump on the armature object and the head's tilt about the camera's axis (world y)."""
    rig.keyframe_insert("location", frame=TAKE_OFF)
    rig.keyframe_insert("location", frame=LAND)
    rig.location.z += JUMP
    rig.keyframe_insert("location", frame=TOP)
    rig.location.z -= JUMP
    head = rig.pose.bones["Head"]
    # The world's y axis in the bone's rest frame.
    axis = rig.data.bones["Head"].matrix_local.to_3x3().transposed() @ Vector((0, 1, 0))
    head.keyframe_insert("rotation_quaternion", frame=TILT_START)
    head.rotation_quaternion = Quaternion(axis, math.radians(TILT))
    head.keyframe_insert("rotation_quaternion", frame=LAND)


def follow_rig(obj, rig):
    """Dynamics > Follow Rig as an artist sets it: Fill Attach from Armature, then the eyes (parts
    of their own the bones do not reach) painted into the Attach group."""
    dynamics = obj.modal_deform.dynamics
    dynamics.enabled, dynamics.follow_rig = True, True
    dynamics.period, dynamics.damping = PERIOD, DAMPING
    assert bpy.ops.modal_deform.fill_attach() == {"FINISHED"}
    attach = obj.vertex_groups[dynamics.attach_group]
    held = np.zeros(len(obj.data.vertices), bool)
    for v in obj.data.vertices:
        held[v.index] = any(g.group == attach.index for g in v.groups)
    parts = part_of_vertices(obj)
    eyes = np.flatnonzero(~np.isin(parts, parts[held]))
    attach.add(eyes.tolist(), 1.0, "REPLACE")
    return np.count_nonzero(held), eyes.size


def part_of_vertices(obj):
    """The connected part of each vertex (its edges), as a label per vertex."""
    edges = np.empty(2 * len(obj.data.edges), np.int64)
    obj.data.edges.foreach_get("vertices", edges)
    label = np.arange(len(obj.data.vertices))
    edges = edges.reshape(-1, 2)
    while True:  # label propagation: each vertex takes the smallest label of its neighbours
        low = np.minimum(label[edges[:, 0]], label[edges[:, 1]])
        new = label.copy()
        np.minimum.at(new, edges[:, 0], low)
        np.minimum.at(new, edges[:, 1], low)
        new = new[new]
        if np.array_equal(new, label):
            return label
        label = new


def rig_only(obj):
    """A copy of obj showing the Armature modifier's result alone (no Modal Deform display)."""
    copy = obj.copy()
    bpy.context.scene.collection.objects.link(copy)
    copy.modal_deform.dynamics.enabled = False
    copy.modal_deform.dynamics.cache = None
    for modifier in list(copy.modifiers):
        if modifier.type == "NODES":
            copy.modifiers.remove(modifier)
    return copy


def rig_dynamics(frame_cache, output, width, samples):
    """Build, rig, key and bake the character, play it with Follow Rig and render the STRIP frames
    (`width` pixels wide each) with and without the add-on into OUTPUT/demo_rig.png. Prints the
    figures: the ears' offset from the Armature modifier's result frame by frame, their lag and
    overshoot, and the settle error. Returns the strip's path."""
    scene = bpy.context.scene
    shown = [o for o in scene.objects if o.type == "MESH" and not o.hide_render]
    for obj in shown:
        obj.hide_render = True
    # The camera in front of the character, the sun from the front, above and to the left.
    camera, sun = scene.camera, next(o for o in scene.objects if o.type == "LIGHT")
    saved = (camera.matrix_world.copy(), sun.matrix_world.copy(), camera.data.lens)
    saved += (scene.cycles.samples, scene.render.resolution_x, scene.render.resolution_y)
    camera.location, camera.rotation_euler = (0.0, -13.0, -0.4), (math.pi / 2, 0.0, 0.0)
    sun.rotation_euler = Vector((0.4, 1.0, -0.6)).to_track_quat("-Z", "Y").to_euler()
    camera.data.lens, scene.cycles.samples = 95, samples
    scene.render.resolution_x, scene.render.resolution_y = width, width * 4 // 3

    obj, num_head = character(LEVELS)
    rig = armature(obj, num_head)
    V = np.empty(3 * len(obj.data.vertices))
    obj.data.vertices.foreach_get("co", V)
    V = V.reshape(-1, 3)
    assert bpy.ops.modal_deform.bake() == {"FINISHED"}
    attached, eyes = follow_rig(obj, rig)
    keyed(rig)
    scene.frame_start, scene.frame_end = 1, SETTLED
    scene.frame_set(1)
    reference = rig_only(obj)
    size = np.ptp(V, axis=0).max()
    ears = np.flatnonzero(np.abs(V[:num_head, 0]) > 1.0)

    rows, ear_lag = ([], []), []
    for frame in range(1, SETTLED + 1):
        scene.frame_set(frame)
        offset = evaluated_positions(obj) - evaluated_positions(reference)
        ear_lag.append(offset[ears, 2].mean() / size)
        if frame in STRIP:
            for row, name, (ours, theirs) in zip(
                rows, ("follow", "armature"), ((obj, reference), (reference, obj))
            ):
                ours.hide_render, theirs.hide_render = False, True
                row.append(render(output / f"demo_rig_{name}_{frame:02d}.png"))
    settled = np.abs(evaluated_positions(obj) - evaluated_positions(reference)).max() / size
    ear_lag = np.array(ear_lag)
    print(
        f"rig demo: {len(V)} vertices, {attached} attached by Fill Attach from Armature (+{eyes} of "
        f"the eyes painted in); the jump from frame {TAKE_OFF} to {LAND}, the head's tilt from "
        f"{TILT_START} to {LAND}"
    )
    print(
        "the ears' mean offset from the Armature modifier's result, up (z) as a fraction of the "
        "character's size, frames 1 to 40: " + " ".join(f"{e:+.3f}" for e in ear_lag[:40])
    )
    lag, ahead = ear_lag[: TOP + 1].min(), ear_lag[TOP:LAND].max()
    below = ear_lag[LAND : LAND + 8].min()
    print(
        f"the ears lag {-lag:.3f} of the size behind the rig going up, swing {ahead:.3f} ahead of it "
        f"when it turns down and overshoot {-below:.3f} below it after the landing; settle error "
        f"at frame {SETTLED}: {settled:.1e} of the size"
    )
    cache = frame_cache.get(obj)
    print(f"{len(cache)} frames cached in {cache.nbytes() / 1024:.1f} KB")
    for made in (reference, obj, rig):
        bpy.data.objects.remove(made)
    for obj in shown:
        obj.hide_render = False
    camera.matrix_world, sun.matrix_world, camera.data.lens = saved[:3]
    scene.cycles.samples, scene.render.resolution_x, scene.render.resolution_y = saved[3:]
    strip = output / "demo_rig.png"
    # Pixels are bottom row first: the rig alone (rows[1]) is put first to be drawn below.
    side_by_side([np.concatenate((below, above)) for above, below in zip(*rows)], strip)
    return strip
