"""Solving the in-betweens into the per-frame cache and showing them.

InbetweenJob reads everything on the main thread (the basis and handles of the object's Player,
the keys, the settings), solves on a thread (core.Inbetween; the solve itself is one native call,
so Esc takes effect once it returns) and takes the state (q, v) of every frame of the scene's range
into a new cache of kind "INBETWEEN", which finish() puts in place of the old one: until then the
old motion plays. The cache records the signature and the keyframes' digest the motion was solved
for; show() plays it as long as the basis fits, and asks for a new solve (request) when the
signature or the keys changed. Before the cache's first frame the mesh holds that frame, after its
last frame the last one (the motion before the first key holds that key's static pose, and after
the last key it settles as Simulation would, up to the scene's end).

Only one motion is solved at a time for an object; a solve that failed or was cancelled is not
asked again until the keys or the settings change (the panel says why, and Solve In-betweens
asks again).
"""

import json

import bpy
import numpy as np

from .. import core as mdc
from .. import handles, storage
from ..jobs import ThreadJob
from ..ops_common import FAILURES
from ..playback import frame_cache, frame_display, rig, timeline
from . import keys as keys_

#: The key error, as a fraction of the mesh's diagonal, above which the panel says a key is missed.
MISSED = 0.01
#: Why a rig's mesh gets no in-betweens: the core's motion is not skinned (core.Inbetween has no rig).
ON_A_RIG = "In-betweens do not follow a rig: turn Follow Rig or In-betweens off"
#: obj name -> the job solving its motion now; obj name -> (signature, digest) of the last solve
#: that failed or was cancelled, and why (not asked again until they change).
running = {}
refused = {}
# obj name -> the last Player made for it, which maps the motion solved last while a handle is
# unusable (x̄ + U q depends on the basis alone).
_mappers = {}


def freshness(obj, scene):
    """(signature, keyframes' digest) of obj now: what its in-betweens are solved for."""
    return frame_cache.signature(obj, scene), frame_cache.keys_digest(
        frame_cache.controller_curves(obj)
    )


def is_fresh(cache, wanted):
    """Whether `cache` holds the in-betweens for `wanted` (freshness)."""
    return cache.kind == "INBETWEEN" and (cache.signature, cache.block["keys_digest"]) == wanted


def key_errors(inbetween, rest, keyed_handles, keys):
    """[(frame, handle name, error)]: how far each keyed handle's rigid fit at its key lies from the
    keyed transform (the largest distance over its vertices), as a fraction of the mesh's diagonal."""
    diagonal = float(np.linalg.norm(np.ptp(rest, axis=0)))
    errors = []
    for frame, transforms in keys:
        X = inbetween.positions(frame).astype(np.float64)
        for handle, T in zip(keyed_handles, transforms):
            if T is None:
                continue
            points = np.c_[rest[handle.indices], np.ones(len(handle.indices))]
            fit = mdc.rigid_fit(rest[handle.indices], X[handle.indices])
            miss = np.linalg.norm(points @ (fit - T)[:3].T, axis=1).max()
            errors.append((frame, handle.name, float(miss / diagonal)))
    return errors


class InbetweenJob(ThreadJob):
    """One solve of obj's in-betweens for its keys and settings now (read on the calling thread)."""

    thread_name = "modal_deform in-betweens"

    def __init__(self, obj, scene):
        if rig.follows(obj):
            raise ValueError(ON_A_RIG)
        self.object_name = obj.name
        self.stage, self.fraction = "reading the keys", 0.0
        self.cancelling = False
        self.error = self.cache = None
        self.seconds = 0.0
        self.wanted = freshness(obj, scene)
        self.fingerprint = storage.fingerprint(obj.data)
        player = timeline.player(obj, scene, self.wanted[0])
        self.basis, self.handles = player.basis, player.handles
        self.keys = keys_.read(obj, scene, self.handles)
        settings, dynamics = obj.modal_deform, obj.modal_deform.dynamics
        self.options = dict(
            pull=settings.stiffness,
            period=dynamics.period,
            damping=dynamics.damping,
            fps=scene.render.fps / scene.render.fps_base,
            substeps=dynamics.substeps,
            weights=[h.weight for h in self.handles],
            energy=settings.status.energy.lower(),
        )
        self.frames = range(max(0, scene.frame_start), max(0, scene.frame_end) + 1)
        self.basis_id = frame_cache.basis_id(obj)
        self.notes = []

    @property
    def overall(self):
        return 0.1 + 0.9 * self.fraction if self.stage == "frames" else 0.05

    def _work(self):
        self.stage = "solving"
        inbetween = mdc.Inbetween(
            self.basis, [h.indices for h in self.handles], self.keys, **self.options
        )
        stats = inbetween.solve()
        self.stage = "frames"
        self.states = []
        for i, frame in enumerate(self.frames):
            if self.cancelling:
                raise mdc.Cancelled("in-betweens cancelled")
            self.states.append(inbetween.state(frame))
            self.fraction = (i + 1) / len(self.frames)
        self.stats = stats
        errors = key_errors(inbetween, self.basis.rest, self.handles, self.keys)
        missed = [e for e in errors if e[2] > MISSED]
        if missed:
            frame, name, error = max(missed, key=lambda e: e[2])
            self.notes.append(
                f"{len(missed)} keyed poses missed by more than {MISSED:.0%} of the mesh's size (the "
                f"worst: handle '{name}' at frame {frame}, {error:.1%}): the basis cannot reach "
                f"them; key a smaller move, or bake more modes and derivatives"
            )
        if not stats["converged"]:
            self.notes.append(
                f"solve stopped at {stats['iterations']} iterations, short of converging: the "
                f"motion is near the one of least force"
            )

    def finish(self):
        """Put the motion in place of obj's cache (main thread): (level, message) for a report."""
        obj, report = self._finished_object(
            "In-betweens",
            f"'{self.object_name}' changed during the solve: the motion was discarded",
        )
        if report:
            return report
        if frame_cache.basis_id(obj) != self.basis_id:
            return "WARNING", "the basis was baked again during the solve: the motion was discarded"
        if frame_cache.kind(obj) != "INBETWEEN":
            return (
                "WARNING",
                "In-betweens were turned off during the solve: the motion was discarded",
            )
        scene = bpy.context.scene
        cache = frame_cache.create(obj, scene, self.frames[0])
        cache.block["kind"] = "INBETWEEN"
        cache.block["signature"], cache.block["keys_digest"] = self.wanted
        cache.block["notes"] = json.dumps(self.notes)
        for q, v in self.states:
            cache.append(q, v, np.empty(0), np.empty(0))
        self.written = True
        message = (
            f"In-betweens of '{obj.name}' through {len(self.keys)} keys (frames "
            f"{self.keys[0][0]} to {self.keys[-1][0]}) in {self.seconds:.1f} s, cached for frames "
            f"{self.frames[0]} to {self.frames[-1]}"
        )
        if self.notes:
            return "WARNING", message + ": " + "; ".join(self.notes)
        return "INFO", message


def notes(cache):
    """What the solve of a cache of in-betweens said of its keys (missed, not converged)."""
    return json.loads(cache.block.get("notes", "[]"))


def request(obj, scene):
    """Ask for obj's in-betweens for its keys and settings now, unless they are being solved or
    were refused as they are: solved here at once in a Blender without windows (a render, a
    script), else in the background with a progress bar (operators.solve_in_background)."""
    if obj.name in running:
        return
    wanted = freshness(obj, scene)
    if refused.get(obj.name, (None,))[0] == wanted:
        return
    refused.pop(obj.name, None)
    windows = bpy.context.window_manager.windows if bpy.context.window_manager else ()
    if bpy.app.background or not windows:
        solve_now(obj, scene)
    else:
        from . import operators

        operators.solve_in_background(obj, windows[0])


def solve_now(obj, scene):
    """Solve obj's in-betweens here: (level, message); the reason is kept when it fails."""
    try:
        job = InbetweenJob(obj, scene)
    except FAILURES as error:
        return failed(obj, scene, "ERROR", str(error))
    job.run()
    level, message = job.finish()
    return (level, message) if job.written else failed(obj, scene, level, message)


def failed(obj, scene, level, message):
    """Remember why obj's in-betweens could not be solved for its keys and settings now."""
    refused[obj.name] = (freshness(obj, scene), message)
    return level, message


def problem(obj):
    """Why obj's in-betweens are not what its keys and settings ask for now ("" when they are, or
    while they are solved)."""
    found = refused.get(obj.name)
    return found[1] if found else ""


def show(obj, scene, edits_reported=False, stand_in=False):
    """Show obj's in-betweens at the scene's frame (timeline.show for a cache of kind
    "INBETWEEN"; `stand_in` while the timeline plays), asking for them again when the keys or the
    settings changed: meanwhile, and when that fails for a handle that cannot be used now, the
    motion solved last plays on. Raises storage.NotReady when the mesh changed since the bake,
    ValueError when there is no motion to show and none is being solved, or obj follows a rig."""
    if rig.follows(obj):
        raise ValueError(ON_A_RIG)
    cache = frame_cache.get(obj)
    try:
        player = timeline.player(obj, scene)
        player.check_mesh(obj, edits_reported)
        _mappers[obj.name] = player
    except handles.HandleError as error:
        player = _mappers.get(obj.name)
        failed(obj, scene, "ERROR", str(error))
        if player is None or cache is None or player.basis_id != cache.basis_id:
            raise
    usable = cache is not None and cache.kind == "INBETWEEN" and len(cache)
    if usable and cache.basis_id == frame_cache.basis_id(obj):
        if is_fresh(cache, freshness(obj, scene)):
            refused.pop(obj.name, None)
        else:
            request(obj, scene)
    else:
        request(obj, scene)
        cache = frame_cache.get(obj)
        usable = cache is not None and cache.kind == "INBETWEEN" and len(cache)
    if not usable or player.basis_id != cache.basis_id:
        if obj.name in running:  # the panel says it is solving; the mesh shows itself meanwhile
            frame_display.remove(obj)
            return
        raise ValueError(problem(obj) or "In-betweens: not solved")
    frame = min(max(scene.frame_current, cache.start), cache.end)
    mesh = frame_display.frame_mesh(obj, stand_in=stand_in)
    player.positions(cache.array("q")[cache.row(frame)], frame_display.frame_positions(mesh))
    mesh.update()


def forget(*args):
    running.clear()
    refused.clear()
    _mappers.clear()
