"""The per-frame cache of an object's reduced state, in the .blend file: what a static animation
bake or the simulation computed for each frame, played back as x = x̄ + U q (timeline.py).

What: from the cache's first frame on, one row per frame of q (r,) (the coordinates of the basis
vectors) and, for a simulation, of its velocity; a few hundred bytes a frame where a shape key per
frame costs 12 bytes a vertex. Beside them, what each frame was computed from, to tell when it no
longer holds: the controllers' transforms at that frame (the handles' 4x4 matrices) and the values
of the controllers' animation curves there; and, for the whole cache, its kind ("STATIC": the
pose of each frame; "DYNAMIC": the simulation; "INBETWEEN": the in-betweens, solved whole by
inbetweens/motion.py), the bake id of the basis and a signature of the settings (dynamics
parameters, stiffness, handles).

Where: like the basis (storage.py), a Palette datablock named with a leading "." that
``Object.modal_deform.dynamics.cache`` points to, each array one flat float64 ID property (Blender
keeps the bytes: the cache reloads bit for bit), read back by ``np.frombuffer``. An array may hold
room for more frames after the last one: a frame is cached by writing its row in place (append()).

Invalidation, as Blender's point caches: a change of a setting or of the basis empties the cache
(the next frame shown starts it again); a changed keyframe of a controller cuts the cache before the
first frame whose curve values changed (``keyframes_changed``, when the keyframes' digest changed,
checked at every frame shown); and a frame whose controllers stand elsewhere than when it was cached (a
constraint, a driver, a moved parent) cuts the cache there when it is shown.
"""

import hashlib
import json

import bpy
import numpy as np
from mathutils import Matrix

from .. import handles, mesh_io, storage
from . import rig

PREFIX = ".Modal Deform Cache "
_IDENTITY = Matrix.Identity(4)
#: "rig", on a rig only (playback/rig.py): each frame's rig (Rig.frame), the bones whose motion the
#: next frame's step needs (Simulation.rig_state: the frame's and the one before's).
_ARRAYS = ("q", "v", "transforms", "curves", "rig")
_OPTIONAL = ("rig",)
#: What a cache datablock holds (create() writes them all; an optional array only on a rig).
_FIELDS = (
    "kind",
    "start",
    "signature",
    "basis_id",
    "curve_paths",
    "keys_digest",
    "frames",
) + tuple(f for name in _ARRAYS if name not in _OPTIONAL for f in (name, name + "_width"))


def kind(obj):
    """The kind of cache obj's settings call for: "INBETWEEN" with dynamics and its in-betweens
    enabled (inbetweens/), "DYNAMIC" with dynamics enabled, else "STATIC"."""
    dynamics = obj.modal_deform.dynamics
    if not dynamics.enabled:
        return "STATIC"
    return "INBETWEEN" if dynamics.inbetweens else "DYNAMIC"


def _pose_fields(obj):
    """The settings the static pose depends on, (name, value) pairs: the stiffness and the handles."""
    settings = obj.modal_deform
    return (
        ("stiffness", settings.stiffness),
        (
            "handles",
            tuple(
                (
                    h.vertex_group,
                    h.weight,
                    h.controller.name if h.controller else "",
                    tuple(value for row in h.bind_matrix for value in row),
                )
                + ((h.bone,) if h.bone else ())  # an object controller's as before bones came
                + (  # a handle bound in the rig's rest pose as before bind_skinning came
                    ()
                    if h.bind_skinning == _IDENTITY
                    else (tuple(value for row in h.bind_skinning for value in row),)
                )
                for h in settings.handles
            ),
        ),
    )


def pose_signature(obj):
    """What the static pose depends on besides the basis and the controllers' motion, as a string
    (the repr of plain values: every frame shown computes it, where JSON took twice as long)."""
    return repr(_pose_fields(obj))


def signature(obj, scene):
    """What the cached frames depend on besides the controllers' motion, as a string (as
    pose_signature): the settings of the kind of cache obj's settings call for, the handles and the
    scene's frame rate."""
    dynamics = obj.modal_deform.dynamics
    fields = (("kind", kind(obj)),) + _pose_fields(obj)
    if dynamics.enabled:
        fields += (
            ("period", dynamics.period),
            ("damping", dynamics.damping),
            ("substeps", dynamics.substeps),
            # In-betweens start at the first key and are cached over the scene's frames.
            ("range", scene.frame_start, scene.frame_end)
            if dynamics.inbetweens
            else ("start", dynamics.frame_start),
            ("fps", scene.render.fps / scene.render.fps_base),
        )
        if dynamics.follow_rig:
            fields += (("rig", rig.signature(obj)),)
    return repr(fields)


def basis_id(obj):
    """The bake id of obj's stored basis ("" when there is none)."""
    block = obj.modal_deform.basis
    return "" if block is None else str(block.get(storage.BAKE_ID, ""))


class Cache:
    """A view of an object's cache datablock: its kind, first frame, frames and arrays (read-only
    numpy views; append() and cut() write the datablock)."""

    def __init__(self, block):
        """Raises ValueError when the datablock lacks what a cache holds (damaged, or not a cache)."""
        missing = [name for name in _FIELDS if name not in block]
        if missing:
            raise ValueError(
                f"the cache '{block.name}' is damaged (no '{missing[0]}'): Free it and bake again"
            )
        self.block = block

    kind = property(lambda self: self.block["kind"])
    start = property(lambda self: self.block["start"])
    signature = property(lambda self: self.block["signature"])
    basis_id = property(lambda self: self.block["basis_id"])
    curve_paths = property(lambda self: json.loads(self.block["curve_paths"]))

    def array(self, name):
        """(frames, width) float64 view of the array `name` ("q", "v", "transforms", "curves",
        "rig")."""
        width = self.block.get(name + "_width", 0)
        if not width:
            return np.empty((len(self), 0))
        return _values(self.block, name)[: len(self) * width].reshape(-1, width)

    def __len__(self):
        """The number of frames cached, from start on."""
        return self.block["frames"]

    @property
    def end(self):
        """The last frame cached (start - 1 when empty)."""
        return self.start + len(self) - 1

    def row(self, frame):
        """The index of `frame`'s row, or None when it is not cached."""
        index = frame - self.start
        return index if 0 <= index < len(self) else None

    def state(self, frame):
        """(q, v) of a cached frame (v None for a static cache), copies."""
        index = self.row(frame)
        v = self.array("v")
        return self.array("q")[index].copy(), (v[index].copy() if v.shape[1] else None)

    def append(self, q, v, transforms, curves, rig=None):
        """Add the frame after the last (end + 1): each row written in place into the room its array
        keeps after the last frame, the array grown to twice the frames when full (so that caching a
        frame costs the same at any length of cache, where copying every array grew with it)."""
        frames = len(self)
        rows = {
            "q": q,
            "v": np.empty(0) if v is None else v,
            "transforms": transforms,
            "curves": curves,
            "rig": np.empty(0) if rig is None else rig,
        }
        for name, row in rows.items():
            row = np.asarray(row, np.float64).ravel()
            width = self.block.get(name + "_width", 0)
            if not row.size and not width:
                continue
            if frames and row.size != width:
                raise ValueError(
                    f"cache: frame {self.end + 1}'s {name} has {row.size} values, earlier frames "
                    f"{width}"
                )
            if not frames or name not in self.block or len(self.block[name]) < (frames + 1) * width:
                room = np.zeros(max(_FIRST_ROOM, 2 * (frames + 1)) * row.size)
                room[: frames * width] = self.array(name).ravel()
                _set_array(self.block, name, room)
                self.block[name + "_width"] = width = row.size
            _values(self.block, name)[frames * width : (frames + 1) * width] = row
        self.block["frames"] = frames + 1

    def cut(self, frame):
        """Forget `frame` and every frame after it."""
        keep = max(0, min(len(self), frame - self.start))
        if keep == len(self):
            return
        for name in _ARRAYS:
            width = self.block.get(name + "_width", 0)
            if name not in self.block:
                continue
            _set_array(
                self.block, name, self.array(name)[:keep].ravel().copy() if width else np.empty(0)
            )
        self.block["frames"] = keep

    def nbytes(self):
        return sum(self.array(name).nbytes for name in _ARRAYS)


#: The frames an array has room for when its first frame is cached.
_FIRST_ROOM = 16


def _values(block, name):
    """The flat float64 array `name` of the datablock, a writeable view of its ID property."""
    value = block[name]
    return np.frombuffer(value, dtype=np.float64) if len(value) else np.empty(0)


def _set_array(block, name, values):
    """block[name] = values (float64), the old array deleted first: Blender 4.5 corrupts its heap
    when an ID property array is assigned over one of another length."""
    if name in block:
        del block[name]
    block[name] = values


def get(obj):
    """obj's Cache, or None; raises ValueError when its datablock is damaged."""
    block = obj.modal_deform.dynamics.cache
    return None if block is None else Cache(block)


def create(obj, scene, start):
    """A new empty cache for obj, starting at frame `start`, for obj's settings and controller
    curves as they are now, in place of any other."""
    free(obj)
    block = bpy.data.palettes.new(PREFIX + obj.name)
    block.use_fake_user = False
    block["kind"] = kind(obj)
    block["start"] = start
    block["signature"] = signature(obj, scene)
    block["basis_id"] = basis_id(obj)
    curves = controller_curves(obj)
    block["curve_paths"] = json.dumps([path for path, _ in curves])
    block["keys_digest"] = keys_digest(curves)
    block["frames"] = 0
    for name in _ARRAYS:
        if name not in _OPTIONAL:
            _set_array(block, name, np.empty(0))
            block[name + "_width"] = 0
    obj.modal_deform.dynamics.cache = block
    return Cache(block)


def free(obj):
    """Forget obj's cache (the datablock goes when no other object uses it)."""
    storage.release(obj.modal_deform.dynamics, "cache")


def outdated(cache, obj, signature_now):
    """Why the cache no longer fits obj ("" when it does): another kind, settings or basis.
    `signature_now`: signature(obj, scene), which the caller computes once for the frame."""
    if cache.kind != kind(obj):
        return "dynamics switched " + ("on" if kind(obj) == "DYNAMIC" else "off")
    if cache.basis_id != basis_id(obj):
        return "the basis was baked again"
    if cache.signature != signature_now:
        return "a setting changed"
    return ""


def settings_changed(obj):
    """A dynamics setting changed: the cache no longer holds (a static cache does not depend on them)."""
    cache = get(obj)
    if kind(obj) == "INBETWEEN" and cache is not None and cache.kind == "INBETWEEN":
        return  # the motion plays until the one for the new settings is solved (inbetweens/)
    if cache is not None and cache.kind != "STATIC" or obj.modal_deform.dynamics.enabled:
        free(obj)


def controller_curves(obj):
    """The animation curves of obj's controllers, as (path, F-curve): path "controller:data_path[index]";
    on a rig, then those that move the rig (rig.action_curves).
    A bone's are those of its armature's action that move it: the armature object's own (paths not
    under pose.bones) and those of the bone and its parents (paths under pose.bones["name"])."""
    from .frame_keys import action_fcurves

    found = []
    for handle in obj.modal_deform.handles:
        controller = handle.controller
        if controller is None:
            continue
        moves = moves_bone(handles.pose_bone(handle))
        for curve in action_fcurves(controller.animation_data) or ():
            if moves(curve.data_path):
                found.append((f"{controller.name}:{curve.data_path}[{curve.array_index}]", curve))
    found.sort(key=lambda item: item[0])
    return found + (rig.action_curves(obj) if rig.follows(obj) else [])


def moves_bone(bone):
    """A test of a data path of the armature's action: whether it can move `bone` (a pose bone;
    None: every path, as for an object)."""
    if bone is None:
        return lambda path: True
    chain = [bone, *bone.parent_recursive]
    prefixes = tuple(f'pose.bones["{bpy.utils.escape_identifier(b.name)}"]' for b in chain)

    def moves(path):
        return not path.startswith("pose.bones[") or path.startswith(prefixes)

    return moves


def curve_values(curves, frame):
    """The values of the curves (controller_curves) at `frame`."""
    return np.array([curve.evaluate(frame) for _, curve in curves], np.float64)


#: The first bytes of each keyframe in Blender's array of them (BezTriple): its point and both
#: handles, float[3][3].
_KEYFRAME_POINTS_BYTES = 36
#: The distance between two keyframes in that array (the size of a BezTriple, one for a build of
#: Blender), read from the first curve of two keyframes or more that keys_digest meets.
_keyframe_stride = None


def keys_digest(curves):
    """A hash of the curves' keyframes and extrapolation: cheap enough for every frame shown, it
    tells when keyframes_changed must compare values. Each curve's keyframes are hashed as the bytes
    of Blender's array of them (BezTriple, one after another, read in place, as
    mesh_io.item_memory reads it, from the first keyframe alone once the stride is known): every
    keyframe whole (point, handles, interpolation, easing and its parameters) but the last, of which
    only the point and handles shape the curve. A change that moves no value (a selection) leads to
    a comparison that finds nothing. One hash of every curve's bytes joined: every frame shown pays
    this per F-curve (306 on a rig of 100 bones)."""
    global _keyframe_stride
    parts = []
    for path, curve in curves:
        points = curve.keyframe_points
        count = len(points)
        parts.append(f"{path}:{curve.extrapolation}:{count}".encode())
        if not count:
            continue
        memory, stride = mesh_io.item_memory(points, _KEYFRAME_POINTS_BYTES, _keyframe_stride)
        if count > 1:
            _keyframe_stride = stride
        parts.append(memory)
    return hashlib.blake2b(b"".join(parts), digest_size=16).hexdigest()


def keyframes_changed(cache, curves):
    """Cut the cache at the first frame whose controller curves (controller_curves of its object)
    no longer give the values it was cached with (a key added, moved, deleted or its interpolation
    changed); the whole cache when the set of curves changed. Only compares values when the
    keyframes' digest changed. Returns the frame cut from, or None."""
    digest_now = keys_digest(curves)
    if digest_now == cache.block["keys_digest"]:
        return None
    cache.block["keys_digest"] = digest_now
    if [path for path, _ in curves] != cache.curve_paths:
        cache.block["curve_paths"] = json.dumps([path for path, _ in curves])
        cache.cut(cache.start)
        return cache.start
    recorded = cache.array("curves")
    for index in range(len(cache)):
        frame = cache.start + index
        if not np.array_equal(curve_values(curves, frame), recorded[index]):
            cache.cut(frame)
            return frame
    return None


def digest(cache):
    """A hash of the cached arrays (tests compare a cache before and after a reload by it)."""
    h = hashlib.blake2b(digest_size=16)
    for name in _ARRAYS:
        h.update(cache.array(name).tobytes())
    return h.hexdigest()
