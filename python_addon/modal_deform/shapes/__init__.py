"""Shape Keys > Blend as Shapes: the mesh shows the rotation-aware blend of its shape keys
(core.shapes.ShapeSpace) for the keys' values, live and on the timeline, and renders so. keys.py
reads the keys into the space's shapes and weights, blending.py bakes, stores and shows the blend,
operators.py holds the operators and panel.py the panels."""
