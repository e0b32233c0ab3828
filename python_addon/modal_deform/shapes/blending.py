"""Blend as Shapes on an object: its shape space in the .blend, whether it still fits the keys, and
the blend shown for the keys' values.

Stored as the basis is (storage.write_arrays: a hidden Palette that ``Object.modal_deform.shapes.space``
points to), with the names of its keys and a digest of the faces, basis and keys at the bake
(keys.digest): reloading costs milliseconds, no bake. Stale when a key of the space, its Relative To,
the basis or the faces changed since (checked each time the blend is shown: the keys are compared
with copies of the keys last hashed, the digest computed again only when they differ); a key of
the space removed or renamed, too. A key added after the bake stays out of the space: at
weight 0 it changes nothing, at another weight the blend is refused until a re-bake takes it in.

Shown as Dynamics shows its frames (playback/frame_display.py: a Geometry Nodes modifier sets the
positions from a point attribute, a stand-in while the timeline plays), recomputed when the weights
change: at a frame change (a render's too, from the render's evaluated keys) and at any update of
the scene (a key's value moved, keyed or driven): before Blender evaluates it, from the keys'
values as set (a value moved in the panel: that one evaluation shows the blend), and after, from
the evaluated keys (drivers, keyframes: the blend written then is evaluated a second time). A blend is a function of the weights alone
(core.shapes), so the weights last shown are all that is remembered. When the blend cannot be shown
(stale, a weight that is not a number, a key added after the bake with a weight) the display goes,
so the mesh shows Blender's own mix, and the panel says why (problems). Dynamics on the same object
wins: while it plays (enabled, or a cache) its frames show and the blend waits.
"""

import time

import bpy
import numpy as np

from .. import app_handlers, storage
from .. import core as mdc
from ..ops_common import FAILURES, is_posing
from ..playback import frame_display, timeline
from . import keys

PREFIX = ".Modal Deform Shapes "
#: What the panel says while Dynamics plays on an object with Blend as Shapes on.
DYNAMICS_WINS = (
    "Dynamics plays on this object, and its frames show instead of the blend: turn Dynamics off "
    "and Free its cache to see the blend"
)

# Loaded spaces by bake id.
_spaces = storage.RecentLoads(2)
# By object name: (bake id, weights bytes) of the blend shown; the keys last compared with the
# digest (bake id, vertex and corner counts, copies of the arrays, Relative To names) and the stale
# reason found then; the problem that keeps the blend from showing, and a note on the blend shown
# (it diverged, or stopped early).
_shown = {}
_checked = {}
# Whether the handler before Blender's evaluation ran in this update (_update_after).
_shown_before = False
problems = {}
notes = {}


def store(obj, space, digest, names, seconds):
    """Keep `space` (baked of obj's keys `names`, whose keys.digest was `digest`) as obj's space."""
    block = storage.write_arrays(PREFIX + obj.name, space.to_arrays())
    settings = obj.modal_deform.shapes
    storage.release(settings, "space")
    settings.space = block
    settings.key_names = "\n".join(names)
    settings.keys_digest = digest
    settings.dimension = space.dimension
    settings.baked_at = time.strftime("%Y-%m-%d %H:%M")
    settings.seconds = seconds
    _spaces.keep(block[storage.BAKE_ID], space)
    _shown.pop(obj.name, None)


def clear(obj):
    """Forget obj's space and turn Blend as Shapes off (the mesh shows Blender's mix)."""
    settings = obj.modal_deform.shapes
    settings.enabled = False
    storage.release(settings, "space")
    for name in ("key_names", "keys_digest", "dimension", "baked_at", "seconds"):
        settings.property_unset(name)


def space_names(obj):
    """The names of the keys of obj's stored space, in order."""
    return obj.modal_deform.shapes.key_names.split("\n")


def load(obj):
    """obj's stored ShapeSpace (cached per bake). Raises NotReady when there is none or it is damaged."""
    block = obj.modal_deform.shapes.space
    if block is None:
        raise storage.NotReady(f"'{obj.name}': its shape keys are not baked as shapes: Bake")
    return _spaces.load(
        block, mdc.ShapeSpace.from_arrays, f"the shape space stored for '{obj.name}'"
    )


def stale_reason(obj):
    """Why obj's stored space no longer fits its keys ("" when it fits), e.g. "shape key 'Jaw' was
    removed or renamed"; keys.check's refusal when the keys cannot be blended."""
    settings = obj.modal_deform.shapes
    try:
        keys.check(obj)
        arrays, relatives = keys.raw(obj, space_names(obj))
    except ValueError as error:
        return str(error)
    except KeyError as error:
        return f"shape key {error} of the space was removed or renamed"
    mesh = obj.data
    bake_id = settings.space.get(storage.BAKE_ID) if settings.space is not None else None
    counts = (len(mesh.vertices), len(mesh.loops))
    found = _checked.get(obj.name)
    if (
        found is not None
        and found[:2] == (bake_id, counts)
        and found[3] == relatives
        and all(np.array_equal(a, b) for a, b in zip(arrays, found[2]))
    ):
        return found[4]
    reason = ""
    if keys.digest(obj, space_names(obj)) != settings.keys_digest:
        reason = "a key, its Relative To, the basis or the faces were edited"
    _checked[obj.name] = (bake_id, counts, [a.copy() for a in arrays], relatives, reason)
    return reason


def ready(obj):
    """obj's ShapeSpace when it fits the keys now; raises NotReady saying what to do otherwise."""
    if obj.modal_deform.shapes.space is None:
        raise storage.NotReady(f"'{obj.name}': its shape keys are not baked as shapes: Bake")
    reason = stale_reason(obj)
    if reason:
        raise storage.NotReady(f"Shape keys changed since the bake ({reason}): re-bake")
    return load(obj)


def weights(obj, depsgraph=None):
    """The weights of obj's space's keys now ((k,) float64, finite); raises ValueError naming a key
    whose weight is not a number or a key outside the space with a weight."""
    names = space_names(obj)
    w, outside = keys.weights(obj, names, depsgraph)
    if outside:
        raise ValueError(
            f"shape key '{outside[0]}' came after the bake and has a weight: re-bake to blend it, "
            f"or set it to 0"
        )
    bad = np.flatnonzero(~np.isfinite(w))
    if bad.size:
        raise ValueError(
            f"shape key '{names[bad[0]]}' has the weight {w[bad[0]]} (its driver or keyframes?): "
            f"the blend needs a number"
        )
    return w


def blend(obj, space, w, out=None):
    """The blend of obj's `space` (ready()) for the weights `w` ((k,), weights()), #V by 3 float32,
    into `out` when given (a #V by 3 float32 array, contiguous or not); notes what a diverged or
    unconverged blend shows."""
    if out is None or out.flags.c_contiguous:
        out = space.blend(w, out=out)
    else:  # Blender 3.4's strided vertex positions
        out[...] = space.blend(w)
    stats = space.stats
    if stats.get("diverged"):
        notes[obj.name] = (
            "At these weights the blend has no shape to settle on (it ran off): the linear mix shows"
        )
    elif not stats.get("converged", True):
        notes[obj.name] = "At these weights the blend stopped before settling"
    else:
        notes.pop(obj.name, None)
    return out


def linear(obj, w):
    """Blender's mix of the space's shapes for `w`: basis + Σ w_i (shape_i − basis), #V by 3 float64."""
    V = keys.basis(obj)
    X = V.copy()
    for wi, shape in zip(w, keys.shapes(obj, V, space_names(obj))):
        X += wi * (shape - V)
    return X


def show(obj, depsgraph=None):
    """Show on obj the blend for its keys' weights now (read from `depsgraph`'s evaluated keys when
    given), unless it shows already. Raises one of FAILURES saying why it cannot."""
    w = weights(obj, depsgraph)
    space = ready(obj)
    state = (obj.modal_deform.shapes.space[storage.BAKE_ID], w.tobytes())
    playing = timeline._playing  # while the timeline plays, a stand-in shows (frame_display)
    if (
        _shown.get(obj.name) == state
        and frame_display.shows(obj)
        and (not playing or frame_display.has_stand_in(obj))
    ):
        return
    mesh = frame_display.frame_mesh(obj, stand_in=playing)
    blend(obj, space, w, out=frame_display.frame_positions(mesh))
    mesh.update()
    _shown[obj.name] = state


def hide(obj):
    """Take the blend off obj (unless Dynamics shows its frames there): it shows Blender's mix."""
    _shown.pop(obj.name, None)
    notes.pop(obj.name, None)
    if not timeline.plays(obj):
        frame_display.remove(obj)


def refresh(obj, depsgraph=None):
    """Show the blend on obj when Blend as Shapes is on and it can (problems says why not), else
    take it off."""
    settings = obj.modal_deform.shapes
    if not settings.enabled or obj.type != "MESH" or obj.library is not None:
        problems.pop(obj.name, None)
        hide(obj)
        return
    if obj.mode != "OBJECT" or is_posing(obj):  # the mesh being edited or posed shows
        return
    if timeline.plays(obj):
        problems[obj.name] = DYNAMICS_WINS
        _shown.pop(obj.name, None)
        return
    try:
        show(obj, depsgraph)
    except FAILURES as error:
        if problems.get(obj.name) != str(error):
            print(f"Modal Deform: '{obj.name}' cannot blend as shapes: {error}")
        problems[obj.name] = str(error)
        hide(obj)
        return
    problems.pop(obj.name, None)


def _update(scene, depsgraph=None):
    for obj in scene.objects:
        if obj.type == "MESH" and obj.modal_deform.shapes.enabled:
            refresh(obj, depsgraph)


def _update_before(scene, depsgraph=None):
    """Before Blender evaluates an update: the blend for the keys' values as set, so that the
    evaluation shows it (written after it, it would take a second evaluation)."""
    global _shown_before
    _update(scene)
    _shown_before = True


def _update_after(scene, depsgraph=None):
    """After Blender evaluated an update: the blend for the evaluated keys (drivers, keyframes).
    Where the handler before the evaluation showed the blend for these weights already, nothing
    (the keys themselves cannot change during an evaluation: they were checked then)."""
    global _shown_before
    checked, _shown_before = _shown_before, False
    for obj in scene.objects:
        if obj.type == "MESH" and obj.modal_deform.shapes.enabled:
            if checked and _shows_weights(obj, depsgraph):
                continue
            refresh(obj, depsgraph)


def _shows_weights(obj, depsgraph):
    """Whether the blend shown on obj is the one for its keys' weights in `depsgraph`."""
    shown, block = _shown.get(obj.name), obj.modal_deform.shapes.space
    if shown is None or block is None:
        return False
    try:
        w = weights(obj, depsgraph)
    except ValueError:
        return False
    return shown == (block[storage.BAKE_ID], w.tobytes())


def _undone(*args):
    """An undo reads the meshes back: the blends shown are computed again."""
    _shown.clear()
    _checked.clear()


def _forget(*args):
    _spaces.clear()
    _shown.clear()
    _checked.clear()
    problems.clear()
    notes.clear()


_HANDLERS = (
    ("frame_change_post", _update),
    ("depsgraph_update_pre", _update_before),
    ("depsgraph_update_post", _update_after),
    ("undo_post", _undone),
    ("redo_post", _undone),
    ("load_post", _forget),
)


def register():
    app_handlers.register(_HANDLERS)


def unregister():
    app_handlers.unregister(_HANDLERS)
    for obj in bpy.data.objects:
        if obj.type == "MESH" and obj.library is None and obj.modal_deform.shapes.enabled:
            hide(obj)
    _forget()
