"""Where playback shows a frame: a point attribute of the mesh that a Geometry Nodes modifier, first
in the object's stack, sets the positions from (Set Position from a Named Attribute); while the
timeline plays (Blender 4+), a stand-in mesh without shape keys whose positions are the frame, which
the modifier reads instead (frame_mesh(stand_in=True)) because Blender evaluates it faster
(bench/results/playback.json, "evaluate_ms" of "dynamic_step" against "dynamic_step_still").

On a rig (Follow Rig, rig.py) the display is an offset instead (offset_mesh): Set Position adds
a rest-space displacement to the positions as the shape keys leave them, first in the stack and so
before the Armature modifier, which skins it; no stand-in there.

The artist's positions and shape keys are never written. Where the attribute is missing the modifier
leaves the positions alone (the Named Attribute node's "Exists" is Set Position's selection; Blender
3.4 has no such output: there a BOOLEAN point attribute, SHOWN, written True with the attribute, is
the selection, and goes with it). The stand-in goes (end_stand_in) when playback stops, before a
file is saved, when the artist edits the mesh, leaves Object Mode or puts a modifier before the
display's, and after a file is loaded or an undo while the timeline is still. The display goes
(remove) when the cache is freed or no longer plays, when a pose shows (pose.posing.uncover, which
timeline.register hands it) and when the add-on is disabled. Why, and what a file written
mid-playback holds: docs/design.md, "How a pose is shown and kept".
"""

import bpy
import numpy as np

from .. import mesh_io

#: The modifier on an object that plays a cache, and its node group (one per file, shared), which
#: carries the ID property MARK: the modifier is the one whose node group has it, whatever their names.
MODIFIER = "Modal Deform Playback"
NODE_GROUP = "Modal Deform Playback"
MARK = "modal_deform_playback"
#: The FLOAT_VECTOR point attribute holding the frame's positions (object space).
ATTRIBUTE = "modal_deform_playback"
#: Blender 3.4's selection (see the module's comment): True on every point where ATTRIBUTE holds a frame.
SHOWN = "modal_deform_playback_shown"
#: On a rig (playback/rig.py): the FLOAT_VECTOR point attribute holding the frame's rest-space
#: offset, and the ID property marking the node group that adds it (offset_node_group).
OFFSET_ATTRIBUTE = "modal_deform_offset"
OFFSET = "modal_deform_offset"
#: ID property of a stand-in's object, mesh and node group (one each per object that plays): the name
#: of the object it stands in for.
STAND_IN = "modal_deform_stand_in"


def _named_attribute(tree, data_type, name):
    node = tree.nodes.new("GeometryNodeInputNamedAttribute")
    node.data_type = data_type
    node.inputs["Name"].default_value = name
    # Before Blender 4.0 the node has an "Attribute" output per data type, data_type's enabled.
    return node, next(o for o in node.outputs if o.name == "Attribute" and o.enabled)


def _geometry_group(name):
    """A new node group of the display (MARK) taking and giving a geometry."""
    tree = bpy.data.node_groups.new(name, "GeometryNodeTree")
    tree[MARK] = True
    if hasattr(tree, "interface"):  # Blender 4.0+
        tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
        tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    else:
        tree.inputs.new("NodeSocketGeometry", "Geometry")
        tree.outputs.new("NodeSocketGeometry", "Geometry")
    return tree


def node_group():
    """The file's node group (made on first use): Geometry → Set Position (Position: ATTRIBUTE,
    Selection: where it exists) → Geometry."""
    tree = next(
        (
            g
            for g in bpy.data.node_groups
            if g.library is None and g.get(MARK) and not g.get(STAND_IN) and not g.get(OFFSET)
        ),
        None,
    )
    if tree is not None:
        return tree
    tree = _geometry_group(NODE_GROUP)
    group_in, group_out = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
    set_position = tree.nodes.new("GeometryNodeSetPosition")
    positions, position_output = _named_attribute(tree, "FLOAT_VECTOR", ATTRIBUTE)
    if "Exists" in positions.outputs:
        selection = positions.outputs["Exists"]
    else:
        selection = _named_attribute(tree, "BOOLEAN", SHOWN)[1]
    tree.links.new(group_in.outputs[0], set_position.inputs["Geometry"])
    tree.links.new(position_output, set_position.inputs["Position"])
    tree.links.new(selection, set_position.inputs["Selection"])
    tree.links.new(set_position.outputs[0], group_out.inputs[0])
    return tree


def _add_modifier(obj, tree=None):
    """The modifier, new, first in obj's stack (before the artist's modifiers: they act on the frame),
    hidden in Edit Mode (which shows the mesh being edited); `tree`: its node group (node_group())."""
    modifier = obj.modifiers.new(MODIFIER, "NODES")
    modifier.node_group = tree or node_group()
    modifier.show_in_editmode = modifier.show_on_cage = False
    if len(obj.modifiers) > 1:
        if hasattr(obj.modifiers, "move"):  # Blender 4.0+
            obj.modifiers.move(len(obj.modifiers) - 1, 0)
        else:
            with bpy.context.temp_override(object=obj):
                bpy.ops.object.modifier_move_to_index(modifier=modifier.name, index=0)
    return modifier


def modifier_of(obj):
    """obj's display modifier, or None."""
    return next(
        (
            m
            for m in obj.modifiers
            if m.type == "NODES" and m.node_group is not None and m.node_group.get(MARK)
        ),
        None,
    )


def positions(obj, stand_in=False):
    """Where the frame shown on obj goes: frame_positions(frame_mesh(obj, stand_in)). Use at once,
    then update the mesh."""
    return frame_positions(frame_mesh(obj, stand_in))


def frame_mesh(obj, stand_in=False):
    """The mesh obj's frame is written into: its stand-in's while it has one (made first when
    `stand_in`: the timeline plays), else obj's own, with ATTRIBUTE (made if needed, with the modifier
    that shows it). No stand-in while the artist has put a modifier before the display's."""
    modifier = modifier_of(obj) or _add_modifier(obj)
    found = _stand_in(modifier.node_group)
    # A stand-in replaces the geometry it is given: only first in the stack does it show what the attribute shows.
    first = obj.modifiers[0] == modifier
    if modifier.node_group.get(STAND_IN) and (
        found is None or not first
    ):  # its object deleted, or not first
        end_stand_in(obj)
        found = None
    if found is None and stand_in and first:
        found = _make_stand_in(obj, modifier)
    if found is not None:
        return found.data
    mesh = obj.data
    attributes = mesh.attributes
    if attributes.get(ATTRIBUTE) is None:
        attributes.new(ATTRIBUTE, "FLOAT_VECTOR", "POINT")
        if _reads_shown(modifier.node_group):
            shown = attributes.get(SHOWN) or attributes.new(SHOWN, "BOOLEAN", "POINT")
            shown.data.foreach_set("value", np.ones(len(mesh.vertices), bool))
    return mesh


def offset_node_group():
    """The file's node group of the display on a rig (made on first use): Geometry → Set Position
    (Offset: OFFSET_ATTRIBUTE, zero where it is missing; Position as the geometry has it) →
    Geometry. An offset of zero leaves every position's bits as they are."""
    tree = next(
        (g for g in bpy.data.node_groups if g.library is None and g.get(MARK) and g.get(OFFSET)),
        None,
    )
    if tree is not None:
        return tree
    tree = _geometry_group(NODE_GROUP + " Offset")
    tree[OFFSET] = True
    group_in, group_out = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
    set_position = tree.nodes.new("GeometryNodeSetPosition")
    tree.links.new(group_in.outputs[0], set_position.inputs["Geometry"])
    tree.links.new(
        _named_attribute(tree, "FLOAT_VECTOR", OFFSET_ATTRIBUTE)[1], set_position.inputs["Offset"]
    )
    tree.links.new(set_position.outputs[0], group_out.inputs[0])
    return tree


def shows_offset(obj):
    """Whether obj's display is the offset on a rig (offset_mesh)."""
    modifier = modifier_of(obj)
    return modifier is not None and bool(modifier.node_group.get(OFFSET))


def offset_mesh(obj):
    """The mesh whose OFFSET_ATTRIBUTE (made if needed, zero) the display on a rig adds to the
    positions, first in obj's stack (before its Armature modifier: the skinning carries the
    offset); the display of positions (frame_mesh) goes first. No stand-in: the offset adds to the
    mesh as its shape keys leave it."""
    modifier = modifier_of(obj)
    if modifier is not None and not modifier.node_group.get(OFFSET):
        remove(obj)
        modifier = None
    if modifier is None:
        _add_modifier(obj, offset_node_group())
    mesh = obj.data
    if mesh.attributes.get(OFFSET_ATTRIBUTE) is None:
        mesh.attributes.new(OFFSET_ATTRIBUTE, "FLOAT_VECTOR", "POINT")
    return mesh


def offset_values(mesh):
    """The #V by 3 float32 view of OFFSET_ATTRIBUTE's values in `mesh` (offset_mesh). Use at once,
    then update the mesh."""
    return mesh_io.attribute_co(mesh, mesh.attributes[OFFSET_ATTRIBUTE])


def frame_positions(mesh):
    """The frame's #V by 3 float32 view of Blender's array in `mesh` (frame_mesh): a stand-in's
    positions, else ATTRIBUTE's values (mesh_io). Use at once, then update the mesh."""
    if mesh.get(STAND_IN):
        return mesh_io.vertex_positions(mesh)
    return mesh_io.attribute_co(mesh, mesh.attributes[ATTRIBUTE])


def _make_stand_in(obj, modifier):
    """Have obj's `modifier` read a stand-in of its own, showing the frame shown now; returns it."""
    frame = positions(obj).copy()
    mesh = obj.data.copy()
    for name in (ATTRIBUTE, SHOWN):
        if name in mesh.attributes:
            mesh.attributes.remove(mesh.attributes[name])
    if (
        mesh.shape_keys is not None
    ):  # the copy's own (Object.shape_key_clear leaves it in Blender 4.2 to 4.5)
        bpy.data.batch_remove([mesh.shape_keys])
    # Named with a leading "." as Blender's hidden datablocks: out of the artist's menus.
    stand_in = bpy.data.objects.new(f".{obj.name} (Modal Deform playback)", mesh)
    mesh.name = stand_in.name
    mesh_io.vertex_positions(mesh)[...] = frame
    tree = _geometry_group(f".{NODE_GROUP}: {obj.name}")
    for block in (stand_in, mesh, tree):
        block[STAND_IN] = obj.name
    group_out = tree.nodes.new("NodeGroupOutput")
    info = tree.nodes.new("GeometryNodeObjectInfo")
    info.transform_space = "ORIGINAL"  # the stand-in's geometry as it is, shared rather than copied
    info.inputs["Object"].default_value = stand_in
    tree.links.new(info.outputs["Geometry"], group_out.inputs[0])
    modifier.node_group = tree
    return stand_in


def end_stand_in(obj):
    """Have obj's modifier read ATTRIBUTE again, holding the stand-in's frame, and delete the stand-in."""
    if not has_stand_in(obj):
        return
    modifier = modifier_of(obj)
    tree = modifier.node_group
    stand_in = _stand_in(tree)
    frame = mesh_io.vertex_positions(stand_in.data).copy() if stand_in is not None else None
    modifier.node_group = node_group()
    bpy.data.node_groups.remove(tree)
    _delete_stand_ins()
    # In Edit Mode the mesh's arrays are not the ones edited: the next frame shown writes ATTRIBUTE.
    mesh = obj.data
    if (
        frame is not None
        and mesh.library is None
        and not mesh.is_editmode
        and len(frame) == len(mesh.vertices)
    ):
        positions(obj)[...] = frame
        mesh.update()


def end_stand_ins():
    """end_stand_in for every object of the file, and delete the stand-ins left without one."""
    for obj in [
        o for o in bpy.data.objects if o.type == "MESH" and o.library is None and has_stand_in(o)
    ]:
        end_stand_in(obj)
    _delete_stand_ins()


def has_stand_in(obj):
    """Whether obj's display is made to read a stand-in (its node group one of a stand-in's)."""
    modifier = modifier_of(obj)
    return modifier is not None and bool(modifier.node_group.get(STAND_IN))


def _stand_in(tree):
    """The stand-in object the display's node group `tree` reads, or None (it reads ATTRIBUTE)."""
    if not tree.get(STAND_IN):
        return None
    info = next((node for node in tree.nodes if node.bl_idname == "GeometryNodeObjectInfo"), None)
    return info.inputs["Object"].default_value if info is not None else None


def _delete_stand_ins():
    """Delete the stand-ins no modifier reads (node groups, then the objects and meshes they read)."""
    for collection in (bpy.data.node_groups, bpy.data.objects, bpy.data.meshes):
        for block in [
            b for b in collection if b.library is None and b.get(STAND_IN) and not b.users
        ]:
            collection.remove(block)


def _reads_shown(tree):
    """Whether the node group takes its selection from SHOWN (made in Blender 3.4)."""
    return any(
        node.bl_idname == "GeometryNodeInputNamedAttribute"
        and node.inputs["Name"].default_value == SHOWN
        for node in tree.nodes
    )


def in_use():
    """Whether an object of the file may show the display (a node group of it has users): when not,
    the frame handler looks at no object for a display to take away."""
    return any(tree.users and tree.get(MARK) for tree in bpy.data.node_groups)


def shows(obj):
    """Whether obj carries the display (its modifier or attribute)."""
    return obj.type == "MESH" and (ATTRIBUTE in obj.data.attributes or modifier_of(obj) is not None)


def remove(obj):
    """Take the display off obj (its modifier and attributes): the mesh shows what it shows without it."""
    if not shows(obj):
        return
    modifier = modifier_of(obj)
    if modifier is not None:
        stand_in = modifier.node_group.get(STAND_IN)
        obj.modifiers.remove(modifier)
        if stand_in:
            _delete_stand_ins()
    mesh = obj.data
    if (
        mesh.library is not None
    ):  # a linked mesh's attribute is the library's: the modifier alone goes
        return
    for name in (ATTRIBUTE, SHOWN, OFFSET_ATTRIBUTE):
        attribute = mesh.attributes.get(name)
        if attribute is not None:
            mesh.attributes.remove(attribute)
    mesh.update()


def remove_all():
    """Take the display off every object of the file, and its node group (disabling the add-on)."""
    for obj in bpy.data.objects:
        if obj.library is None:
            remove(obj)
    _delete_stand_ins()
    for tree in [
        g for g in bpy.data.node_groups if g.library is None and g.get(MARK) and g.users == 0
    ]:
        bpy.data.node_groups.remove(tree)
