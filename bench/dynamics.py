"""Secondary motion (issue 40): mdc.Simulation against the parameters set, and its cost per frame.

- bar: a closed bar (4 by 4 by 16 quads a side, 20 modes and 30 derivatives, 300-vertex ghost) as
  a free body released along its lowest flexible mode at 1% of it: the period and, undamped, the
  amplitude after 10 periods, at several frame rates and substeps; with damping ratios ζ the
  logarithmic decrement against 2πζ/√(1−ζ²). Energy (issue 50): the bar with 15 modes and 52
  derivatives released undamped at 0.5%, 5% and 10% of its length, period 12 frames, 2 substeps:
  the total energy over 10 periods, what the energy correction removed and added, the lowest
  mode's period and amplitude, against 32 substeps at a tight tolerance.
- cost: the 23k and 100k dragons (default bake), the tail held and the head on a controller that
  turns 60° about the vertical in 12 frames and stops (the demo's motion), then 48 frames of
  settling: the core's step (stats "ms": the integrator) and the map of q to the mesh
  (Simulation.positions), per frame.
- stress: the 23k dragon, 1000 frames of fast random controllers (turns up to 150°, jumps of about a
  third of its length), then the controller still in a moderate pose: non-finite frames, energy
  increases once it is still, the distance to ReducedSolver's pose at the end.
- proxy: the 100k dragon midpoint-subdivided twice (1.6M vertices) baked on a proxy: the cost of
  the demo's motion there, and the stress run on it.
- tolerance: BFGS's stopping tolerance against the frames of a tight solve (the 5k dragon, the
  demo's motion): why SIMULATION_OPTIONS["tolerance"] is what it is.
"""

import time

import numpy as np
from common import median_ms
from shapes import rigid_transform as rigid
from support import SHARED_MESHES as MESHES
from support.dynamics import AMPLITUDE, damped_oscillation, free_motion, released, swing
from support.subdivision import midpoint_subdivide

import modal_deform.core as mdc

# The handles' pull the dynamics records were made with.
PULL = 100.0

BAR = dict(modes=20, derivatives=30, ghost=300)
# The bar of issue 50's energy measurement.
ENERGY_BAR = dict(modes=15, derivatives=52)


def bar(quick):
    V, F = mdc.testing.bar(4, 4, 16, 1, 1, 4)
    basis = mdc.bake(V, F, **BAR)
    undamped = []
    for period, fps, substeps in [
        (12.0, 24.0, 2),
        (12.0, 24.0, 1),
        (24.0, 24.0, 1),
        (6.0, 60.0, 3),
        (4.0, 24.0, 2),
    ]:
        trace = released(
            basis, int(10 * period) + 1, period=period, damping=0.0, fps=fps, substeps=substeps
        )
        measured, _ = damped_oscillation(trace)
        undamped.append(
            {
                "period": period,
                "fps": fps,
                "substeps": substeps,
                "measured_period": measured,
                "amplitude_after_10_periods": float(
                    np.abs(trace[-int(np.ceil(period)) :]).max() / AMPLITUDE
                ),
            }
        )
    damped = []
    for zeta in (0.02, 0.05, 0.1, 0.2, 0.5):
        trace = released(basis, 48, damping=zeta)
        measured, decrement = damped_oscillation(trace)
        damped.append(
            {
                "damping": zeta,
                "measured_period": measured,
                "decrement": decrement,
                "expected_decrement": 2 * np.pi * zeta / np.sqrt(1 - zeta**2),
            }
        )
    return {
        "vertices": len(V),
        "dimension": basis.dimension,
        "undamped": undamped,
        "damped": damped,
        "energy": energy(V, F),
    }


def energy(V, F):
    """Large undamped swings, where the midpoint rule alone drifts: the energy over 10 periods."""
    basis = mdc.bake(V, F, **ENERGY_BAR)
    period, frames = 12.0, 121
    rows = []
    for fraction in (0.005, 0.05, 0.1):
        amplitude = swing(basis, fraction)
        runs = {}
        for name, options in (
            ("substeps_2", {}),
            ("substeps_32", dict(substeps=32, tolerance=1e-12, max_iterations=200)),
        ):
            trace, energies, removed, added = free_motion(
                basis, frames, amplitude, period=period, damping=0.0, **options
            )
            runs[name] = {
                "energy_end": float(energies[-1] / energies[0]),
                "energy_min": float(energies.min() / energies[0]),
                "energy_max": float(energies.max() / energies[0]),
                "energy_removed": removed / energies[0],
                "energy_added": added / energies[0],
                "measured_period": damped_oscillation(trace)[0],
                "amplitude_after_10_periods": float(
                    np.abs(trace[-int(period) :]).max() / amplitude
                ),
            }
        rows.append({"fraction_of_length": fraction, **runs})
    return {"bake": ENERGY_BAR, "dimension": basis.dimension, "period": period, "rows": rows}


def tail_and_head(V):
    """The dragon's handles: the 10% of its length at each end (tail held, head on a controller)."""
    x = (V[:, 0] - V[:, 0].min()) / np.ptp(V[:, 0])
    return [np.flatnonzero(x > 0.9), np.flatnonzero(x < 0.1)]


def demo_motion(V, handles, frames):
    """The head turns 60° about the vertical in 12 frames, then stays."""
    centre = V[handles[1]].mean(axis=0)
    return [
        [np.eye(4), rigid([0, 0, 1], np.radians(60) * min(f, 12) / 12, centre)]
        for f in range(1, frames + 1)
    ]


def per_frame_cost(basis, V, handles, moves, **parameters):
    """Per frame: the core's step, the map after it, BFGS's iterations and evaluations, the step's
    time per evaluation; and the map run back to back (its threads awake), which a busy machine
    otherwise delays by waking them after each serial step."""
    sim = mdc.Simulation(basis, handles, **parameters, pull=PULL)
    out = np.empty((len(V), 3), np.float32)
    step_ms, map_ms, iterations, evaluations = [], [], [], []
    for T in moves:
        sim.step(T)
        step_ms.append(sim.stats["ms"])
        iterations.append(sim.stats["iterations"])
        evaluations.append(sim.stats["evaluations"])
        start = time.perf_counter()
        sim.positions(out)
        map_ms.append(1e3 * (time.perf_counter() - start))
    summary = lambda xs: {
        "median": float(np.median(xs)),
        "p95": float(np.percentile(xs, 95)),
        "max": float(max(xs)),
    }
    return {
        "frames": len(moves),
        "step_ms": summary(step_ms),
        "map_ms": summary(map_ms),
        "map_back_to_back_ms": median_ms(lambda: sim.positions(out), 20),
        "iterations": summary(iterations),
        "evaluations": summary(evaluations),
        "ms_per_evaluation": summary([t / e for t, e in zip(step_ms, evaluations) if e]),
        "step_ms_per_frame": step_ms,
        "iterations_per_frame": iterations,
    }


def cost(quick):
    runs = {}
    for name in ["dragon_vrip_res4"] if quick else ["dragon_vrip_res3", "dragon_vrip_res2"]:
        V, F = mdc.read_mesh(MESHES / f"{name}.ply.gz")
        start = time.perf_counter()
        basis = mdc.bake(V, F)
        bake_s = time.perf_counter() - start
        handles = tail_and_head(V)
        runs[name] = {
            "vertices": len(V),
            "dimension": basis.dimension,
            "ghost": len(basis.ghost_vertices),
            "bake_s": bake_s,
            **per_frame_cost(basis, V, handles, demo_motion(V, handles, 60)),
        }
        print(
            f"   {name}: step {runs[name]['step_ms']['median']:.2f} ms, map {runs[name]['map_ms']['median']:.2f} ms",
            flush=True,
        )
    return runs


def stress_run(basis, V, handles, frames, still):
    """`frames` frames of fast random controllers (turns up to 150°, jumps of about a third of the
    mesh's length) on the head, the tail held, then `still` frames with the controller still in a
    moderate pose: non-finite frames, energy increases once it is still, the distance to
    ReducedSolver's pose at the end."""
    diagonal = np.linalg.norm(np.ptp(V, axis=0))
    length = np.ptp(V[:, 0])
    damping = 0.3
    sim = mdc.Simulation(basis, handles, damping=damping, pull=PULL)
    rng = np.random.default_rng(1)
    centre = V[handles[1]].mean(axis=0)
    non_finite, farthest, step_ms, euler, evaluations = 0, 0.0, [], 0, []
    removed = added = 0.0
    start = time.perf_counter()
    for _ in range(frames):
        T = rigid(
            rng.normal(size=3),
            rng.uniform(0, np.radians(150)),
            centre,
            rng.normal(scale=length / 3, size=3),
        )
        X = sim.step([np.eye(4), T])
        non_finite += int(not (np.isfinite(X).all() and np.isfinite(sim.energy())))
        farthest = max(farthest, float(np.abs(X - V.mean(axis=0)).max() / diagonal))
        step_ms.append(sim.stats["ms"])
        evaluations.append(sim.stats["evaluations"])
        euler += sim.stats["implicit_euler"]
        removed += sim.stats["energy_removed"]
        added += sim.stats["energy_added"]
    moving_s = time.perf_counter() - start
    T = rigid([0, 0, 1], np.radians(60), centre)
    sim.step([np.eye(4), T])
    energies = [sim.energy()]
    for _ in range(still):
        X = sim.step([np.eye(4), T])
        energies.append(sim.energy())
    increases = np.diff(energies)
    solver = mdc.ReducedSolver(basis, handles, pull=PULL)
    solver.set_transforms([np.eye(4), T])
    solved = solver.solve(max_iterations=1000, tolerance=1e-12)
    return {
        "vertices": len(V),
        "frames": frames,
        "still_frames": still,
        "damping": damping,
        "non_finite_frames": non_finite,
        "farthest_vertex_diagonals": farthest,
        "moving_s": moving_s,
        "step_ms_median": float(np.median(step_ms)),
        "step_ms_max": float(max(step_ms)),
        "evaluations_median": float(np.median(evaluations)),
        "evaluations_max": int(max(evaluations)),
        "implicit_euler_substeps": euler,
        "energy_removed": removed,
        "energy_added": added,
        "energy_at_stop": energies[0],
        "energy_at_end": energies[-1],
        "largest_energy_increase_still": float(increases.max()),
        "pose_converged": solved["converged"],
        "settled_distance_diagonals": float(np.abs(X - solver.positions()).max() / diagonal),
    }


def stress(quick):
    name = "dragon_vrip_res4" if quick else "dragon_vrip_res3"
    V, F = mdc.read_mesh(MESHES / f"{name}.ply.gz")
    basis = mdc.bake(V, F)
    return {
        "mesh": name,
        **stress_run(basis, V, tail_and_head(V), *((100, 150) if quick else (1000, 300))),
    }


def proxy(quick):
    """The demo's motion and the stress run on the 1.6M proxy bake."""
    V, F = mdc.read_mesh(MESHES / f"{'dragon_vrip_res4' if quick else 'dragon_vrip_res2'}.ply.gz")
    for _ in range(2):
        V, F = midpoint_subdivide(V, F)
    sizes = {"proxy": 5000, "proxy_above": 10000} if quick else {}
    start = time.perf_counter()
    basis = mdc.bake(V, F, **sizes)
    bake_s = time.perf_counter() - start
    handles = tail_and_head(V)
    return {
        "vertices": len(V),
        "proxy_vertices": basis.num_basis_vertices,
        "dimension": basis.dimension,
        "bake_s": bake_s,
        **per_frame_cost(basis, V, handles, demo_motion(V, handles, 30)),
        "stress": stress_run(basis, V, handles, *((100, 150) if quick else (1000, 300))),
    }


def tolerance(quick):
    V, F = mdc.read_mesh(MESHES / "dragon_vrip_res4.ply.gz")
    basis = mdc.bake(V, F)
    handles = tail_and_head(V)
    diagonal = np.linalg.norm(np.ptp(V, axis=0))
    moves = demo_motion(V, handles, 72)

    def frames(tol):
        sim = mdc.Simulation(basis, handles, tolerance=tol, max_iterations=200, pull=PULL)
        X, iterations = [], []
        for T in moves:
            X.append(sim.step(T).astype(np.float64))
            iterations.append(sim.stats["iterations"])
        return X, iterations

    reference, _ = frames(1e-14)
    rows = []
    for tol in (1e-12, 1e-10, 1e-9, 1e-8, 1e-7, 1e-6):
        X, iterations = frames(tol)
        distance = max(np.abs(x - r).max() for x, r in zip(X, reference)) / diagonal
        rows.append(
            {
                "tolerance": tol,
                "iterations_median": float(np.median(iterations)),
                "iterations_moving": float(np.mean(iterations[:12])),
                "iterations_still": float(np.mean(iterations[-24:])),
                "largest_distance_diagonals": float(distance),
            }
        )
    return {
        "mesh": "dragon_vrip_res4",
        "vertices": len(V),
        "frames": len(moves),
        "reference_tolerance": 1e-14,
        "rows": rows,
    }


def run(quick=False):
    figures = {}
    for name, part in (
        ("bar", bar),
        ("tolerance", tolerance),
        ("cost", cost),
        ("stress", stress),
        ("proxy", proxy),
    ):
        start = time.perf_counter()
        figures[name] = part(quick)
        print(f"   {name}: {time.perf_counter() - start:.0f} s", flush=True)
    parameters = {
        "defaults": {name: o.default for name, o in mdc.SIMULATION_OPTIONS.items()},
        "pull": PULL,
        "bar_bake": BAR,
        "amplitude": AMPLITUDE,
    }
    return parameters, figures
