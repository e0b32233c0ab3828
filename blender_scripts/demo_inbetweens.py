"""The demo's in-betweens (issue 51): Suzanne's head keyed at three poses only (at rest, tilted
to her left, then to her right: about the camera's axis, so the ears swing in the picture), her
ears free. Dynamics > In-betweens moves her through the keys the way that needs the least force;
the same keys with Dynamics off (Bake Animation: each frame posed where Blender's F-curves put the
Empty) are what Blender makes of the keys without it. Rendered as a strip of frames, the
in-betweens above, Blender's interpolation below, and under them a plot of the left ear tip's
height over the frames for both.

Solved twice: first with Solve In-betweens as the artist clicks it (the add-on's default of
100 iterations, which stops short of converging here: the panel says the motion is near the one of
least force), then by the job that operator runs with SOLVE_ITERATIONS, to convergence (the add-on
has no setting for it); the strip and the plot show the second. Prints its stats (converged,
iterations, seconds), the ear tip's height frame by frame and its overshoot, and how far the first
solve's ear tip is from the second's.

Called by demo.py after its stage (camera, light, Cycles) is set up; run inside Blender.
"""

import math
import time

import bpy
import numpy as np
from demo_dynamics import head_handle
from headless import evaluated_positions, smooth_suzanne
from rendering import look_at, render, side_by_side

#: The keys: (frame, the head's Empty turned about the camera's axis, degrees).
KEYS = ((1, 0), (8, 35), (16, -30))
#: The frames of the strip (the keys among them), and the last frame solved and plotted.
STRIP = (1, 5, 8, 11, 14, 16, 17, 19, 22, 40)
LAST = 48
#: The solve's iterations at most: about 280 converge here, at 2 subdivisions (the add-on's 100
#: stop short).
SOLVE_ITERATIONS = 400
#: The camera for this strip: in front of Suzanne, a little to her left (+x) and above.
EYE, TARGET, LENS = (0.8, -7.0, 0.6), (0.0, 0.0, 0.05), 75
#: The plot's colours (RGB): the in-betweens, Blender's interpolation, the axes and key lines, the
#: background.
INBETWEEN_COLOUR, INTERPOLATION_COLOUR = (0.3, 0.6, 1.0), (0.9, 0.55, 0.2)
AXIS_COLOUR, BACKGROUND = (0.45, 0.45, 0.45), (0.04, 0.04, 0.045)


def _keyed(controller):
    """The head's Empty keyed at KEYS, rotation only (it turns about itself)."""
    for frame, tilt in KEYS:
        controller.rotation_euler.y = math.radians(tilt)
        controller.keyframe_insert("rotation_euler", frame=frame)


def _played(obj, tip, output, name):
    """Every frame 1 to LAST shown on the timeline: the ear tip's position per frame, and the STRIP
    frames rendered."""
    scene = bpy.context.scene
    path, pictures = [], []
    for frame in range(1, LAST + 1):
        scene.frame_set(frame)
        path.append(evaluated_positions(obj)[tip])
        if frame in STRIP:
            pictures.append(render(output / f"demo_inbetweens_{name}_{frame:02d}.png"))
    return np.array(path, np.float64), pictures


def _segment_distance(px, py, a, b):
    """Each pixel's distance (px, py grids) to the segment from a to b (pixels)."""
    d = b - a
    t = np.clip(((px - a[0]) * d[0] + (py - a[1]) * d[1]) / max(d @ d, 1e-12), 0.0, 1.0)
    return np.hypot(px - a[0] - t * d[0], py - a[1] - t * d[1])


def _draw(image, px, py, points, colour, width):
    """The polyline through `points` (pixels), `width` pixels wide, antialiased, over image."""
    distance = np.full(px.shape, np.inf)
    for a, b in zip(points[:-1], points[1:]):
        distance = np.minimum(distance, _segment_distance(px, py, a, b))
    alpha = np.clip(width / 2 + 0.5 - distance, 0.0, 1.0)[..., None]
    image[..., :3] = (1 - alpha) * image[..., :3] + alpha * np.asarray(colour)


def plot(paths, width, height):
    """The curves `paths` ((colour, heights per frame 1 to LAST) pairs) over frames, as pixels
    (height, width, 4), bottom row first: the frame axis along the bottom, a vertical line at each
    key and a tick at each frame of the strip, a horizontal line at the rest height."""
    image = np.zeros((height, width, 4), np.float32)
    image[..., :3], image[..., 3] = BACKGROUND, 1.0
    py, px = np.mgrid[0:height, 0:width].astype(np.float64)
    margin = height // 10
    values = np.concatenate([p for _, p in paths])
    low, high = values.min(), values.max()
    pad = 0.08 * (high - low)
    low, high = low - pad, high + pad

    def x(frame):
        return margin + (frame - 1) / (LAST - 1) * (width - 2 * margin)

    def y(value):
        return margin + (value - low) / (high - low) * (height - 2 * margin)

    frames = np.arange(1, LAST + 1)
    bottom, top = float(margin), float(height - margin)
    _draw(image, px, py, np.array([[x(1), bottom], [x(LAST), bottom]]), AXIS_COLOUR, 2)
    for frame, _ in KEYS:
        _draw(image, px, py, np.array([[x(frame), bottom], [x(frame), top]]), AXIS_COLOUR, 2)
    for frame in STRIP:
        _draw(image, px, py, np.array([[x(frame), bottom - 8], [x(frame), bottom]]), AXIS_COLOUR, 2)
    rest = paths[0][1][0]
    _draw(image, px, py, np.array([[x(1), y(rest)], [x(LAST), y(rest)]]), AXIS_COLOUR, 1)
    for colour, heights in paths:
        _draw(image, px, py, np.c_[x(frames), y(heights)], colour, 4)
    return image


def inbetweens(addon, output, levels, width):
    """Bake a Suzanne subdivided `levels` times, key her head at KEYS, solve her in-betweens, play
    them and the same keys with Dynamics off (Bake Animation) and render the STRIP frames (`width`
    pixels wide each) and the ear tip's plot into OUTPUT/demo_inbetweens.png. Prints the solve's
    stats and the ear tip's overshoot. Returns the strip's path."""
    frame_cache, motion = addon
    scene = bpy.context.scene
    shown = [o for o in scene.objects if o.type == "MESH" and not o.hide_render]
    for obj in shown:
        obj.hide_render = True
    camera = scene.camera
    placed = camera.matrix_world.copy(), camera.data.lens
    look_at(camera, EYE, TARGET)
    camera.data.lens = LENS
    scene.render.resolution_x, scene.render.resolution_y = width, width * 3 // 4

    suzanne = smooth_suzanne("Suzanne in-betweens", levels)
    V, controller = head_handle(suzanne)
    bpy.context.view_layer.objects.active = suzanne
    _keyed(controller)
    scene.frame_start, scene.frame_end = 1, LAST
    tip = int(np.argmax(V[:, 0]))  # the left ear's tip (her left: +x)
    dynamics = suzanne.modal_deform.dynamics
    dynamics.enabled, dynamics.inbetweens = True, True

    # As the artist clicks Solve: the add-on's settings.
    start = time.perf_counter()
    assert bpy.ops.modal_deform.solve_inbetweens() == {"FINISHED"}
    print(f"Solve In-betweens: {time.perf_counter() - start:.1f} s")
    default = np.array(
        [(scene.frame_set(f), evaluated_positions(suzanne)[tip])[1] for f in range(1, LAST + 1)]
    )
    # The job that operator runs, with more iterations (the add-on has no setting for them).
    job = motion.InbetweenJob(suzanne, scene)
    job.options["solve_iterations"] = SOLVE_ITERATIONS
    job.run()
    level, message = job.finish()
    assert job.written, message
    stats = job.stats
    print(
        f"in-betweens of {len(V)} vertices through keys at frames "
        f"{', '.join(str(k[0]) for k in KEYS)}, solve_iterations {SOLVE_ITERATIONS}: converged "
        f"{stats['converged']}, {stats['iterations']} iterations, {stats['ms'] / 1e3:.1f} s "
        f"({stats['nodes']} substeps solved for; the control from {stats['initial_control']:.3g} "
        f"to {stats['control']:.3g}); {level}: {message}"
    )
    ours, ours_pictures = _played(suzanne, tip, output, "solved")
    cache = frame_cache.get(suzanne)
    print(f"in-betweens: {len(cache)} frames cached in {cache.nbytes() / 1024:.1f} KB")

    dynamics.enabled = False
    assert bpy.ops.modal_deform.bake_animation() == {"FINISHED"}
    theirs, their_pictures = _played(suzanne, tip, output, "interpolated")

    size = np.ptp(V, axis=0).max()
    print(f"the left ear tip's height (Suzanne is {size:.2f} wide), frames 1 to {LAST}:")
    for name, path in (("in-betweens", ours), ("Blender's interpolation", theirs)):
        print(f"  {name:24}" + " ".join(f"{z:+.2f}" for z in path[:, 2]))
    last = KEYS[-1][0] - 1
    rises = ours[last:, 2].max() - theirs[last, 2]
    print(
        f"after the last key (frame {last + 1}) the ear tip rises {rises:.2f} ({rises / size:.1%} "
        f"of her width) above where Blender's interpolation holds it and settles within "
        f"{np.linalg.norm(ours[-1] - theirs[-1]):.3f} of it by frame {LAST}; the two paths are "
        f"{np.linalg.norm(ours - theirs, axis=1).max():.2f} apart at most; the add-on's default "
        f"solve (100 iterations) is within {np.linalg.norm(default - ours, axis=1).max():.3f} of "
        f"this one"
    )

    bpy.data.objects.remove(controller)
    bpy.data.objects.remove(suzanne)
    for obj in shown:
        obj.hide_render = False
    camera.matrix_world, camera.data.lens = placed
    rows = [np.concatenate(row, axis=1) for row in (their_pictures, ours_pictures)]
    curves = plot(
        [(INTERPOLATION_COLOUR, theirs[:, 2]), (INBETWEEN_COLOUR, ours[:, 2])],
        rows[0].shape[1],
        rows[0].shape[0],
    )
    strip = output / "demo_inbetweens.png"
    # Pixels are bottom row first: the plot, then Blender's interpolation, then the in-betweens.
    side_by_side([np.concatenate([curves] + rows)], strip)
    return strip
