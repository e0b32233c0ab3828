"""Modal Deform: pose high-resolution meshes with a physically based energy in a reduced space.

This file only registers the Blender layer. ``modal_deform.core`` is the bpy-free API and
imports without Blender.
"""
bl_info = {
    "name": "Modal Deform",
    "author": "Modal Deform developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Modal Deform",
    "description": "Interactive surface modeling with vibration modes and modal derivatives",
    "category": "Mesh",
}


def register():
    pass


def unregister():
    pass
