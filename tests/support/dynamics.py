"""The free-body measurement of secondary motion, shared by tests/python/test_dynamics.py and
bench/dynamics.py: a body released along its lowest flexible mode, and the period and decrement of
the trace it leaves."""

import numpy as np

import modal_deform.core as mdc

AMPLITUDE = 0.01


def damped_oscillation(trace):
    """(period in frames, logarithmic decrement a period) of p_k = A r^k cos(θk + φ), from the
    recurrence p_{k+1} = 2r cos θ p_k − r² p_{k−1} fitted by least squares."""
    (a, b), *_ = np.linalg.lstsq(np.column_stack([trace[1:-1], trace[:-2]]), trace[2:], rcond=None)
    r = np.sqrt(-b)
    theta = np.arccos(a / (2 * r))
    return float(2 * np.pi / theta), float(-np.log(r) * 2 * np.pi / theta)


def swing(basis, fraction):
    """The amplitude along the lowest flexible mode that moves the farthest vertex by `fraction`
    of the body's length (its largest extent)."""
    sim = mdc.Simulation(basis, [])
    length = np.ptp(basis.rest, axis=0).max()
    # The map is linear in q: measured at a displacement of about the length, beyond float32's
    # rounding.
    probe = length / np.abs(basis.vectors @ sim.lowest_mode).max()
    moved = np.linalg.norm(sim.positions_of(probe * sim.lowest_mode) - basis.rest, axis=1).max()
    return fraction * length * probe / moved


def free_motion(basis, frames, amplitude=AMPLITUDE, **parameters):
    """A free body released at rest from `amplitude` along its lowest flexible mode, `frames`
    frames: the mode's coordinate at the end of each frame, the total energy at the start and at the
    end of each frame (frames + 1), and the steps' energy_removed and energy_added summed."""
    sim = mdc.Simulation(basis, [], **parameters)
    mode = sim.lowest_mode
    sim.set_state(amplitude * mode, np.zeros_like(mode))
    trace, energies, removed, added = [], [sim.energy()], 0.0, 0.0
    for _ in range(frames):
        sim.step([])
        trace.append(sim.state[0] @ mode)
        energies.append(sim.energy())
        removed += sim.stats["energy_removed"]
        added += sim.stats["energy_added"]
    return np.array(trace), np.array(energies), removed, added


def released(basis, frames, **parameters):
    """A free body released at rest from AMPLITUDE along its lowest flexible mode: the mode's
    coordinate at the end of each frame."""
    return free_motion(basis, frames, **parameters)[0]
