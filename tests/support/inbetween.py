"""Keys taken from a motion, shared by tests/python/test_inbetween.py and bench/inbetween.py: the
rigid fit of each handle's vertices at chosen frames of a free motion that Simulation produces from
rest in a static pose."""

import numpy as np

import modal_deform.core as mdc


def free_motion_keys(basis, handles, start, frames, key_frames, **parameters):
    """A free body released at rest from posing's minimum with `handles` at `start` (one 4x4 each),
    stepped `frames` frames by Simulation: its positions at frames 0 … frames, and the keys at
    `key_frames`, every handle keyed there at the rigid fit of its vertices."""
    pose = mdc.ReducedSolver(basis, handles, pull=parameters.get("pull", 1000.0))
    pose.set_transforms(start)
    pose.solve(max_iterations=1000, tolerance=1e-8)
    sim = mdc.Simulation(basis, [], **{k: v for k, v in parameters.items() if k != "pull"})
    sim.set_state(pose.q, np.zeros(basis.dimension))
    positions = [sim.positions().copy()]
    for _ in range(frames):
        positions.append(sim.step([]).copy())
    rest = basis.rest
    keys = [(f, [mdc.rigid_fit(rest[h], positions[f][h]) for h in handles]) for f in key_frames]
    return np.array(positions), keys
