"""Small Cycles renders on the CPU, shared by the demo (demo.py) and the benchmark figures
(render_figures.py): a stage (camera, sun, world), one render to pixels, images side by side.

Run inside Blender (imports bpy); the scripts put this folder on sys.path.
"""

import bpy
import numpy as np
from mathutils import Vector


def stage(target, eye, lens=50, samples=16, resolution=(480, 270)):
    """Camera at `eye` looking at `target` (world units), a sun from above the camera (so that the
    side facing the camera is lit), a dim grey world, Cycles on the CPU with `samples` samples per
    pixel and no denoiser, PNG output of `resolution` pixels."""
    scene = bpy.context.scene
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    view = look_at(camera, eye, target)
    camera.data.lens = lens
    camera.data.clip_end = 10 * (Vector(target) - Vector(eye)).length
    scene.camera = camera
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 4.0
    sun.rotation_euler = (view + Vector((0.3, 0.3, -0.8))).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(sun)
    world = bpy.data.worlds.new("World")
    world.color = (0.05, 0.05, 0.06)
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.6
    scene.world = world
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = resolution
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    return camera


def look_at(camera, eye, target):
    """Place `camera` at `eye` looking at `target`, its up the world's z; returns the unit view direction."""
    camera.location = eye
    view = (Vector(target) - Vector(eye)).normalized()
    camera.rotation_euler = view.to_track_quat("-Z", "Y").to_euler()
    return view


def render(path):
    """Render the scene to `path` (PNG); returns its pixels (height, width, 4) float32, bottom row first."""
    scene = bpy.context.scene
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(str(path))
    pixels = np.empty(image.size[0] * image.size[1] * 4, np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(scene.render.resolution_y, scene.render.resolution_x, 4)


def side_by_side(images, path):
    """Write the images (same height) left to right into one PNG at `path`."""
    both = np.concatenate(images, axis=1)
    image = bpy.data.images.new("side_by_side", both.shape[1], both.shape[0], alpha=True)
    image.pixels.foreach_set(both.ravel())
    image.filepath_raw = str(path)
    image.file_format = "PNG"
    image.save()
    bpy.data.images.remove(image)
