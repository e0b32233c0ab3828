"""Inside Blender: meshes with shape keys for Blend as Shapes (shapes/), built in the test."""

import bpy
import numpy as np

from . import blender


def bend(V, angle):
    """V (mdc.testing.bar's: 1 by 1 by 4 along z) bent by `angle` radians into a circular arc in the
    x-z plane, its centre line (x = 0.5) keeping its length and its base (z = 0) in place."""
    radius = V[:, 2].max() / angle
    rho = radius - (V[:, 0] - 0.5)
    phi = V[:, 2] / radius
    X = V.copy()
    X[:, 0] = 0.5 + radius - rho * np.cos(phi)
    X[:, 2] = rho * np.sin(phi)
    return X


def mesh_object(V, F, name="Bar"):
    """A new mesh object of V, F (float64, int) in place of the startup file's objects, active."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(V.tolist(), [], F.tolist())
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    return obj


def add_key(obj, name, X):
    """A shape key `name` holding X (#V by 3), relative to the basis, at value 0."""
    if obj.data.shape_keys is None:
        obj.shape_key_add(name="Basis", from_mix=False)
    block = obj.shape_key_add(name=name, from_mix=False)
    block.data.foreach_set("co", np.asarray(X, np.float32).ravel())
    return block


def bar_with_bend(modes=12, derivatives=20, ghost=300):
    """The bar mdc.testing.bar(3, 3, 12) (1 by 1 by 4) as a mesh with a key "Bend" bending it 90°,
    the add-on's bake settings set; (obj, V, F, bent) with V and bent float64 as Blender holds them
    (float32 values)."""
    mdc = blender.enable_addon("core")
    V, F = mdc.testing.bar(3, 3, 12)
    V = V.astype(np.float32).astype(np.float64)
    obj = mesh_object(V, F)
    bent = bend(V, np.pi / 2).astype(np.float32).astype(np.float64)
    add_key(obj, "Bend", bent)
    settings = obj.modal_deform
    settings.modes, settings.derivatives, settings.ghost = modes, derivatives, ghost
    return obj, V, F, bent


class _Layout:
    """A stand-in for Blender's UILayout that records the labels and operators drawn (headless
    Blender draws no panel)."""

    def __init__(self, drawn):
        self.drawn = drawn

    def __getattr__(self, name):  # column(), row(), box(), prop(), ...: a layout again
        return lambda *args, **kwargs: self

    def label(self, text="", **kwargs):
        self.drawn.append(text)

    def operator(self, idname, text="", **kwargs):
        self.drawn.append(f"[{text or idname}]")
        return self


def draw_panels(obj):
    """The text of Blend as Shapes's panels drawn for obj (the sidebar's, then the Shape Keys'
    addition), one string."""
    import sys
    import types

    # The enabled add-on's module (enabling again would re-register it and forget its problems).
    panel = next(m for name, m in sys.modules.items() if name.endswith("modal_deform.shapes.panel"))
    drawn = []
    region = types.SimpleNamespace(width=400)
    preferences = types.SimpleNamespace(system=types.SimpleNamespace(ui_scale=1.0))
    context = types.SimpleNamespace(object=obj, region=region, preferences=preferences)
    layout = _Layout(drawn)
    panel.VIEW3D_PT_modal_deform_shapes.draw(types.SimpleNamespace(layout=layout), context)
    panel._draw_in_shape_keys(types.SimpleNamespace(layout=layout), context)
    return " ".join(drawn)
