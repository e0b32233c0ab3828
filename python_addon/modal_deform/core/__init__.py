"""Modal Deform's Python API, free of bpy: numpy in, numpy out.

    import modal_deform.core as mdc

The pipeline, one module per stage: ``mesh`` (check, mass, reading), ``energy`` (discrete
shells, ARAP), ``modes`` (vibration modes, rigid motions, modal-derivative solves), ``reduction``
(the ghost), ``bake`` (the whole preprocess, mesh to Basis), ``solve`` (posing), ``dynamics``
(secondary motion), ``shapes`` (shape keys blended as shapes); ``testing`` holds the generated test shapes.
"""

from .._native import Cancelled, OutOfMemoryError
from . import testing as testing
from .bake import BAKE_OPTIONS, BAKE_STAGES, Basis, bake
from .bake import bake_fraction as bake_fraction
from .dynamics import SIMULATION_OPTIONS, Simulation
from .energy import MATERIAL_OPTIONS, Arap, DiscreteShells
from .frame_budget import FrameBudget as FrameBudget
from .inbetween import INBETWEEN_OPTIONS, Inbetween
from .mesh import check, mass, read_mesh
from .modes import rigid_motions, solve_in_range, vibration_modes
from .reduction import ghost_mesh, restrict_to_ghost
from .rig import skin
from .shapes import BLEND_OPTIONS, ShapeSpace
from .solve import (
    FULL_SOLVE_OPTIONS,
    SOLVE_OPTIONS,
    SOLVER_OPTIONS,
    ReducedSolver,
    solve_full,
)
from .solve import nearest_rigid as nearest_rigid
from .solve import rigid_fit as rigid_fit

# FrameBudget, bake_fraction, nearest_rigid and rigid_fit serve the add-on, testing the tests: mdc.<name>
# works (imported `as` themselves, re-exported), __all__ leaves them out.
__all__ = [
    "Arap",
    "BAKE_OPTIONS",
    "BAKE_STAGES",
    "BLEND_OPTIONS",
    "Basis",
    "Cancelled",
    "DiscreteShells",
    "FULL_SOLVE_OPTIONS",
    "INBETWEEN_OPTIONS",
    "Inbetween",
    "MATERIAL_OPTIONS",
    "OutOfMemoryError",
    "ReducedSolver",
    "SIMULATION_OPTIONS",
    "SOLVER_OPTIONS",
    "SOLVE_OPTIONS",
    "ShapeSpace",
    "Simulation",
    "bake",
    "check",
    "ghost_mesh",
    "mass",
    "read_mesh",
    "restrict_to_ghost",
    "skin",
    "rigid_motions",
    "solve_full",
    "solve_in_range",
    "vibration_modes",
]
