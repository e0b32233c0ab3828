"""shapes.blend (shapes_blend.py) reloaded: the space comes back from the file without a bake and
shows the same bits; a render of a frame (the path `blender -b file -f N` takes) shows the blend of
that frame's weights; a key edited after the bake makes the space stale: the panel's reason, the
mesh back to Blender's mix, nothing of the artist's changed; Re-bake blends the edited key."""

import time

import bpy
import numpy as np
from support import blender as support
from support.shape_keys import draw_panels

mdc, blending, storage, frame_display = support.enable_addon(
    "core", "shapes.blending", "storage", "playback.frame_display"
)
obj = bpy.data.objects["Bar"]
scene = bpy.context.scene
settings = obj.modal_deform.shapes
assert settings.enabled and settings.space is not None
bake_id = settings.space["bake_id"]
start = time.perf_counter()
space = blending.load(obj)
print(f"LOAD {1000 * (time.perf_counter() - start):.1f} ms")
assert blending.stale_reason(obj) == ""
block = obj.data.shape_keys.key_blocks["Bend"]


def shown():
    return support.evaluated_positions(obj)


scene.frame_set(6)
w6 = block.value
at6 = space.blend([w6])
assert shown().tobytes() == at6.tobytes(), "the reloaded space shows another blend"
assert settings.space["bake_id"] == bake_id, "reloading baked again"
panels = draw_panels(obj)
assert "1 keys" in panels and "Stale" not in panels and "[modal_deform.keep_blend]" in panels, (
    panels
)


# A render of frame 6 as `blender -b shapes.blend -f 6` makes it (a one-frame animation render,
# whose own depsgraph evaluates the keys): the blend, not the linear mix.
camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
scene.collection.objects.link(camera)
camera.data.type, camera.data.ortho_scale = "ORTHO", 6.0
camera.location, camera.rotation_euler = (0.5, -10.0, 2.0), (np.pi / 2, 0.0, 0.0)
scene.camera = camera
material = bpy.data.materials.new("Glow")
material.use_nodes = True
nodes = material.node_tree.nodes
emission = nodes.new("ShaderNodeEmission")
material.node_tree.links.new(emission.outputs[0], nodes["Material Output"].inputs[0])
obj.data.materials.append(material)
scene.render.engine = "CYCLES"
scene.cycles.samples, scene.cycles.use_denoising = 1, False
scene.render.resolution_x = scene.render.resolution_y = 64
scene.render.resolution_percentage = 100
scene.world.use_nodes = True
scene.world.node_tree.nodes["Background"].inputs[1].default_value = 0.0
# BMP, read here: Blender under Wine cannot load an image file back (it maps the file).
scene.render.image_settings.file_format = "BMP"
scene.render.image_settings.color_mode = "RGB"
seen = []


def record(scene_, depsgraph=None):  # after the add-on's handler: what the render's keys weighed
    if depsgraph is not None and depsgraph.mode == "RENDER":
        seen.append((scene_.frame_current, blending._shown.get(obj.name)))


bpy.app.handlers.frame_change_post.append(record)


def read_bmp(path):
    """A 24-bit BMP's pixels (rows bottom first, columns, RGB) in [0, 1]."""
    data = np.fromfile(path, np.uint8)

    def field(start, size):
        return int.from_bytes(data[start : start + size].tobytes(), "little", signed=True)

    offset, width, height, bits = field(10, 4), field(18, 4), field(22, 4), field(28, 2)
    assert bits == 24 and height > 0, (bits, height)
    stride = (3 * width + 3) // 4 * 4
    rows = data[offset : offset + stride * height].reshape(height, stride)[:, : 3 * width]
    return rows.reshape(height, width, 3)[..., ::-1] / 255.0


def render(name):
    """Frame 6 rendered as an animation of one frame, its pixels (rows, columns, RGB)."""
    scene.frame_start = scene.frame_end = 6
    scene.render.filepath = support.tmp(name + "_")
    assert bpy.ops.render.render(animation=True) == {"FINISHED"}
    pixels = read_bmp(support.tmp(name + "_0006.bmp"))
    assert pixels.shape == (64, 64, 3), pixels.shape
    return pixels


scene.frame_set(1)  # the render goes to frame 6 itself
blend_image = render("blend")
assert seen and seen[-1][0] == 6 and seen[-1][1][1] == np.array([w6]).tobytes(), seen
settings.enabled = False
linear_image = render("linear")
assert np.abs(blend_image - linear_image).max() > 0.5, "the render shows the linear mix"
# The blend kept as a key, Bend muted, Blender's own mix: the render of the blend.
settings.enabled = True
scene.frame_set(6)
assert bpy.ops.modal_deform.keep_blend() == {"FINISHED"}
settings.enabled = False
block.mute = True
obj.data.shape_keys.key_blocks["Blended Shape"].value = 1.0
kept_image = render("kept")
print("RENDER", np.abs(blend_image - kept_image).max(), np.abs(blend_image - linear_image).max())
assert np.abs(blend_image - kept_image).mean() < 1e-3, "the render is not the blend"
obj.shape_key_remove(obj.data.shape_keys.key_blocks["Blended Shape"])
block.mute = False
settings.enabled = True
bpy.app.handlers.frame_change_post.remove(record)

# A key edited after the bake: stale, the mesh shows Blender's mix, the key as edited.
scene.frame_set(6)
assert shown().tobytes() == at6.tobytes()
block.data[7].co.x += 0.25
edited = support.key_positions(obj, "Bend").copy()
bpy.context.view_layer.update()
reason = blending.stale_reason(obj)
assert "were edited" in reason, reason
assert "re-bake" in blending.problems[obj.name], blending.problems
assert not frame_display.shows(obj), "a stale space still shows"
panels = draw_panels(obj)
assert "Stale (a key" in panels and "[Re-bake]" in panels, panels
assert support.key_positions(obj, "Bend").tobytes() == edited.tobytes()
# Saved and reloaded stale, it says so too (the digest, not the copies in memory).
blending._forget()
assert "were edited" in blending.stale_reason(obj)
# Re-bake: the edited key blends.
assert bpy.ops.modal_deform.bake_shapes() == {"FINISHED"}
assert settings.space["bake_id"] != bake_id and blending.stale_reason(obj) == ""
scene.frame_set(5)
scene.frame_set(6)
assert shown().tobytes() == blending.load(obj).blend([w6]).tobytes()
assert np.abs(shown() - at6).max() > 1e-3, "the re-bake did not take the edited key"
print("RELOADED")
