"""Secondary motion: the mesh follows its controllers with inertia, in the basis it was baked with.

The dynamics whose quasi-static limits are the poses (paper section 3), integrated in the reduced
space x = x̄ + U q by the implicit midpoint rule written as a minimisation, each step solved by
the warm-started BFGS of posing and its end velocity rescaled to the energy the step should have
(docs/design.md, "Secondary motion", has the scheme and its reasons). The artist's parameters are in frames: ``period``, the period of the lowest flexible mode (it sets
the mass), and ``damping``, that mode's damping ratio ζ (Rayleigh damping, stiffer modes damped
more). Both hold exactly for the lowest mode of small motions, whatever ``fps`` and ``substeps``.

On a rig (``rig=W``, skinning weights), the simulated unknown is a displacement of the mesh in its
rest space, x = x̄ + U q, that linear blend skinning then carries: the world shape is
``skin(x, W, B)`` (``rig.skin``). It is driven by the inertial forces of the skinned motion, felt
in each vertex's frame:

- for vertex i, the world acceleration of its rest point, Ä_i x̄_i with A_i = Σ_b W_ib B_b, pulled
  back into rest space per bone: c_i = Σ_b W_ib L_b⁻¹ B̈_b x̄_i (L_b the bone's 3x3 linear part).
  This is L_i⁻¹ Ä_i x̄_i exactly where a vertex follows one bone or its bones move together (a
  free point then stays still in world space), L_bᵀ for rigid bones; L⁻¹ rather than Lᵀ so that a
  scaled bone does not scale the felt acceleration by its scale squared; per bone rather than by
  the blended L_i⁻¹ so that the force stays linear in each bone's L_b⁻¹ B̈_b and its projection on
  the basis is precomputed (at a joint bent in between the two differ by the bones' relative turn);
- the force −m_i c_i projected on the basis, per unit of the reduced mass ρ: g = −s⁴ Uᵀ M c (s the
  normalised frame's scale; the basis is M-orthonormal there), so ρ q̈ = ρ g − ∇V − damping: the
  rig's motion moves the mesh the same whatever the period;
- the centrifugal, Euler and Coriolis forces of the rotating frame acting on the displacement
  itself (L⁻¹ L̈ u, 2 L⁻¹ L̇ u̇) are dropped: first order in the small displacement, the centrifugal
  one relative to the elastic forces as (the rig's angular speed / the lowest mode's)², zero
  whenever the rig is still, and keeping them would cost O(b² r²) a frame and make the stiffness
  the period sets depend on the rig's speed;
- B̈ is the second difference of the frame's bones with the previous two frames' (B_{n+1} − 2 B_n
  + B_{n−1}) fps², taken with L_b of B_n, constant over the frame (every substep sees the same g).
  Before the first frame the rig was still in the pose first given (no kick on a posed first
  frame); ``rig_state`` holds the two frames' bones the next frame needs, and ``set_state`` takes
  them, so a frame is the same bits however it is reached.

Handles stay in rest space: an identity transform holds its vertices where the rig puts them (an
Attach group: zero displacement there); an Empty or a bone driving a handle maps into rest space by
the inverse of the skinning at the handle's centre. Without handles nothing holds the basis's rigid
motions in rest space: the mesh may drift off its bones. On a rig ``period`` and ``damping`` are
those of the lowest mode of the mesh as attached (the reduced rest Hessian plus the handles' term),
the wobble the artist sees; without a rig they stay those of the lowest flexible mode.

Cost on a rig: once, O(nonzero weights · r) to project each bone's force on the basis (an (r, 12b)
matrix); a frame, O(b) 3x3 solves and one (r, 12b) product, O(b r), whatever the number of
vertices, on top of the frame without a rig.
"""

import numpy as np

from .. import _native
from . import _arrays, _inputs, _options
from . import rig as _rig
from .solve import SOLVER_OPTIONS

#: Simulation's options, the native core's (cpp/solve/reduced_dynamics.h): {name: Option}.
SIMULATION_OPTIONS = _options.table(_native.SIMULATION_OPTIONS)


class Simulation(_inputs.InBasis):
    """Reduced dynamics of a baked basis driven by handles.

    ``basis``: from ``mdc.bake`` (kept alive). ``handles``: a list of vertex index arrays, one per
    controller, possibly empty (a free body); ``weights``: one per handle (default 1); ``energy``:
    as for ReducedSolver. ``period`` and ``damping`` hold exactly for the lowest flexible mode of
    small motions; see step() for ``memory_frames``. Starts at rest, at rest velocity, with every
    controller at the identity. ``rig``: None, or (n, b) skinning weights (dense or scipy sparse;
    ``rig.skin`` says what they must be): the simulation on a rig (the module's docstring), stepped
    with each frame's bones. Raises ValueError naming the argument that is wrong.
    """

    @_options.takes_options(SIMULATION_OPTIONS)
    def __init__(
        self,
        basis,
        handles,
        weights=None,
        energy=SOLVER_OPTIONS["energy"].default,
        rig=None,
        **options,
    ):
        basis = _inputs.basis(basis)
        handles = [] if _inputs.is_empty(handles) else _inputs.handles(handles)
        weights = np.zeros(0) if not handles else _inputs.weights(weights, len(handles))
        if not isinstance(energy, str):
            raise ValueError(f'energy: expected "shells" or "arap", got {energy!r}')
        if rig is not None:
            rig = _rig.skinning_weights(rig, basis.num_vertices).native
        self._native = _native.Simulation(basis._native, handles, weights, energy, rig, **options)
        self._basis = basis
        self.stats = None  #: the last step's: see step()

    @property
    def num_handles(self):
        return self._native.num_handles

    @property
    def num_bones(self):
        """The rig's bones (columns of ``rig``); 0 without a rig."""
        return self._native.num_bones

    def step(self, transforms, out=None, *, bones=None):
        """Advances one frame: the controllers reach ``transforms`` (one rigid 4x4 per handle; [] for
        a free body) at its end, moving there from the previous frame's (rotations by slerp, each
        handle's centre on a straight line). On a rig, ``bones``: (b, 4, 4), each bone's world
        skinning matrix at the frame's end (required there, refused without a rig), and
        ``transforms`` are in rest space. Returns the positions at the frame's end, as
        ``positions(out)``: in rest space on a rig (``skin`` them for the world's). ``self.stats`` then holds {"substeps", "iterations", "evaluations",
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
        self.advance(transforms, bones=bones)
        return self.positions(out)

    def advance(self, transforms, *, bones=None):
        """step() without the positions, for a frame simulated only to reach a later one (a jump
        forward): the fine mesh's map costs as much as reading U (40 MB at 100k vertices). Returns
        ``self.stats``."""
        self.stats = self._native.step(self._checked_transforms(transforms), self._bones(bones))
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
        coordinates of basis.vectors' columns: what a cache stores (with ``rig_state`` on a rig)."""
        return self._native.q, self._native.v

    @property
    def rig_state(self):
        """On a rig, (2, b, 4, 4): the bones at the frame before the state and at the state, what
        the next frame's acceleration needs (``set_state(..., bones=...)`` takes it back). None
        without a rig, or before the rig is first given (the next step then takes it as still in
        the pose it is given), or after ``set_state`` without bones."""
        current = self._native.rig_current
        if not current:
            return None
        return np.array([self._native.rig_previous, current])

    def positions_of(self, q, out=None):
        """x̄ + U q for a q of its own (e.g. a cached frame's), as ``positions(out)`` does for the
        simulation's; the simulation's state stays as it is."""
        out = _arrays.positions_out(out, self.num_vertices)
        self._native.positions_of(_arrays.values(q, "q", self.dimension), out.reshape(-1))
        return out

    def displacement_of(self, q, out=None):
        """U q alone, (n, 3) float32 as ``positions_of`` (exactly zero at q = 0): on a rig, the
        rest-space offset shown before the Armature modifier, written without reading x̄."""
        out = _arrays.positions_out(out, self.num_vertices)
        self._native.displacement_of(_arrays.values(q, "q", self.dimension), out.reshape(-1))
        return out

    def set_state(self, q, v, transforms=None, *, bones=None):
        """Puts the simulation at (q, v), e.g. a cached frame's, or a pose's ``ReducedSolver.q``
        with zero velocity. ``transforms``: the controllers' at that state (one 4x4 per handle), the
        start of the next step; None keeps the current ones. On a rig, ``bones``: a cached
        ``rig_state`` (2, b, 4, 4), or (b, 4, 4), the rig at the state and still in that pose
        before it; None: no history, the next step takes the rig as still in the pose it is given
        (as a fresh simulation's first frame), whatever was stepped before. BFGS's memory (step())
        is forgotten unless this is the simulation's own state, bit for bit (rig's included)."""
        r = self.dimension
        q = _arrays.values(q, "q", r)
        v = _arrays.values(v, "v", r)
        previous, current = [], []
        if bones is not None:
            B = _arrays.reals(bones, "bones")
            if B.ndim == 4 and B.shape[0] == 2:
                previous = _rig.bone_matrices(B[0], "bones[0]")
                current = _rig.bone_matrices(B[1], "bones[1]")
            else:
                current = _rig.bone_matrices(B)
        self._native.set_state(
            q,
            v,
            [] if transforms is None else self._checked_transforms(transforms),
            previous,
            current,
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
        period is ``period``. On a rig, the lowest mode of the mesh as attached (the rest Hessian
        plus the handles' term)."""
        return self._native.lowest_mode

    @property
    def mass_scale(self):
        """ρ: the reduced mass matrix is ρ I."""
        return self._native.mass_scale

    @property
    def rig_acceleration(self):
        """On a rig, the last frame's g (r,): the rig's inertial force per unit of the reduced
        mass, per second squared (zero without a rig)."""
        return self._native.rig_acceleration if self._native.on_rig else np.zeros(self.dimension)

    def _bones(self, bones):
        """The frame's bones for the core, which checks them (one per bone on a rig, none off it)."""
        return [] if bones is None else _rig.bone_matrices(bones)

    def _checked_transforms(self, transforms):
        if _inputs.is_empty(transforms):
            transforms = []
        return _inputs.transforms(transforms, self._native.num_handles)
