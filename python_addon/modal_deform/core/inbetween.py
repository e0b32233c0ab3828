"""Physics in-betweens: key a few poses of the handles, get the motion through them that needs the
least control force under Simulation's dynamics (spacetime constraints: Hildebrandt, Schulz, von
Tycowicz and Polthier 2012; Schulz et al. 2014), in the same basis, mass scale, damping and
midpoint rule as ``Simulation``.

How it is solved (cpp/solve/inbetween.h has the equations): the unknowns are the reduced states at
every substep from the first key to the last. Each substep is a free step of Simulation's implicit
midpoint rule; the control is the velocity impulse needed at each substep boundary (the midpoint
equation's control force there), and the solve minimises the sum of its squares in the mass metric,
with each keyed handle's rigid fit pulled to its keyed transform at its key by a penalty (on the
rigid part of the handle's miss only: the handle's own deformation stays the physics'), weighted to
outweigh the motion's terms there ten thousand-fold: keys are met well within posing's precision.
L-BFGS over all frames at once, from the keys' static poses interpolated linearly, its initial
inverse Hessian the inverse of a Gauss-Newton matrix of the dynamics linearised along the motion
(the energy's Hessian at the keys' static poses, interpolated in time), block-banded in time (two
r-by-r blocks either side of the diagonal) and factored once; the gradient is exact and a line
search keeps every step a descent. Cost, with N = frames × substeps between the first key and the
last and r = basis.dimension: O(N r³) once for the model, then per iteration O(N) ghost gradient
evaluations (each O(ghost vertices × r), the nodes' in parallel on the threads, the same bits
for any thread count) and O(N r²) for the banded solve; tens of iterations.

Simulation's energy correction (a rescaling of each substep's end velocity) is not smooth: the
in-betweens measure the control on the midpoint equation alone, so a free motion of Simulation is
reproduced exactly where that correction does nothing (small motions, whose energy is quadratic),
and closely otherwise.

Before the first key the mesh holds the static pose of that key (posing's minimum with the
handles keyed there at their transforms, the never-keyed at the identity, the others free), at
rest. A keyed handle acts only at its keys; a handle never keyed is a spring at the identity
throughout. After the last key the motion is Simulation's from the state reached there, each keyed
handle a spring at its last keyed transform: those frames are stepped in order once and cached, so
any frame, asked in any order, is the same bits.
"""

import numbers

import numpy as np

from .. import _native
from . import _arrays, _inputs, _options
from .solve import SOLVER_OPTIONS

#: Inbetween's options, the native core's (cpp/solve/inbetween.h): Simulation's and the solve's.
INBETWEEN_OPTIONS = _options.table(_native.INBETWEEN_OPTIONS)
#: The most keyed frames an Inbetween takes.
MAX_KEYS = _native.MAX_INBETWEEN_KEYS


class Inbetween(_inputs.InBasis):
    """The motion of a baked basis's mesh through keyed poses of its handles.

    ``basis``, ``handles``, ``weights``, ``energy``: as for Simulation (handles: one vertex index
    array per controller, at least one). ``keys``: a list of ``(frame, transforms)``, ``frame`` an
    int >= 0, ``transforms`` one entry per handle: a rigid 4x4 where that handle is keyed at that
    frame, or None where it is not (a key keys at least one handle); keys at distinct frames, in any
    order. Raises ValueError naming what is wrong.
    """

    @_options.takes_options(INBETWEEN_OPTIONS)
    def __init__(
        self, basis, handles, keys, weights=None, energy=SOLVER_OPTIONS["energy"].default, **options
    ):
        basis = _inputs.basis(basis)
        handles = _inputs.handles(handles)
        weights = _inputs.weights(weights, len(handles))
        if not isinstance(energy, str):
            raise ValueError(f'energy: expected "shells" or "arap", got {energy!r}')
        frames, transforms = _keys(keys, len(handles))
        self._native = _native.Inbetween(
            basis._native, handles, weights, frames, transforms, energy, **options
        )
        self._basis = basis
        self.stats = None  #: the last solve()'s

    @property
    def num_handles(self):
        return self._native.num_handles

    @property
    def first_frame(self):
        return self._native.first_frame

    @property
    def last_frame(self):
        return self._native.last_frame

    @property
    def mass_scale(self):
        """ρ, Simulation's: the reduced mass matrix is ρ I."""
        return self._native.mass_scale

    def solve(self):
        """Solves the whole motion and returns ``self.stats``: {"converged" (the last step met
        ``solve_tolerance``, or the objective is a millionth of the starting guess's and no step
        decreases it further), "stalled" (no step decreases it, and it is not that low),
        "iterations", "evaluations" (ghost gradients), "nodes" (substeps solved for), "control"
        and "initial_control" (half the sum of the squared control impulses, in h²/ρ units, at the
        end and for the starting guess), "ms"}. Solving again gives the same bits."""
        self.stats = self._native.solve()
        return self.stats

    def state(self, frame):
        """(q, v) at ``frame`` (an int >= 0): the reduced coordinates and their velocity per
        second. Solves first if solve() has not run."""
        q, v = self._native.state(_frame(frame))
        return q, v

    def positions(self, frame, out=None):
        """x̄ + U q at ``frame``: (n, 3) float32, mesh units, written into ``out`` if given (as
        Simulation.positions). Solves first if solve() has not run."""
        out = _arrays.positions_out(out, self.num_vertices)
        self._native.positions(_frame(frame), out.reshape(-1))
        return out


def _frame(frame, name="frame"):
    if isinstance(frame, (bool, np.bool_)) or not isinstance(frame, numbers.Integral):
        raise ValueError(f"{name}: expected an integer frame, got {frame!r}")
    frame = int(frame)
    if frame < 0 or frame > np.iinfo(np.int32).max:
        raise ValueError(f"{name}: expected a frame >= 0, got {frame}")
    return frame


def _keys(keys, num_handles):
    """The keys as the core takes them: frames, and per key one 4x4 or None per handle."""
    if keys is None:
        raise ValueError("keys: none given; in-betweens need at least one key")
    try:
        keys = list(keys)
    except TypeError:
        raise ValueError(
            f"keys: expected a list of (frame, transforms), got {type(keys).__name__}"
        ) from None
    frames, transforms = [], []
    for k, key in enumerate(keys):
        try:
            frame, per_handle = key
        except (TypeError, ValueError):
            raise ValueError(f"keys[{k}]: expected (frame, transforms)") from None
        frames.append(_frame(frame, f"keys[{k}] frame"))
        try:
            per_handle = list(per_handle)
        except TypeError:
            raise ValueError(
                f"keys[{k}]: expected one transform (or None) per handle, got "
                f"{type(per_handle).__name__}"
            ) from None
        if len(per_handle) != num_handles:
            raise ValueError(
                f"keys[{k}] (frame {frame}): expected {num_handles} transforms (one per handle, "
                f"None where not keyed), got {len(per_handle)}"
            )
        matrices = []
        for h, T in enumerate(per_handle):
            if T is None:
                matrices.append(None)
                continue
            T = _arrays.reals(T, f"keys[{k}] (frame {frame}), handle {h}")
            if T.shape != (4, 4):
                raise ValueError(
                    f"keys[{k}] (frame {frame}), handle {h}: expected a 4x4 matrix, got shape "
                    f"{T.shape}"
                )
            matrices.append(T)
        transforms.append(matrices)
    return frames, transforms
