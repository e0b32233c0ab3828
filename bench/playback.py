"""The per-frame cache in headless Blender (issue 40): per frame, what playback costs (a cached frame
read back, x = x̄ + U q into the display, playback/frame_display.py; one simulation step live) and Blender's
evaluation after it, the frames played (the display reading a stand-in) and, for a live step, stepped
through with the timeline still (the display's attribute); and for FRAMES frames of the dragon (100k
vertices), the cache's size and the .blend's against the same animation exported as a shape key per
frame and as a PC2 file.

    blender -b --factory-startup --python bench/playback.py -- --output out.json [--quick] [--subdivide 2]

In bpy, with the add-on installed from the extension zip (what `make bench` runs, bench/run.py):

    BLENDER_USER_RESOURCES=$(mktemp -d) .venv/bpy-4.5/bin/python tests/blender/bpy_session.py \
        --extension dist/modal_deform-0.1.0-blender_4.2_to_5.0-linux_x64.zip bench/playback.py -- --output out.json

Per frame, each frame reached by scene.frame_set as the timeline reaches it: "handler" is the
add-on's frame handler (playback: checks, the cache read or the step, the mapping into the
display), timed by handlers run just before and after it; "evaluate" is Blender's evaluation of
what it changed, from the handler's end to frame_set's return; "map" is the mapping x̄ + U q
alone (the frame's q mapped again after, into an array of its own), the part of "handler" that
grows with the mesh. Each figure is the median over the frames of a frame's least over ROUNDS
rounds of the same frames (a live step's frames simulated again each round). A jump forward
simulates every frame in between: its handler's time per frame simulated. For reference, Blender's
evaluation of the same mesh without the display, its vertex positions written (a copy of the mesh
on another object): the floor of what the display costs. The load average (1, 5, 15 min) before and
after the run.

The rig case (issue 50, "rig"; --rig-only runs it alone): the dragon, its handles taken off, skinned by
an Armature modifier to a chain of RIG_BONES bones along its long axis (chain_rig), keyed to jump,
turn, bend and stop (animate_rig), Follow Rig on; per frame played and simulated live, the add-on's
frame handler split (RIG_PARTS: the bones read, the step, the map into the offset attribute; the
rest) beside Blender's evaluation before and after it, then the same frames with the add-on off the
mesh (its Armature modifier alone: the floor).
"""

import argparse
import json
import math
import os
import pathlib
import sys
import tempfile
import time

import bpy
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
import blender_pose  # noqa: E402 (found through the line above; its meshes and handles)
from headless import enable_addon  # noqa: E402 (blender_pose put blender_scripts/ on the path)

#: Rounds of the timed frames (timed_frames): each figure is a frame's least over them.
ROUNDS = 3


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--output", required=True)
    parser.add_argument(
        "--frames", type=int, default=250, help="frames of the animation cached and exported"
    )
    parser.add_argument(
        "--timed", type=int, default=40, help="frames timed for each per-frame figure"
    )
    parser.add_argument(
        "--subdivide",
        type=int,
        default=0,
        help="midpoint subdivisions of the 100k dragon (2: 1.6M vertices, baked on a proxy)",
    )
    parser.add_argument(
        "--no-sizes", action="store_true", help="skip the .blend sizes (dense meshes)"
    )
    parser.add_argument(
        "--quick", action="store_true", help="dragon_vrip_res4 and a small basis (smoke test)"
    )
    parser.add_argument(
        "--rig-bones",
        type=int,
        nargs="+",
        default=RIG_BONES,
        help="the rig case's bone counts (quick: the first)",
    )
    parser.add_argument("--rig-only", action="store_true", help="the rig case alone")
    return parser.parse_args(argv)


def animate(controller, frames):
    """The controller turns by 90 degrees and back about the vertical and slides, a cycle every 48
    frames, keyed every 6 frames."""
    start = controller.matrix_world.copy()
    for frame in range(1, frames + 1, 6):
        phase = 2 * math.pi * (frame - 1) / 48
        controller.rotation_euler.z = math.radians(45) * (1 - math.cos(phase))
        controller.location.x = start.translation.x + 0.05 * math.sin(phase)
        controller.keyframe_insert("rotation_euler", frame=frame)
        controller.keyframe_insert("location", frame=frame)


def playback_handler(name):
    """The add-on's playback handler in bpy.app.handlers.`name`: the frame change's, and those Blender
    calls when the timeline starts or stops playing (Blender 4+), which headless frame changes do not
    call."""
    return next(
        h for h in getattr(bpy.app.handlers, name) if h.__module__.endswith(".playback.timeline")
    )


class HandlerClock:
    """Clocks read just before and just after the add-on's frame handler (``before``, ``after``,
    perf_counter seconds), by handlers put around it in frame_change_post until ``remove()``."""

    def __init__(self):
        self.before = self.after = None
        handlers = bpy.app.handlers.frame_change_post
        add_on_handler = playback_handler("frame_change_post")
        handlers.insert(list(handlers).index(add_on_handler), self._before)
        handlers.insert(list(handlers).index(add_on_handler) + 1, self._after)

    def _before(self, *args):
        self.before = time.perf_counter()

    def _after(self, *args):
        self.after = time.perf_counter()

    def remove(self):
        bpy.app.handlers.frame_change_post.remove(self._before)
        bpy.app.handlers.frame_change_post.remove(self._after)


def timed_frames(
    obj, scene, timeline, frame_cache, frames, stepping=False, rounds=ROUNDS, playing=True
):
    """Handler, map and evaluation milliseconds over `frames`, each reached by scene.frame_set as
    the timeline reaches it, played (`playing`: between the calls of the add-on's playback handlers,
    the display reading a stand-in) or stepped through while still (the display's attribute):
    "handler" from the start to the end of the add-on's frame handler
    (clocks read by handlers put before and after it), "evaluate" from its end to the return of
    frame_set (Blender evaluating what the handler changed); `stepping`: also the simulation step's
    own milliseconds and BFGS iterations (Simulation.stats, timed natively), each round after the
    cache is cut at the first frame, so that every frame is simulated live again (the same work:
    the same bits). Each figure: the median over the frames of its least over `rounds` rounds, which
    leaves out the time a neighbour on this shared machine takes from a frame (a frame is the same
    work in every round)."""
    scratch = np.empty((len(obj.data.vertices), 3), np.float32)
    clock = HandlerClock()
    figures = {
        name: np.full((rounds, len(frames)), np.inf)
        for name in ("handler", "map", "evaluate", "step")
    }
    iterations = []
    if playing:
        playback_handler("animation_playback_pre")(scene, None)
    try:
        for round_ in range(rounds):
            if stepping:
                frame_cache.get(obj).cut(frames[0])
            for index, frame in enumerate(frames):
                scene.frame_set(frame)
                returned = time.perf_counter()
                assert obj.name not in timeline.problems, timeline.problems
                figures["handler"][round_, index] = 1e3 * (clock.after - clock.before)
                figures["evaluate"][round_, index] = 1e3 * (returned - clock.after)
                if stepping:
                    stats = timeline.player(obj, scene).simulation.stats
                    figures["step"][round_, index] = stats["ms"]
                    iterations.append(stats["iterations"])
                q = frame_cache.get(obj).state(frame)[0]
                start = time.perf_counter()
                timeline.player(obj, scene).positions(q, scratch)
                figures["map"][round_, index] = 1e3 * (time.perf_counter() - start)
    finally:
        clock.remove()
        if playing:
            playback_handler("animation_playback_post")(scene, None)
    least = {name: float(np.median(values.min(axis=0))) for name, values in figures.items()}
    result = {
        "handler_ms": least["handler"],
        "map_ms": least["map"],
        "evaluate_ms": least["evaluate"],
        "frames": len(frames),
        "rounds": rounds,
        # For comparison, the medians over every round's frames, a neighbour's load included.
        "every_round": {
            name + "_ms": float(np.median(values))
            for name, values in figures.items()
            if stepping or name != "step"
        },
    }
    if stepping:
        result.update(step_ms=least["step"], iterations=float(np.median(iterations)))
    return result


def jump_forward(obj, scene, timeline, frame_cache, frames):
    """Milliseconds per frame of a jump forward over `frames` frames simulated (the cache cut after
    its first frame, then the frame `frames` + 1 shown): each frame stepped from the one before at
    its own frame (set_frame), the last one mapped into the display."""
    cache = frame_cache.get(obj)
    cache.cut(cache.start + 1)
    timeline.set_frame(scene, cache.start + frames)
    start = time.perf_counter()
    timeline.show(obj, scene)
    return {"ms_per_frame": 1e3 * (time.perf_counter() - start) / frames, "frames": frames}


def without_display(obj, timeline, frame_cache, frames):
    """Blender's evaluation of a copy of obj's mesh (which has no shape keys) on another object
    without the display's modifier (obj hidden), its vertex positions written from the cached
    frames: median milliseconds."""
    mesh_io = blender_pose.addon("mesh_io")
    assert obj.data.shape_keys is None
    mesh = obj.data.copy()
    copy = bpy.data.objects.new("Without the display", mesh)
    bpy.context.scene.collection.objects.link(copy)
    obj.hide_set(True)
    player, cache = timeline.player(obj, bpy.context.scene), frame_cache.get(obj)
    evaluate = []
    for frame in frames:
        player.positions(cache.state(frame)[0], mesh_io.vertex_positions(mesh))
        mesh.update()
        start = time.perf_counter()
        bpy.context.view_layer.update()
        evaluate.append(1e3 * (time.perf_counter() - start))
    bpy.data.objects.remove(copy)
    bpy.data.meshes.remove(mesh)
    obj.hide_set(False)
    return {"evaluate_ms": float(np.median(evaluate)), "frames": len(evaluate)}


#: The rig case's armatures: chains of these many bones along the dragon's long axis.
RIG_BONES = (3, 30, 100)
#: The rig case's parts of a frame's handler, each the time spent in the add-on's calls named:
#: the rig's bones read (playback.rig.Rig.frame), the simulation's step (Simulation.advance) and
#: the map of its q into the display's offset attribute (the simulation's displacement U q).
RIG_PARTS = {
    "bones": ("rig", ("frame",)),
    "step": ("simulation", ("advance",)),
    "map": ("simulation", ("displacement_of",)),
}


def chain_rig(obj, bones):
    """An armature of `bones` bones in a chain along obj's long axis, through the centre of its
    bounding box, placed as obj; obj's vertex groups named like them, weights by formula (linear
    between the bones' centres, two bones a vertex at most, in steps of 1/255: a call of
    VertexGroup.add a weight); an Armature modifier after the display's; the Attach group filled by
    the add-on's operator within a tenth of the dragon's length of the chain. Returns the armature."""
    V = blender_pose.addon("mesh_io").positions(obj.data)
    axis = int(np.argmax(np.ptp(V, axis=0)))
    low, high = V[:, axis].min(), V[:, axis].max()
    centre = (V.min(axis=0) + V.max(axis=0)) / 2
    armature = bpy.data.objects.new(f"Rig {bones}", bpy.data.armatures.new(f"Rig {bones}"))
    bpy.context.scene.collection.objects.link(armature)
    armature.matrix_world = obj.matrix_world
    view_layer = bpy.context.view_layer
    view_layer.objects.active = armature
    bpy.ops.object.mode_set(mode="EDIT")
    parent = None
    for b in range(bones):
        bone = armature.data.edit_bones.new(f"Bone{b}")
        head, tail = centre.copy(), centre.copy()
        head[axis] = low + (high - low) * b / bones
        tail[axis] = low + (high - low) * (b + 1) / bones
        bone.head, bone.tail = head, tail
        bone.parent, bone.use_connect = parent, parent is not None
        parent = bone
    bpy.ops.object.mode_set(mode="OBJECT")
    view_layer.objects.active = obj

    t = (V[:, axis] - low) / (high - low)
    centres = (np.arange(bones) + 0.5) / bones
    k = np.clip(np.searchsorted(centres, t) - 1, 0, bones - 2)
    s = np.clip((t - centres[k]) / (centres[k + 1] - centres[k]), 0.0, 1.0)
    vertex = np.repeat(np.arange(len(V)), 2)
    bone = np.column_stack([k, k + 1]).ravel()
    level = np.rint(255 * np.column_stack([1 - s, s]).ravel()).astype(np.int64)
    keep = level > 0
    vertex, bone, level = vertex[keep], bone[keep], level[keep]
    keys, inverse = np.unique(bone * 256 + level, return_inverse=True)
    order = np.argsort(inverse, kind="stable")
    groups = [obj.vertex_groups.new(name=f"Bone{b}") for b in range(bones)]
    for key, members in zip(keys, np.split(vertex[order], np.cumsum(np.bincount(inverse))[:-1])):
        groups[key // 256].add(members.tolist(), (key % 256) / 255, "REPLACE")
    modifier = obj.modifiers.new("Armature", "ARMATURE")
    modifier.object = armature
    reach = 0.1 * bones  # a tenth of the length, in bone lengths
    assert bpy.ops.modal_deform.fill_attach(reach=reach) == {"FINISHED"}
    return armature


def animate_rig(armature, bones, length):
    """The rig moves fast and stops: the armature object jumps by a fifth of `length` (frames 1 to
    5 up, 5 to 9 down) turning by 30 degrees about the vertical, then every bone bends by 60/bones
    degrees (frames 9 to 13) and back (13 to 17); still from frame 17 on."""
    armature.keyframe_insert("location", frame=1)
    armature.keyframe_insert("rotation_euler", frame=1)
    armature.location.z += 0.2 * length
    armature.keyframe_insert("location", frame=5)
    armature.location.z -= 0.2 * length
    armature.rotation_euler.z = math.radians(30)
    armature.keyframe_insert("location", frame=9)
    armature.keyframe_insert("rotation_euler", frame=9)
    for pose_bone in armature.pose.bones:
        pose_bone.rotation_mode = "XYZ"
        for frame, angle in ((9, 0.0), (13, 60.0 / bones), (17, 0.0)):
            pose_bone.rotation_euler = (0.0, 0.0, math.radians(angle))
            pose_bone.keyframe_insert("rotation_euler", frame=frame)


class Parts:
    """Milliseconds spent in the add-on's calls of RIG_PARTS during a frame, per part (each call
    of a method of the object's Player wrapped while it is in place)."""

    def __init__(self, player):
        self.ms = dict.fromkeys(RIG_PARTS, 0.0)
        self._wrapped = []
        for part, (owner_name, methods) in RIG_PARTS.items():
            owner = getattr(player, owner_name)
            for name in methods:
                setattr(owner, name, self._timed(part, getattr(owner, name)))
                self._wrapped.append((owner, name))

    def _timed(self, part, method):
        def timed(*args, **kwargs):
            start = time.perf_counter()
            try:
                return method(*args, **kwargs)
            finally:
                self.ms[part] += 1e3 * (time.perf_counter() - start)

        return timed

    def take(self):
        """The milliseconds since the last take, per part."""
        found, self.ms = self.ms, dict.fromkeys(RIG_PARTS, 0.0)
        return found

    def remove(self):
        for owner, name in self._wrapped:
            delattr(owner, name)


def timed_rig_frames(obj, scene, timeline, frame_cache, frames, rounds=ROUNDS):
    """Per frame of `frames`, played (the add-on's playback handlers called around them) and
    simulated live (the cache cut at the first frame each round): "before" Blender's evaluation from
    frame_set's call to the add-on's frame handler (the animation, the rig, the mesh with the offset
    it had), "handler" the handler's work (playback.timeline.show), split into RIG_PARTS and "other"
    (the checks, the cache, the attribute's update), "evaluate" Blender's evaluation after it (the
    mesh with its new offset: the display's Geometry Nodes modifier, then the Armature modifier),
    and the step's own milliseconds (Simulation.stats). Each: the median over the frames of its
    least over `rounds` rounds."""
    clock = HandlerClock()
    names = ("before", "handler", *RIG_PARTS, "other", "evaluate", "step_native")
    figures = {name: np.full((rounds, len(frames)), np.inf) for name in names}
    player = timeline.player(obj, scene)
    parts = Parts(player)
    playback_handler("animation_playback_pre")(scene, None)
    try:
        for round_ in range(rounds):
            frame_cache.get(obj).cut(frames[0])
            for index, frame in enumerate(frames):
                parts.take()
                called = time.perf_counter()
                scene.frame_set(frame)
                returned = time.perf_counter()
                assert obj.name not in timeline.problems, timeline.problems
                assert timeline.player(obj, scene) is player, "the Player was made again"
                handler = 1e3 * (clock.after - clock.before)
                split = parts.take()
                row = {
                    "before": 1e3 * (clock.before - called),
                    "handler": handler,
                    "other": handler - sum(split.values()),
                    "evaluate": 1e3 * (returned - clock.after),
                    "step_native": player.simulation.stats["ms"],
                    **split,
                }
                for name, value in row.items():
                    figures[name][round_, index] = value
    finally:
        clock.remove()
        parts.remove()
        playback_handler("animation_playback_post")(scene, None)
    result = {
        name + "_ms": float(np.median(values.min(axis=0))) for name, values in figures.items()
    }
    result.update(frames=len(frames), rounds=rounds)
    return result


def armature_alone(scene, frames, rounds=ROUNDS):
    """The floor: frame_set's time with the add-on's display and dynamics off the rigged mesh (the
    animation, the rig, the mesh's Armature modifier alone): the median over the frames of the
    least over `rounds` rounds."""
    times = np.full((rounds, len(frames)), np.inf)
    for round_ in range(rounds):
        for index, frame in enumerate(frames):
            start = time.perf_counter()
            scene.frame_set(frame)
            times[round_, index] = 1e3 * (time.perf_counter() - start)
    return {"evaluate_ms": float(np.median(times.min(axis=0))), "frames": len(frames)}


def rig_case(obj, scene, timeline, frame_cache, bones, timed):
    """Follow Rig on obj (its handles taken off) skinned by a chain of `bones` bones (chain_rig,
    animate_rig): the frames `timed` played (timed_rig_frames), then the same frames with the
    add-on's display and dynamics off (armature_alone); the rig, its vertex groups and Attach group
    taken off after."""
    settings = obj.modal_deform
    settings.handles.clear()
    timeline.free(obj)
    start = time.perf_counter()
    armature = chain_rig(obj, bones)
    setup_seconds = time.perf_counter() - start
    animate_rig(armature, bones, max(obj.dimensions))
    settings.dynamics.enabled = settings.dynamics.follow_rig = True
    start = time.perf_counter()
    scene.frame_set(1)  # the Player made: the rig's weights read once
    first_seconds = time.perf_counter() - start
    assert obj.name not in timeline.problems, timeline.problems
    attached = len(timeline.player(obj, scene).rig.attach)
    result = {
        "bones": bones,
        "attached": attached,
        "setup_seconds": setup_seconds,
        "first_frame_seconds": first_seconds,
        "played": timed_rig_frames(obj, scene, timeline, frame_cache, timed),
    }
    timeline.free(obj)
    settings.dynamics.follow_rig = settings.dynamics.enabled = False
    result["armature_alone"] = armature_alone(scene, timed)
    obj.modifiers.remove(obj.modifiers["Armature"])
    for group in list(obj.vertex_groups):
        if group.name.startswith("Bone") or group.name == settings.dynamics.attach_group:
            obj.vertex_groups.remove(group)
    settings.dynamics.attach_group = ""
    bpy.data.objects.remove(armature)
    return result


def saved_size(folder, name):
    path = os.path.join(folder, name)
    bpy.ops.wm.save_as_mainfile(filepath=path, copy=True)
    return os.path.getsize(path)


def main():
    args = arguments()
    blender_pose.ADDON = enable_addon().__name__
    blender_pose.clear_scene()
    frame_cache, timeline = blender_pose.addon("playback.frame_cache", "playback.timeline")
    name = "dragon_vrip_res4" if args.quick else "dragon_vrip_res2"
    obj, vertices, moving = blender_pose.posed_dragon(name, args.subdivide)
    settings = obj.modal_deform
    # The paper's 67 dimensions, as the pose benchmarks (blender_pose.py) bake them.
    settings.modes, settings.derivatives, settings.ghost = (
        (12, 12, 300) if args.quick else (15, 52, 1000)
    )
    start = time.perf_counter()
    assert bpy.ops.modal_deform.bake() == {"FINISHED"}
    bake_seconds = time.perf_counter() - start
    scene = bpy.context.scene
    frames = 20 if args.quick else args.frames
    timed = range(2, 2 + min(args.timed, frames - 1))
    scene.frame_start, scene.frame_end = 1, frames
    animate(moving.controller, frames)
    load_before = os.getloadavg()
    results = {
        "blender": bpy.app.version_string,
        "mesh": name,
        "subdivide": args.subdivide,
        "vertices": vertices,
        "dimension": settings.status.dimension,
        "proxy_vertices": settings.status.proxy_vertices,
        "bake_seconds": bake_seconds,
        "frames": frames,
    }

    if not args.rig_only:
        # The static animation: baked into the cache, then read back frame by frame.
        start = time.perf_counter()
        assert bpy.ops.modal_deform.bake_animation(frame_start=1, frame_end=frames) == {"FINISHED"}
        results["static_bake_seconds"] = time.perf_counter() - start
        results["static_cache_bytes"] = frame_cache.get(obj).nbytes()
        results["static_read"] = timed_frames(obj, scene, timeline, frame_cache, timed)
        with tempfile.TemporaryDirectory() as folder:
            if not args.no_sizes:
                results["blend_with_cache_bytes"] = saved_size(folder, "cache.blend")
                pc2 = os.path.join(folder, "dragon.pc2")
                assert bpy.ops.modal_deform.export_mesh_cache(filepath=pc2, file_format="PC2") == {
                    "FINISHED"
                }
                results["pc2_bytes"] = os.path.getsize(pc2)

            # Secondary motion: each frame simulated live from the one before, then read back.
            settings.dynamics.enabled = True
            timeline.set_frame(scene, 1)
            timeline.show(obj, scene)
            results["dynamic_step"] = timed_frames(
                obj, scene, timeline, frame_cache, timed, stepping=True
            )
            results["dynamic_step_still"] = timed_frames(
                obj, scene, timeline, frame_cache, timed, stepping=True, playing=False
            )
            results["dynamic_read"] = timed_frames(obj, scene, timeline, frame_cache, timed)
            results["dynamic_cache_bytes_per_frame"] = frame_cache.get(obj).nbytes() / len(
                frame_cache.get(obj)
            )
            results["dynamic_jump"] = jump_forward(obj, scene, timeline, frame_cache, len(timed))
            results["without_display"] = without_display(obj, timeline, frame_cache, timed)

            if not args.no_sizes:
                # The static animation as a shape key per frame, as Bake Animation wrote it before the cache.
                settings.dynamics.enabled = False
                assert bpy.ops.modal_deform.bake_animation(frame_start=1, frame_end=frames) == {
                    "FINISHED"
                }
                start = time.perf_counter()
                assert bpy.ops.modal_deform.export_shape_keys() == {"FINISHED"}
                results["shape_keys_export_seconds"] = time.perf_counter() - start
                results["blend_with_shape_keys_bytes"] = saved_size(folder, "keys.blend")
    # Follow Rig (issue 50): the dragon skinned by chains of bones, the frames played live.
    if obj.data.shape_keys is not None:  # the export's, which the rig's mesh has not
        obj.shape_key_clear()
    results["rig"] = [
        rig_case(obj, scene, timeline, frame_cache, bones, timed)
        for bones in (args.rig_bones[:1] if args.quick else args.rig_bones)
    ]
    results["load_average"] = {"before": load_before, "after": os.getloadavg()}
    pathlib.Path(args.output).write_text(json.dumps(results, indent=1))
    print(json.dumps(results, indent=1))


main()
