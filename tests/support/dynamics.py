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


def released(basis, frames, **parameters):
    """A free body released at rest from AMPLITUDE along its lowest flexible mode: the mode's
    coordinate at the end of each frame."""
    sim = mdc.Simulation(basis, [], **parameters)
    mode = sim.lowest_mode
    sim.set_state(AMPLITUDE * mode, np.zeros_like(mode))
    trace = []
    for _ in range(frames):
        sim.step([])
        trace.append(sim.state[0] @ mode)
    return np.array(trace)
