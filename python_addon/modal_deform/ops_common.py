"""What the operators share: the poll of operators that act on a mesh (or a controller of one),
and the errors they report to the artist instead of raising."""
from . import handles, posing, storage

#: Errors with a message for the artist: not baked or stale, a bad handle, a bad option.
FAILURES = (storage.NotReady, handles.HandleError, ValueError, RuntimeError)


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
    if posing.is_posing(obj):
        cls.poll_message_set("Posing: Enter applies the pose, Esc cancels it")
        return False
    return True


class ThreadJobOperator:
    """What the bake and Refine operators share: a jobs job run at once (execute) or on its thread
    (invoke) with a progress bar and status text on a timer, Esc to cancel, the result reported when
    the thread ends. Subclasses give _job(context) (raising one of FAILURES for the artist),
    _status() (the status text) and _finish() (report; the operator's return value)."""

    def execute(self, context):
        try:
            self.job = self._job(context)
        except FAILURES as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self.job.run()
        return self._finish()

    def invoke(self, context, event):
        try:
            self.job = self._job(context)
        except FAILURES as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self.job.start()
        wm = context.window_manager
        self.timer = wm.event_timer_add(0.1, window=context.window)
        wm.progress_begin(0, 1000)
        wm.modal_handler_add(self)
        self._show(context)
        return {"RUNNING_MODAL"}

    def _show(self, context):
        context.window_manager.progress_update(int(1000 * self.job.overall))
        context.workspace.status_text_set(f"{self._status()}   (Esc: cancel)")

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            self.job.cancel()
        if event.type != "TIMER":
            return {"RUNNING_MODAL"} if event.type == "ESC" else {"PASS_THROUGH"}
        if not self.job.done:
            self._show(context)
            return {"RUNNING_MODAL"}
        self._stop(context)
        result = self._finish()
        for area in context.screen.areas:
            area.tag_redraw()
        return result

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
