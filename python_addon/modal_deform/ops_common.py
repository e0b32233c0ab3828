"""What the operators share: the poll of operators that act on a mesh (or a controller of one),
and the errors they report to the artist instead of raising."""
from . import handles, storage

#: Errors with a message for the artist: not baked or stale, a bad handle, a bad option.
FAILURES = (storage.NotReady, handles.HandleError, ValueError, RuntimeError)


def mesh_poll(cls, context):
    """The mesh object's operators: a mesh or its controller active, in Object Mode, not linked."""
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
    return True
