"""Rigs the Blender test scripts build: a chain of bones along z, weights along it, the skinning.
Run inside Blender (imports bpy)."""

import bpy
import numpy as np


def chain_armature(name, bones, length, matrix_world=None):
    """An armature object in the scene, placed at `matrix_world` (default: identity), of `bones`
    connected bones Bone0, Bone1, … along its z axis from 0 to `length`. The active object stays."""
    view_layer = bpy.context.view_layer
    active = view_layer.objects.active
    armature = bpy.data.objects.new(name, bpy.data.armatures.new(name))
    bpy.context.scene.collection.objects.link(armature)
    if matrix_world is not None:
        armature.matrix_world = matrix_world
    view_layer.objects.active = armature
    bpy.ops.object.mode_set(mode="EDIT")
    parent = None
    for b in range(bones):
        bone = armature.data.edit_bones.new(f"Bone{b}")
        bone.head, bone.tail = (0, 0, b * length / bones), (0, 0, (b + 1) * length / bones)
        bone.parent, bone.use_connect = parent, parent is not None
        parent = bone
    bpy.ops.object.mode_set(mode="OBJECT")
    view_layer.objects.active = active
    return armature


def chain_weights(z, bones, length):
    """(n, bones): a partition of unity along z, linear between the bones' centres."""
    centres = (np.arange(bones) + 0.5) * length / bones
    W = np.zeros((len(z), bones))
    k = np.clip(np.searchsorted(centres, z) - 1, 0, bones - 2)
    t = np.clip((z - centres[k]) / (centres[k + 1] - centres[k]), 0.0, 1.0)
    W[np.arange(len(z)), k], W[np.arange(len(z)), k + 1] = 1 - t, t
    return W


def skin(obj, armature, W):
    """obj skinned to `armature` by the weights W (n, bones): vertex groups named like the bones
    (Bone0, …) holding W's non-zero weights, and an Armature modifier, returned."""
    for b in range(W.shape[1]):
        name = f"Bone{b}"
        group = obj.vertex_groups.get(name) or obj.vertex_groups.new(name=name)
        for i in np.flatnonzero(W[:, b] > 0):
            group.add([int(i)], float(W[i, b]), "REPLACE")
    modifier = obj.modifiers.new("Armature", "ARMATURE")
    modifier.object = armature
    return modifier
