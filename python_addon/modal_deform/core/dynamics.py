"""Secondary motion: the mesh follows its controllers with inertia, in the basis it was baked with.

The dynamics whose quasi-static limits are the poses (paper section 3), integrated in the reduced
space x = x̄ + U q by the implicit midpoint rule written as a minimisation, each step solved by
the warm-started BFGS of posing and its end velocity rescaled to the energy the step should have
(docs/design.md, "Secondary motion", has the scheme and its reasons). The artist's parameters are in frames: ``period``, the period of the lowest flexible mode (it sets
the mass), and ``damping``, that mode's damping ratio ζ (Rayleigh damping, stiffer modes damped
more). Both hold exactly for the lowest mode of small motions, whatever ``fps`` and ``substeps``.
"""

import numpy as np

from .. import _native
from . import _arrays, _inputs, _options
from .solve import SOLVER_OPTIONS

#: Simulation's options, the native core's (cpp/solve/reduced_dynamics.h): {name: Option}.
SIMULATION_OPTIONS = _options.table(_native.SIMULATION_OPTIONS)


class Simulation(_inputs.InBasis):
    """Reduced dynamics of a baked basis driven by handles.

    ``basis``: from ``mdc.bake`` (kept alive). ``handles``: a list of vertex index arrays, one per
    controller, possibly empty (a free body); ``weights``: one per handle (default 1); ``energy``:
    as for ReducedSolver. ``period`` and ``damping`` hold exactly for the lowest flexible mode of
    small motions; see step() for ``memory_frames``. Starts at rest, at rest velocity, with every
    controller at the identity. Raises ValueError naming the argument that is wrong.
    """

    @_options.takes_options(SIMULATION_OPTIONS)
    def __init__(
        self, basis, handles, weights=None, energy=SOLVER_OPTIONS["energy"].default, **options
    ):
        basis = _inputs.basis(basis)
        handles = [] if _inputs.is_empty(handles) else _inputs.handles(handles)
        weights = np.zeros(0) if not handles else _inputs.weights(weights, len(handles))
        if not isinstance(energy, str):
            raise ValueError(f'energy: expected "shells" or "arap", got {energy!r}')
        self._native = _native.Simulation(basis._native, handles, weights, energy, **options)
        self._basis = basis
        self.stats = None  #: the last step's: see step()

    @property
    def num_handles(self):
        return self._native.num_handles

    def step(self, transforms, out=None):
        """Advances one frame: the controllers reach ``transforms`` (one rigid 4x4 per handle; [] for
        a free body) at its end, moving there from the previous frame's (rotations by slerp, each
        handle's centre on a straight line). Returns the positions at the frame's end, as
        ``positions(out)``. ``self.stats`` then holds {"substeps", "iterations", "evaluations",
        "converged", "stalled", "line_search_failures", "implicit_euler", "energy_removed",
        "energy_added", "ms"}: "converged" when every substep's minimisation met its stopping
        test, "stalled" when one could not decrease its objective (its state is taken all the
        same: the step never fails), "energy_removed" and "energy_added" what the energy
        correction took from the motion and gave to it (each substep ends with the energy it had,
        plus the handles' work, less the damping's: the midpoint rule alone drifts either way on a
        nonlinear energy, and an unconverged substep may create energy), "implicit_euler" the
        substeps a violent motion had taken by implicit Euler instead. No substep ends above the
        energy it had plus the handles' work.

        BFGS keeps what it learnt of the curvature from step to step (far fewer evaluations a
        frame), and forgets it before a step when it holds ``memory_frames`` frames, at forget()
        and at set_state() of a state not the simulation's own: a frame is a function of the
        state it starts from and of the frames since the memory was forgotten
        (``remembered_frames``). For the same bits however a frame is reached, forget at fixed
        blocks of frames and reach a frame inside a block by stepping from the block's start
        (playback.Player.next does).
        """
        self.advance(transforms)
        return self.positions(out)

    def advance(self, transforms):
        """step() without the positions, for a frame simulated only to reach a later one (a jump
        forward): the fine mesh's map costs as much as reading U (40 MB at 100k vertices). Returns
        ``self.stats``."""
        self.stats = self._native.step(self._checked_transforms(transforms))
        return self.stats

    def forget(self):
        """Forgets BFGS's memory: the next step learns the curvature afresh."""
        self._native.forget()

    @property
    def memory_frames(self):
        return self._native.memory_frames

    @property
    def remembered_frames(self):
        """The frames stepped since BFGS's memory was last forgotten (at most memory_frames)."""
        return self._native.remembered_frames

    @property
    def state(self):
        """(q, v): the reduced coordinates (r,) and their velocity (r,) per second (copies), in the
        coordinates of basis.vectors' columns: what a cache stores."""
        return self._native.q, self._native.v

    def positions_of(self, q, out=None):
        """x̄ + U q for a q of its own (e.g. a cached frame's), as ``positions(out)`` does for the
        simulation's; the simulation's state stays as it is."""
        out = _arrays.positions_out(out, self.num_vertices)
        self._native.positions_of(_arrays.values(q, "q", self.dimension), out.reshape(-1))
        return out

    def set_state(self, q, v, transforms=None):
        """Puts the simulation at (q, v), e.g. a cached frame's, or a pose's ``ReducedSolver.q``
        with zero velocity. ``transforms``: the controllers' at that state (one 4x4 per handle), the
        start of the next step; None keeps the current ones. BFGS's memory (step()) is forgotten
        unless this is the simulation's own state, bit for bit."""
        r = self.dimension
        q = _arrays.values(q, "q", r)
        v = _arrays.values(v, "v", r)
        self._native.set_state(
            q, v, [] if transforms is None else self._checked_transforms(transforms)
        )

    def energy(self):
        """The total energy, kinetic plus potential (deformation energy plus handle term), in the
        normalised frame at the current transforms."""
        return self._native.energy()

    def kinetic_energy(self):
        return self._native.kinetic_energy()

    def potential_energy(self):
        return self._native.potential_energy()

    @property
    def lowest_mode(self):
        """The lowest flexible mode of the reduced rest Hessian (r,), unit norm: the motion whose
        period is ``period``."""
        return self._native.lowest_mode

    @property
    def mass_scale(self):
        """ρ: the reduced mass matrix is ρ I."""
        return self._native.mass_scale

    def _checked_transforms(self, transforms):
        if _inputs.is_empty(transforms):
            transforms = []
        return _inputs.transforms(transforms, self._native.num_handles)
