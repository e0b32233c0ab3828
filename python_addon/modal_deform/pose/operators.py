"""Posing operators: interactive (modal, timer-driven), solve (converged, for scripts), refine (the
exact minimum on the full mesh, on a thread with progress and Esc), reset."""

import time

import bpy

from .. import core as mdc
from .. import handles, mesh_io, ops_common
from ..ops_common import FAILURES, JobOperator, mesh_poll
from . import displays, posing
from .refine import RefineJob


class MODAL_DEFORM_OT_pose(bpy.types.Operator):
    """Pose interactively: move the controllers (G, R) and the mesh follows. Enter or right-click > Apply \
keeps the pose, Esc restores the mesh as it was"""

    bl_idname = "modal_deform.pose"
    bl_label = "Pose"
    bl_options = {"REGISTER", "UNDO"}

    poll = classmethod(mesh_poll)

    def invoke(self, context, event):
        obj = handles.owner(context.object)
        try:
            self.pose = posing.Pose(context, obj)
        except FAILURES as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        for warning in self.pose.warnings:
            self.report({"WARNING"}, warning)
        self.shown = displays.display(obj)
        self.area = context.area
        self.request = None
        self.tick_ms = 0.0
        # The solve gets what the rest of the update leaves of a 60 fps frame (FrameBudget): ours is
        # timed in the tick, Blender's evaluation and drawing from the tick's end to the viewport's
        # next draw (no viewport drawn: the artist's budget).
        self.budget = mdc.FrameBudget(obj.modal_deform.budget)
        self.written_at = self.drawn_at = None
        self.rest_ms = 0.0
        self.draw_handler = bpy.types.SpaceView3D.draw_handler_add(
            self._drawn, (), "WINDOW", "POST_PIXEL"
        )
        wm = context.window_manager
        self.timer = wm.event_timer_add(1.0 / 60.0, window=context.window)
        wm.modal_handler_add(self)
        context.workspace.status_text_set(
            "Modal Deform: move the controllers (G, R)   Enter: apply   Esc: cancel   Right-click: menu"
        )
        ops_common.running = self
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if self.request is not None:
            return self.end(context, self.request)
        if (
            event.type == "TIMER"
        ):  # ours or another's: a tick either way (3.x events do not say whose)
            return self._tick(context)
        if event.value == "PRESS":
            if event.type == "ESC":
                return self.end(context, "CANCEL")
            if event.type in {"RET", "NUMPAD_ENTER"}:
                return self.end(context, "APPLY")
            if event.type == "RIGHTMOUSE":
                bpy.ops.wm.call_menu(name=MODAL_DEFORM_MT_pose.bl_idname)
                return {"RUNNING_MODAL"}
            if event.type == "Z" and (event.ctrl or event.oskey):
                self.report({"WARNING"}, "Undo is off while posing: Enter applies, Esc cancels")
                return {"RUNNING_MODAL"}
        return {"PASS_THROUGH"}

    def _drawn(self):
        if self.written_at is not None and self.drawn_at is None:
            self.drawn_at = time.perf_counter()

    def _tick(self, context):
        if (
            self.drawn_at is not None
        ):  # the last update was drawn: all it took besides the solve is known
            self.budget.measured(self.rest_ms + 1e3 * (self.drawn_at - self.written_at))
            self.written_at = self.drawn_at = None
        obj = self.pose.obj
        try:
            obj.mode
        except ReferenceError:  # deleted while posing
            return self.end(context, "CANCEL")
        if obj.mode != "OBJECT":
            self.report({"WARNING"}, "Left Object Mode: the pose so far is kept")
            return self.end(context, "APPLY")
        start = time.perf_counter()
        try:
            moved = self.pose.follow_controllers()
            if (
                not self.shown.shows_pose()
            ):  # shape keys added mid-pose: the pose goes on in the key
                self.keep_in_shape_key()
            if moved or not self.pose.stats["converged"]:
                solve_ms = self.pose.step(self.budget.ms)["ms"]
                self.pose.write(self.shown.array())
                self.written_at, self.drawn_at = time.perf_counter(), None
                self.tick_ms = 1e3 * (self.written_at - start)
                self.rest_ms = self.tick_ms - solve_ms
        except FAILURES as error:  # e.g. a controller deleted while posing
            self.report({"ERROR"}, str(error))
            return self.end(context, "CANCEL")
        if self.area is not None:
            self.area.header_text_set(posing.header_text(self.pose.stats, self.tick_ms))
        return {"PASS_THROUGH"}

    def keep_in_shape_key(self):
        """The pose so far into the "Modal Deform" shape key, where it goes on (a file saved mid-pose,
        shape keys added mid-pose)."""
        self.shown = self.shown.keep(self.pose)

    def request_end(self, how):
        """End at the next event: "APPLY" keeps the pose, "CANCEL" restores the mesh."""
        self.request = how

    def end(self, context, how):
        """End now: the timer, draw handler and texts go, and the pose is kept ("APPLY") or the mesh
        restored ("CANCEL"). Returns the operator's result."""
        ops_common.running = None
        context.window_manager.event_timer_remove(self.timer)
        bpy.types.SpaceView3D.draw_handler_remove(self.draw_handler, "WINDOW")
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        try:
            if self.area is not None:
                self.area.header_text_set(None)
            if how == "CANCEL":
                self.shown.restore()
            else:
                self.keep_in_shape_key()
        except (
            ReferenceError
        ):  # the object (or the screen) went away while posing: nothing to restore
            return {"CANCELLED"}
        return {"CANCELLED"} if how == "CANCEL" else {"FINISHED"}

    def cancel(self, context):
        """Blender ends the operator (file loaded, window closed): put the mesh back."""
        self.end(context, "CANCEL")


class MODAL_DEFORM_OT_pose_end(bpy.types.Operator):
    """End the interactive pose"""

    bl_idname = "modal_deform.pose_end"
    bl_label = "End Pose"
    bl_options = {"INTERNAL"}

    how: bpy.props.EnumProperty(
        items=(
            ("APPLY", "Apply", "Keep the pose in the shape key"),
            ("CANCEL", "Cancel", "Restore the mesh as it was before posing"),
        ),
        description="Whether the pose is kept or the mesh restored",
    )

    @classmethod
    def poll(cls, context):
        return ops_common.running is not None

    def execute(self, context):
        ops_common.running.request_end(self.how)
        return {"FINISHED"}


class MODAL_DEFORM_MT_pose(bpy.types.Menu):
    bl_idname = "MODAL_DEFORM_MT_pose"
    bl_label = "Modal Deform"

    def draw(self, context):
        layout = self.layout
        layout.operator(
            MODAL_DEFORM_OT_pose_end.bl_idname, text="Apply", icon="CHECKMARK"
        ).how = "APPLY"
        layout.operator(
            MODAL_DEFORM_OT_pose_end.bl_idname, text="Cancel", icon="CANCEL"
        ).how = "CANCEL"


class MODAL_DEFORM_OT_solve(bpy.types.Operator):
    """Solve the pose for the controllers as they are, to convergence, into the "Modal Deform" shape key"""

    bl_idname = "modal_deform.solve"
    bl_label = "Solve"
    bl_options = {"REGISTER", "UNDO"}

    max_iterations: bpy.props.IntProperty(
        name="Max Iterations",
        default=posing.CONVERGE_MAX_ITERATIONS,
        min=1,
        description="BFGS iterations at most; fewer may leave the pose unfinished",
    )
    tolerance: bpy.props.FloatProperty(
        name="Tolerance",
        default=mdc.SOLVE_OPTIONS["tolerance"].default,
        min=1e-12,
        max=0.5,
        description="Stopping tolerance of the Gill-Murray-Wright test: smaller "
        "solves more exactly and takes longer",
    )

    poll = classmethod(mesh_poll)

    def execute(self, context):
        obj = handles.owner(context.object)
        try:
            pose = posing.Pose(context, obj)
            pose.follow_controllers()
            stats = pose.converge(self.max_iterations, self.tolerance)
        except FAILURES as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        for warning in pose.warnings:
            self.report({"WARNING"}, warning)
        pose.write(mesh_io.shape_key_co(obj.data, posing.pose_key(obj)[0]))
        state = posing.state(stats)
        summary = f"after {stats['iterations']} iterations in {stats['ms']:.0f} ms (energy {stats['energy']:.5g})"
        if state == "converged":
            self.report({"INFO"}, f"Converged {summary}")
        elif state == "stalled":
            self.report({"WARNING"}, f"Stalled {summary}: {posing.STALLED_HINT}")
        else:
            self.report({"WARNING"}, f"Not converged {summary}")
        return {"FINISHED"}


class MODAL_DEFORM_OT_refine(JobOperator, bpy.types.Operator):
    """Solve the pose for the controllers as they are, then polish it on the full mesh (Newton's method) into \
the "Modal Deform" shape key: the exact physically based shape, for a final frame. Takes seconds; Esc cancels"""

    bl_idname = "modal_deform.refine"
    bl_label = "Refine"
    bl_options = {"REGISTER", "UNDO"}

    max_iterations: bpy.props.IntProperty(
        name="Max Iterations",
        default=mdc.FULL_SOLVE_OPTIONS["max_iterations"].default,
        min=1,
        description="Newton iterations at most; fewer may leave the pose unfinished",
    )
    tolerance: bpy.props.FloatProperty(
        name="Tolerance",
        default=mdc.FULL_SOLVE_OPTIONS["tolerance"].default,
        min=1e-12,
        max=0.5,
        description="Factor by which the gradient must shrink: smaller solves more "
        "exactly and takes longer",
    )

    poll = classmethod(mesh_poll)

    def _job(self, context):
        job = RefineJob(context, handles.owner(context.object), self.tolerance, self.max_iterations)
        for warning in job.pose.warnings:
            self.report({"WARNING"}, warning)
        return job

    def _status(self):
        job = self.job
        action = "cancelling" if job.cancelling else f"{100 * job.overall:.0f}%"
        return f"Modal Deform: refining '{job.object_name}': {action}"


class MODAL_DEFORM_OT_reset(bpy.types.Operator):
    """Back to rest: controllers return to where they were assigned and the "Modal Deform" shape key goes"""

    bl_idname = "modal_deform.reset"
    bl_label = "Reset Pose"
    bl_options = {"REGISTER", "UNDO"}

    poll = classmethod(mesh_poll)

    def execute(self, context):
        obj = handles.owner(context.object)
        for item in obj.modal_deform.handles:
            handles.restore(obj, item)
        mesh_io.remove_shape_keys(obj, [posing.POSE_KEY])
        return {"FINISHED"}


CLASSES = (
    MODAL_DEFORM_OT_pose,
    MODAL_DEFORM_OT_pose_end,
    MODAL_DEFORM_MT_pose,
    MODAL_DEFORM_OT_solve,
    MODAL_DEFORM_OT_refine,
    MODAL_DEFORM_OT_reset,
)


register, _unregister_classes = bpy.utils.register_classes_factory(CLASSES)


def unregister():
    """Disabling the add-on mid-pose ends the pose as Esc does: Blender drops the modal handler of
    an unregistered operator without calling it, which would leave its timer, header text and
    half-made shape key (or posed vertex positions) behind."""
    if ops_common.running is not None:
        ops_common.running.end(bpy.context, "CANCEL")
    _unregister_classes()
