"""Where playback shows a frame: a point attribute of the mesh that a Geometry Nodes modifier, first in
the object's stack, sets the positions from (Set Position from a Named Attribute).

The artist's positions and shape keys are never written: Edit Mode (the modifier is hidden there)
shows the rest, and a file written mid-playback (a crash's autosave) holds the mesh as it was plus
the frame in the attribute. Where the attribute is missing the modifier leaves the positions alone
(the Named Attribute node's "Exists" is Set Position's selection; Blender 3.4 has no such output:
there a BOOLEAN point attribute, SHOWN, written True with the attribute, is the selection, and goes
with it), so taking the attribute away shows the mesh as before, and a mesh joined to one that
plays keeps its own positions.

Taken away (remove) when the cache is freed or no longer plays, when a pose shows (the interactive
pose, or a result in the "Modal Deform" shape key: pose_displays.display, posing.pose_key) and when
the add-on is disabled.
"""
import bpy
import numpy as np

from . import mesh_io

#: The modifier on an object that plays a cache, and its node group (one per file, shared).
MODIFIER = "Modal Deform Playback"
NODE_GROUP = "Modal Deform Playback"
#: The FLOAT_VECTOR point attribute holding the frame's positions (object space).
ATTRIBUTE = "modal_deform_playback"
#: Blender 3.4's selection (see the module's comment): True on every point where ATTRIBUTE holds a frame.
SHOWN = "modal_deform_playback_shown"


def _named_attribute(tree, data_type, name):
    node = tree.nodes.new("GeometryNodeInputNamedAttribute")
    node.data_type = data_type
    node.inputs["Name"].default_value = name
    # Before Blender 4.0 the node has an "Attribute" output per data type, data_type's enabled.
    return node, next(o for o in node.outputs if o.name == "Attribute" and o.enabled)


def node_group():
    """The file's node group "Modal Deform Playback" (made on first use): Geometry → Set Position
    (Position: ATTRIBUTE, Selection: where it exists) → Geometry."""
    tree = bpy.data.node_groups.get(NODE_GROUP)
    if tree is not None and tree.bl_idname == "GeometryNodeTree" and tree.library is None:
        return tree
    tree = bpy.data.node_groups.new(NODE_GROUP, "GeometryNodeTree")
    if hasattr(tree, "interface"):  # Blender 4.0+
        tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
        tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    else:
        tree.inputs.new("NodeSocketGeometry", "Geometry")
        tree.outputs.new("NodeSocketGeometry", "Geometry")
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


def _add_modifier(obj):
    """The modifier, new, first in obj's stack (before the artist's modifiers: they act on the frame),
    hidden in Edit Mode (which shows the mesh being edited)."""
    modifier = obj.modifiers.new(MODIFIER, "NODES")
    modifier.node_group = node_group()
    modifier.show_in_editmode = modifier.show_on_cage = False
    if len(obj.modifiers) > 1:
        if hasattr(obj.modifiers, "move"):  # Blender 4.0+
            obj.modifiers.move(len(obj.modifiers) - 1, 0)
        else:
            with bpy.context.temp_override(object=obj):
                bpy.ops.object.modifier_move_to_index(modifier=modifier.name, index=0)
    return modifier


def positions(obj):
    """Where the frame shown on obj goes: ATTRIBUTE's #V by 3 float32 view (mesh_io.attribute_co),
    with the modifier that shows it (made if needed, on again if the artist turned it off in the
    viewport). Use at once, then tag the mesh (mesh.update())."""
    modifier = obj.modifiers.get(MODIFIER)
    if modifier is None or modifier.type != "NODES":
        modifier = _add_modifier(obj)
    if modifier.node_group is None or modifier.node_group.name != NODE_GROUP:
        modifier.node_group = node_group()
    mesh = obj.data
    attributes = mesh.attributes
    if attributes.get(ATTRIBUTE) is None:
        attributes.new(ATTRIBUTE, "FLOAT_VECTOR", "POINT")
        if _reads_shown(modifier.node_group):
            shown = attributes.get(SHOWN) or attributes.new(SHOWN, "BOOLEAN", "POINT")
            shown.data.foreach_set("value", np.ones(len(mesh.vertices), bool))
    return mesh_io.attribute_co(mesh, attributes[ATTRIBUTE])


def _reads_shown(tree):
    """Whether the node group takes its selection from SHOWN (made in Blender 3.4)."""
    return any(node.bl_idname == "GeometryNodeInputNamedAttribute" and node.inputs["Name"].default_value == SHOWN
                   for node in tree.nodes)


def shows(obj):
    """Whether obj carries the display (its modifier or attribute)."""
    return obj.type == "MESH" and (MODIFIER in obj.modifiers or ATTRIBUTE in obj.data.attributes)


def remove(obj):
    """Take the display off obj (its modifier and attributes): the mesh shows what it shows without it."""
    if not shows(obj):
        return
    modifier = obj.modifiers.get(MODIFIER)
    if modifier is not None:
        obj.modifiers.remove(modifier)
    mesh = obj.data
    for name in (ATTRIBUTE, SHOWN):
        attribute = mesh.attributes.get(name)
        if attribute is not None:
            mesh.attributes.remove(attribute)
    mesh.update()


def remove_all():
    """Take the display off every object of the file, and its node group (disabling the add-on)."""
    for obj in bpy.data.objects:
        if obj.library is None:
            remove(obj)
    tree = bpy.data.node_groups.get(NODE_GROUP)
    if tree is not None and tree.users == 0 and tree.library is None:
        bpy.data.node_groups.remove(tree)
