"""Blender's app handlers (bpy.app.handlers), registered one way by every module that has some.

A module lists its handlers as (name, function) pairs, e.g. (("load_post", _forget),), and calls
register(pairs) and unregister(pairs) from its own register() and unregister(). Every handler is
persistent (kept when a file is loaded); names this Blender lacks (the playback handlers before
Blender 4) are skipped; registering twice or unregistering what is not registered changes nothing.
"""

import bpy


def register(pairs):
    for name, function in pairs:
        handlers = getattr(bpy.app.handlers, name, None)
        if handlers is not None and function not in handlers:
            handlers.append(bpy.app.handlers.persistent(function))


def unregister(pairs):
    for name, function in pairs:
        handlers = getattr(bpy.app.handlers, name, None)
        if handlers is not None and function in handlers:
            handlers.remove(function)
