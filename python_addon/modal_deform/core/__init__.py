"""Modal Deform's Python API, free of bpy: numpy in, numpy out.

    import modal_deform.core as mdc

The pipeline, one module per stage: ``mesh`` (check, mass, test shapes).
"""
from .._native import Cancelled
from .energy import DiscreteShells
from .mesh import bar, bumpy_plane, check, cylinder, grid, mass, read_mesh

__all__ = ["Cancelled", "DiscreteShells", "bar", "bumpy_plane", "check", "cylinder", "grid", "mass", "read_mesh"]
