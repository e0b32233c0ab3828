"""What the operators share: the poll of operators that act on a mesh (or a controller of one),
the errors they report to the artist instead of raising (playback's frame handler too), the
lifecycle of the long ones (JobOperator) and the interactive pose under way, whose mesh the others
leave alone (running, is_posing)."""

from . import handles, storage

#: Errors with a message for the artist: not baked or stale, a bad handle, a bad option.
FAILURES = (storage.NotReady, handles.HandleError, ValueError, RuntimeError)
#: The interactive pose under way, or None: the Pose operator (pose/operators.py), set while it
#: runs. Besides .pose (its posing.Pose) it offers keep_in_shape_key(), request_end(how) and
#: end(context, how).
running = None


def is_posing(obj):
    """Whether the interactive pose runs on obj: its mesh is then not to be baked, solved or
    checked for staleness (its positions may hold the pose)."""
    try:
        return running is not None and running.pose.obj == obj
    except (
        ReferenceError
    ):  # the pose's object went away (undo, file loaded): it ends at its next event
        return False


def mesh_poll(cls, context):
    """The mesh object's operators: a mesh or its controller active, in Object Mode, not linked, not
    being posed (its positions may hold the pose)."""
    obj = handles.owner(context.object)
    if obj is None:
        cls.poll_message_set("Select a mesh object (or a controller of one)")
        return False
    if obj.mode != "OBJECT":
        cls.poll_message_set("Switch to Object Mode")
        return False
    if obj.library is not None or obj.data.library is not None:
        cls.poll_message_set("The object is linked from a library")
        return False
    if is_posing(obj):
        cls.poll_message_set("Posing: Enter applies the pose, Esc cancels it")
        return False
    return True


class JobOperator:
    """The lifecycle of the long operators (bake, Refine, animation bake) around a jobs job: run at
    once (execute), or (invoke) started and ticked on a timer with a progress bar and status text,
    Esc to cancel, and the job's report when it ends. Subclasses give _job(context) (raising one of
    FAILURES for the artist) and _status() (the status text); the operator finishes when the job
    changed the object and is cancelled otherwise."""

    def _start(self, context):
        try:
            self.job = self._job(context)
        except FAILURES as error:
            self.report({"ERROR"}, str(error))
            return False
        return True

    def execute(self, context):
        if not self._start(context):
            return {"CANCELLED"}
        self.job.run()
        return self._finish()

    def invoke(self, context, event):
        if not self._start(context):
            return {"CANCELLED"}
        self.job.start()
        wm = context.window_manager
        self.timer = wm.event_timer_add(self.job.tick_seconds, window=context.window)
        wm.progress_begin(0, 1000)
        wm.modal_handler_add(self)
        self._show(context)
        return {"RUNNING_MODAL"}

    def _show(self, context):
        context.window_manager.progress_update(int(1000 * self.job.overall))
        if context.workspace is not None:
            context.workspace.status_text_set(f"{self._status()}   (Esc: cancel)")

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            self.job.cancel()
        if event.type != "TIMER":
            return {"RUNNING_MODAL"} if event.type == "ESC" else {"PASS_THROUGH"}
        if self.job.tick():
            self._show(context)
            return {"RUNNING_MODAL"}
        self._stop(context)
        result = self._finish()
        for area in context.screen.areas:
            area.tag_redraw()
        return result

    def _finish(self):
        level, message = self.job.finish()
        self.report({level}, message)
        return {"FINISHED"} if self.job.written else {"CANCELLED"}

    def _stop(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self.timer)
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)

    def cancel(self, context):
        """Blender ends the operator (file loaded, window closed): the job stops, nothing is written."""
        self.job.cancel()
        self._stop(context)
