"""Blender with a window (under Xvfb): draw every panel of the sidebar's Modal Deform tab at the
default sidebar width and screenshot it, in each state an artist sees: not baked, baked with two
handles (one moved by an Empty, one pinned) and a painted stiffness group, and stale after a vertex
moved; every property has a tooltip.

Each screenshot is of the whole window (OUTPUT/window-<state>.png) and of the sidebar cut out of it
(OUTPUT/sidebar-<state>-<n>.png, scrolled down a screen at a time until its end). A panel whose
draw() raises prints a traceback, which the test looks for. Writes OUTPUT/result.json (window.run).
"""

import os

import bpy
import numpy as np
from window import (
    click,
    enable_addon,
    output,
    override,
    run,
    say,
    screenshot,
    show_sidebar_tab,
    sidebar,
    subdivided_suzanne,
    view3d,
)

# Seconds for the sidebar to settle after a change: Blender 4.x animates panels opening and moving.
SETTLE = 1.0


def cut(path, window_size, x, y, width, height, cut_path):
    """Write the rectangle (x, y from the bottom left, as Blender's regions) of the window's PNG at
    path; an X grab is of the whole screen, which the window fills (no window manager)."""
    image = bpy.data.images.load(path)
    full_width, full_height = image.size
    assert (full_width, full_height) == window_size, (
        f"{path}: {image.size[:]}, not the window's {window_size}"
    )
    pixels = np.empty(full_width * full_height * 4, np.float32)
    image.pixels.foreach_get(pixels)
    part = pixels.reshape(full_height, full_width, 4)[y : y + height, x : x + width]
    bpy.data.images.remove(image)
    assert part.std() > 0.01, f"{path}: blank where the sidebar is"
    piece = bpy.data.images.new("sidebar", width, height, alpha=True)
    piece.pixels.foreach_set(np.ascontiguousarray(part).ravel())
    piece.filepath_raw = cut_path
    piece.file_format = "PNG"
    piece.save()
    bpy.data.images.remove(piece)


def scroll_offset(region):
    return region.view2d.region_to_view(0, 0)[1]


def screenshots(state):
    """The window, then the sidebar a screen at a time from its top to its end."""
    window, _, _ = view3d()
    region = sidebar()
    screenshot(f"window-{state}.png")
    # The sidebar floats over the viewport (region overlap): cut its own rectangle, in window pixels.
    part = 0
    while True:
        part += 1
        grab = screenshot("grab.png")
        cut(
            grab,
            (window.width, window.height),
            region.x,
            region.y,
            region.width,
            region.height,
            os.path.join(output, f"sidebar-{state}-{part}.png"),
        )
        os.remove(grab)
        before = scroll_offset(region)
        yield from scroll(region, "WHEELDOWNMOUSE", 12)
        if scroll_offset(region) == before:
            break
    say(
        f"{state}: the window and {part} screens of the sidebar ({region.width} by {region.height} pixels)"
    )
    yield from scroll(region, "WHEELUPMOUSE", 12 * part)


def scroll(region, wheel, clicks):
    window, _, _ = view3d()
    x, y = region.x + region.width // 2, region.y + region.height // 2
    window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
    for _ in range(clicks):
        window.event_simulate(type=wheel, value="PRESS", x=x, y=y)
    yield SETTLE


def select_vertices(obj, mask):
    obj.data.polygons.foreach_set("select", np.zeros(len(obj.data.polygons), bool))
    obj.data.edges.foreach_set("select", np.zeros(len(obj.data.edges), bool))
    obj.data.vertices.foreach_set("select", mask)


def check_tooltips():
    """Every property the add-on defines has a tooltip (those PropertyGroup brings, name, excepted)."""
    from modal_deform import properties

    inherited = set(bpy.types.PropertyGroup.bl_rna.properties.keys())
    for group in properties.CLASSES:
        for prop in group.bl_rna.properties:
            if prop.identifier not in inherited:
                assert prop.description, f"{group.__name__}.{prop.identifier}: no tooltip"
            for item in getattr(prop, "enum_items", ()):
                assert item.description, (
                    f"{group.__name__}.{prop.identifier}: {item.identifier} has no tooltip"
                )
    say("every property has a tooltip")


def steps():
    enable_addon()
    check_tooltips()

    # Suzanne subdivided once (1,968 vertices) seen from the front, the sidebar open on the tab.
    obj = subdivided_suzanne(1)
    with override():
        bpy.ops.view3d.view_axis(type="FRONT")
        bpy.ops.view3d.view_all()
    yield from show_sidebar_tab()
    yield 0.5
    window, _, _ = view3d()
    region = sidebar()
    say(
        f"window {window.width} by {window.height}, sidebar {region.width} pixels wide at UI scale "
        f"{bpy.context.preferences.system.ui_scale:.2f}"
    )
    yield from screenshots("not-baked")

    # Baked, two handles (the top of the head moved by an Empty, the chin pinned), stiffness painted.
    V = np.array([v.co for v in obj.data.vertices])
    stiff = obj.vertex_groups.new(name="Nose")
    stiff.add([int(i) for i in np.flatnonzero(V[:, 1] < -0.8)], 1.0, "REPLACE")
    obj.modal_deform.stiffness_group = stiff.name
    for mask, pinned in ((V[:, 2] > 0.55, False), (V[:, 2] < -0.55, True)):
        select_vertices(obj, mask)
        with override():
            bpy.context.view_layer.objects.active = obj
            bpy.ops.object.mode_set(mode="EDIT")
            assert bpy.ops.modal_deform.add_handle() == {"FINISHED"}
            bpy.ops.object.mode_set(mode="OBJECT")
        if pinned:
            obj.modal_deform.handles[-1].controller = None
    obj.modal_deform.active_handle = 0
    with override():
        bpy.context.view_layer.objects.active = obj
        assert bpy.ops.modal_deform.bake() == {"FINISHED"}
    yield SETTLE
    # Mode Preview starts closed: open it with a click on its header, the last of the tab's panels.
    yield from scroll(region, "WHEELDOWNMOUSE", 40)
    click(region.x + 60, region.y + int(24 * bpy.context.preferences.system.ui_scale))
    yield SETTLE
    yield from scroll(region, "WHEELUPMOUSE", 40)
    yield from screenshots("baked")

    # A vertex moved after the bake: the panels say the basis is stale.
    obj.data.vertices[0].co.x += 0.1
    obj.data.update()
    yield SETTLE
    yield from screenshots("stale")


run(steps)
