"""Modal Deform's Python API, free of bpy: numpy in, numpy out.

    import modal_deform.core as mdc

The pipeline, one module per stage: ``mesh`` (check, mass, reading), ``energy`` (discrete
shells, ARAP), ``modes`` (vibration modes, rigid motions, modal-derivative solves), ``reduction``
(the ghost), ``bake`` (the whole preprocess, mesh to Basis), ``solve`` (posing), ``dynamics``
(secondary motion); ``testing`` holds the generated test shapes.
"""
from .._native import Cancelled, OutOfMemoryError
from .bake import BAKE_OPTIONS, BAKE_STAGES, PROXY, PROXY_ABOVE, Basis, bake, bake_fraction
from .dynamics import MAX_SUBSTEPS, MIN_PERIOD_FRAMES, SIMULATION_DEFAULTS, Simulation
from .energy import Arap, DiscreteShells
from .frame_budget import FrameBudget
from . import testing
from .mesh import check, mass, read_mesh
from .modes import rigid_motions, solve_in_range, vibration_modes
from .reduction import ghost_mesh, restrict_to_ghost
from .solve import FULL_SOLVE_MAX_ITERATIONS, FULL_SOLVE_OPTIONS, SOLVE_TOLERANCE, ReducedSolver, nearest_rigid, solve_full

# FrameBudget, bake_fraction and nearest_rigid serve the add-on: mdc.<name> works, __all__ leaves them out.
__all__ = [
    "Arap", "BAKE_OPTIONS", "BAKE_STAGES", "Basis", "PROXY", "PROXY_ABOVE", "Cancelled", "DiscreteShells", "OutOfMemoryError", "bake", "check",
    "ghost_mesh", "mass", "read_mesh", "restrict_to_ghost", "rigid_motions", "solve_in_range",
    "vibration_modes",
]
__all__ += ["FULL_SOLVE_MAX_ITERATIONS", "FULL_SOLVE_OPTIONS", "SOLVE_TOLERANCE", "ReducedSolver", "solve_full"]
__all__ += ["MAX_SUBSTEPS", "MIN_PERIOD_FRAMES", "SIMULATION_DEFAULTS", "Simulation"]
