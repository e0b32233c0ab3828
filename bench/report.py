"""docs/benchmarks.md and its plots (docs/figures/) from the JSON in bench/results/.

    PYTHONPATH=python_addon /usr/bin/python3 bench/report.py

Everything in the report is read from the results files; missing experiments are listed as such.
"""

import json
import pathlib
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import bake_limit  # noqa: E402
import common  # noqa: E402
import refine  # noqa: E402
import shape_space  # noqa: E402

DOCS = common.ROOT / "docs"
FIGURES = DOCS / "figures"

#: The targets of the project's other issues that no experiment defines, in ms (the bake's are
#: bake_limit.TARGETS, a frame's common.FRAME_TARGETS_MS).
TARGETS = {
    "iteration_67": 0.25,
    "iteration_130": 0.5,
    "map_130": 8.0,
    "tick_67": 12.0,
    "tick_130": 16.0,
}


def load(name):
    path = common.RESULTS / f"{name}.json"
    return json.loads(path.read_text()) if path.exists() else None


def table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


SHARED = " (more than the run's own threads: the machine was shared with other builds and tests)"


def provenance(result):
    m = result["machine"]
    return (
        f"*Made by `{result['command']}` on {result['date']} in {result['seconds']:.0f} s; commit "
        f"`{result['commit'][:12]}`; {m['cpu']}, {m['cores']} cores, {m['memory_gb']} GB; load average at the "
        f"end {m['load_average'][0]:.1f}{SHARED if m['load_average'][0] > m['cores'] + 0.5 else ''}.*"
    )


def save_figure(fig, name):
    """docs/figures/<name>.png, laid out tight, and the figure closed."""
    FIGURES.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(FIGURES / f"{name}.png", dpi=110)
    plt.close(fig)


def measured_apart(runs):
    """The paragraph naming the runs measured apart from the rest and merged into the JSON, each
    with its own provenance (none: no paragraph)."""
    apart = [
        f"{run['blender']}, {run['vertices']:,} vertices: {run['measured']['date']}, commit "
        f"`{run['measured']['commit'][:12]}`, load average at the end {run['measured']['load_average'][0]:.1f}"
        for run in runs
        if "measured" in run
    ]
    return ["", "Measured apart and merged: " + "; ".join(apart) + "."] if apart else []


def section_table1(result):
    rows = result["figures"]["rows"]
    paper = result["parameters"]["paper"]
    floppy = {}  # (model, its zero modes): its dimensions with them
    for r in rows:
        if r["floppy"]:
            floppy.setdefault((r["model"], r["floppy"]), set()).add(r["dimension"])
    zero_modes = "; ".join(
        f"{model}: {count}, so {' and '.join(map(str, sorted(dims)))}"
        for (model, count), dims in floppy.items()
    )
    out = [
        "## Table 1: timings (paper Table 1)",
        "",
        "Per model, basis and ghost: ms per BFGS iteration (mean over a 60-frame pose of up to 10 iterations a "
        "frame, `solve()` alone), ms to map q to the fine mesh (`positions()` into a float32 buffer, median of 20), "
        "ms for a full update (new transforms, 10 iterations, map; median of 20) and the bake in seconds. "
        "Each model is baked once per dimension with a 1k ghost; other ghost sizes reuse that basis with a ghost "
        "rebuilt by `mdc.ghost_mesh` + `mdc.restrict_to_ghost` (the bake's own steps), so the bake time "
        "is that of the 1k run. Dimensions: 67 = 20 modes (the 6 rigid motions included) + 47 derivatives, "
        "130 = 25 + 105 (14 non-rigid modes have only 105 pairs); a floppy mesh's zero modes come on top"
        + (f" ({zero_modes})." if zero_modes else "."),
        "",
    ]
    header = [
        "model",
        "vertices",
        "dims",
        "ghost",
        "ms / iteration",
        "iterations / frame",
        "ms map",
        "ms update (10 it.)",
        "bake s",
    ]
    out.append(
        table(
            header,
            [
                [
                    r["model"],
                    r["vertices"],
                    r["dimension"],
                    r["ghost"],
                    f"{r['ms_per_iteration']:.3f}",
                    f"{r['iterations_per_frame']:.1f}",
                    f"{r['ms_map']:.2f}",
                    f"{r['ms_update']:.2f}",
                    f"{r['bake_s']:.1f}",
                ]
                for r in rows
            ],
        )
    )
    out += ["", "Bake by stage (seconds; one bake per model and dimension):", ""]
    stages = sorted({s for r in rows for s in r["bake_stages_s"]})
    baked = list({(r["model"], r["dimension"]): r for r in rows}.values())
    out.append(
        table(
            ["model", "dims"] + stages + ["total"],
            [
                [r["model"], r["dimension"]]
                + [f"{r['bake_stages_s'].get(s, 0):.2f}" for s in stages]
                + [f"{r['bake_s']:.1f}"]
                for r in baked
            ],
        )
    )
    ours = [r for r in rows if r["model"] == paper["model"] and r["ghost_target"] == paper["ghost"]]
    if ours:
        r = min(ours, key=lambda r: r["dimension"])
        out += [
            "",
            f"Against the paper (its dragon: {paper['vertices']} vertices, {paper['dimension']} dimensions, "
            f"{paper['ghost']} ghost, a 2.66 GHz laptop of 2010; ours: dragon_vrip_res2, {r['vertices']} vertices, "
            f"{r['dimension']} dimensions, {r['ghost']} ghost). Speed-up = paper / ours.",
            "",
        ]
        pairs = [
            ("ms per BFGS iteration", "ms_per_iteration"),
            ("ms to map", "ms_map"),
            ("ms for a 10-iteration update", "ms_update"),
            ("bake (preprocess), s", "bake_s"),
        ]
        out.append(
            table(
                ["", "paper", "ours", "speed-up"],
                [
                    [label, paper[key], f"{r[key]:.3g}", f"{paper[key] / r[key]:.1f}x"]
                    for label, key in pairs
                ],
            )
        )
        ghost = min(
            g for g in result["parameters"]["ghosts"] if g > paper["ghost"]
        )  # the next size up
        ratio = ghost / paper["ghost"]
        growth = [
            r2["ms_per_iteration"] / r1["ms_per_iteration"]
            for r1 in ours
            for r2 in rows
            if r2["model"] == r1["model"]
            and r2["dimension"] == r1["dimension"]
            and r2["ghost_target"] == ghost
        ]
        going = (
            f"From a {paper['ghost'] / 1000:g}k to a {ghost / 1000:g}k ghost the time per iteration on "
            f"{paper['model']}"
        )
        unexplained = 1.6 * ratio  # a growth above this is more than the ghost's size explains
        if growth and max(growth) > unexplained:
            out += [
                "",
                f"{going} grows {min(growth):.1f}–{max(growth):.1f}x, more than the {ratio:g}x the ghost's "
                "size explains. It coincides with the shells energy going parallel (OpenMP from "
                "`DiscreteShells::kParallelElements` terms, which a ghost of about this size reaches): on an "
                "oversubscribed machine threads that wait for each other lose their cores.",
            ]
        elif growth:
            out += [
                "",
                f"{going} grows {min(growth):.1f}–{max(growth):.1f}x, about the ghost's growth in size "
                f"({ratio:g}x).",
            ]
        out += ["", targets_table1(rows, paper["model"])]
    out += ["", provenance(result)]
    return "\n".join(out)


def table1_zero_modes_note(result):
    """The 'not here' line on the 100k dragon's zero modes, when the Table 1 record had any."""
    rows = [
        r
        for r in (result or {}).get("figures", {}).get("rows", [])
        if r["model"] == "dragon_res2" and r["floppy"]
    ]
    if not rows:
        return []
    dims = sorted({r["dimension"] for r in rows})
    return [
        f"- dragon_vrip_res2 had {rows[0]['floppy']} floppy zero modes in this record, which the bake kept on "
        f"top of the modes asked for: its rows have "
        f"{' and '.join(str(d) for d in dims)} dimensions where the paper has "
        f"{' and '.join(str(d - rows[0]['floppy']) for d in dims)}."
    ]


def targets_table1(rows, model):
    def pick(dims_small, ghost=1000):
        rs = [r for r in rows if r["model"] == model and r["ghost_target"] == ghost]
        return sorted(rs, key=lambda r: r["dimension"])[0 if dims_small else -1] if rs else None

    small, large = pick(True), pick(False)
    if not small:
        return ""
    checks = [
        ("bake at 67 dims", small["bake_s"], bake_limit.TARGETS["seconds_67"], "s"),
        ("BFGS iteration at 67 dims", small["ms_per_iteration"], TARGETS["iteration_67"], "ms"),
        ("BFGS iteration at 130 dims", large["ms_per_iteration"], TARGETS["iteration_130"], "ms"),
        ("positions at 130 dims", large["ms_map"], TARGETS["map_130"], "ms"),
    ]
    lines = [f"Targets of the other issues on {model} (1k ghost):", ""]
    lines += [
        f"- {label} ≤ {target:g} {unit}: **{value:.3g} {unit}** — {'met' if value <= target else 'NOT met'}"
        for label, value, target, unit in checks
    ]
    return "\n".join(lines)


def section_accuracy(result):
    parameters, rows = result["parameters"], result["figures"]["rows"]
    sizes = [tuple(size) for size in parameters["sizes"]]
    bases, goals = parameters["bases"], parameters["goals"]
    used = [r for r in rows if r["reference_converged"]]

    def select(name, size, kind, pose=None):
        return [
            r
            for r in used
            if r["shape"] == name
            and (r["modes"], r["derivatives"]) == size
            and r["basis"] == kind
            and pose in (None, r["pose"])
        ]

    out = [
        "## Accuracy against the full solve (paper Figs. 5 and 12)",
        "",
        f"Reduced poses converged (tolerance {parameters['tolerance']:g}) against `mdc.solve_full` (Newton on the "
        f"fine mesh, same objective, stiffness {parameters['stiffness']:g}) at the paper's (modes, derivatives), "
        "its modes counting the 6 rigid motions, for three bases: **paper pairs** (`mdc.bake(V, F, modes, "
        "derivatives)`: derivatives of the pairs of all modes but the translations, the linearised rotations "
        "included; (15, 52) is the paper's 67-dimensional basis), **flexible pairs** (the rule before: pairs of "
        "flexible modes only, `modes + 6` modes so as many flexible ones, `rotation_pairs=False`; 6 dimensions "
        "more) and **linear modes** alone (the paper's dimension). The ghost is the mesh itself, so the error is "
        "the basis's. RMS: vertex RMS distance over the bounding-box diagonal; gap: the objective gap "
        "(f(reduced) − f(full)) / f(full) of the posing objective (shells energy plus handle term), the paper's "
        "measure. Shapes (bench/shapes.py): "
        + "; ".join(
            f"{name} ({parameters['vertices'][name]} vertices): "
            + ", ".join(d for _, d in parameters["poses"][name])
            for name in parameters["shapes"]
        )
        + ".",
        "",
    ]
    missed = [
        f"{r['shape']} {r['pose']}" for r in result["figures"]["references"] if not r["converged"]
    ]
    out += [
        (
            "References that did not converge, left out of every figure below: "
            + ", ".join(missed)
            + "."
            if missed
            else "Every reference converged."
        ),
        "",
    ]

    body = []
    for name in parameters["shapes"]:
        for size in sizes:
            cells = []
            for kind in bases:
                rs = select(name, size, kind)
                cells += [
                    rs[0]["dimension"],
                    f"{100 * np.mean([r['rms_error'] for r in rs]):.2f}%",
                    f"{np.mean([r['objective_gap'] for r in rs]):.3f}",
                ]
            body.append([name, f"{size}"] + cells)
    header = ["shape", "(modes, derivatives)"] + [
        f"{h}, {kind}" for kind in bases for h in ("dims", "RMS", "gap")
    ]
    out += ["Means over each shape's poses:", "", table(header, body), ""]

    for size in sizes[2:4]:
        body = []
        for name in parameters["shapes"]:
            for pose, _ in parameters["poses"][name]:
                cells = []
                for kind in bases:
                    rs = select(name, size, kind, pose)
                    cells += (
                        [f"{100 * rs[0]['rms_error']:.2f}%, {rs[0]['objective_gap']:.3f}"]
                        if rs
                        else ["—"]
                    )
                body.append([name, pose] + cells)
        out += [
            f"Per pose at {size}, RMS and gap:",
            "",
            table(["shape", "pose"] + list(bases), body),
            "",
        ]

    checks = [
        ("gap", (15, 52), "objective_gap", goals["gap_67"], "{:.3f}"),
        ("gap", (20, 110), "objective_gap", goals["gap_130"], "{:.3f}"),
        ("RMS", (20, 110), "rms_error", goals["rms_130"], "{:.2%}"),
    ]
    out += ["Against the absolute goals (paper pairs, per pose):", ""]
    for label, size, key, goal, fmt in checks:
        rs = [
            r
            for r in used
            if (r["modes"], r["derivatives"]) == size and r["basis"] == "paper pairs"
        ]
        misses = [f"{r['shape']} {r['pose']} " + fmt.format(r[key]) for r in rs if r[key] > goal]
        out.append(
            f"- {label} ≤ {fmt.format(goal)} at {size}: met on {len(rs) - len(misses)} of {len(rs)} poses"
            + (f"; missed: {', '.join(misses)}." if misses else ".")
        )
    wins = {
        other: [
            f"{r['shape']} {r['pose']} {(r['modes'], r['derivatives'])}"
            for r in used
            if r["basis"] == "paper pairs"
            for o in select(r["shape"], (r["modes"], r["derivatives"]), other, r["pose"])
            if o["objective_gap"] < r["objective_gap"]
        ]
        for other in bases[1:]
    }
    out += ["", "Where another basis reaches a lower objective than the paper pairs:", ""]
    out += [
        f"- {other}: {len(w)} of {len(used) // len(bases)} cases"
        + (f" ({', '.join(w)})." if w else ".")
        for other, w in wins.items()
    ]

    out += section_accuracy_scans(parameters["scans"], result["figures"])

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for name, colour in zip(parameters["shapes"], ("C0", "C1", "C2")):
        for kind, style in zip(bases, ("-o", ":^", "--s")):
            dims = [select(name, size, kind)[0]["dimension"] for size in sizes]
            axes[0].semilogy(
                dims,
                [np.mean([r["rms_error"] for r in select(name, size, kind)]) for size in sizes],
                style,
                color=colour,
                label=f"{name}, {kind}",
            )
            axes[1].semilogy(
                dims,
                [
                    max(np.mean([r["objective_gap"] for r in select(name, size, kind)]), 1e-6)
                    for size in sizes
                ],
                style,
                color=colour,
            )
    axes[0].set(
        xlabel="basis dimension", ylabel="vertex RMS error / bbox diagonal", title="position error"
    )
    axes[1].set(
        xlabel="basis dimension", ylabel="(f_reduced − f_full) / f_full", title="objective gap"
    )
    axes[0].legend(fontsize=7)
    save_figure(fig, "accuracy")
    out += [
        "",
        accuracy_reading(parameters, used, result["figures"]),
        "",
        "![accuracy](figures/accuracy.png)",
        "",
        "Plot: `bench/report.py` from bench/results/accuracy.json (solid: paper pairs, dotted: flexible pairs, "
        "dashed: linear modes; means over the poses).",
        "",
        provenance(result),
    ]
    return "\n".join(out)


def section_accuracy_scans(scans, figures):
    """The accuracy suite's real scans: each pose against Refine's minimum, per basis."""
    out = [
        "",
        f"A real scan, at the paper's size {tuple(scans['size'])}: "
        + "; ".join(
            f"{name} ({scans['vertices'][name]} vertices): "
            + ", ".join(d for _, d in scans["poses"][name])
            for name in scans["poses"]
        )
        + ". Its reference is Refine's: `solve_full` started at the paper basis's "
        "reduced pose.",
        "",
    ]
    missed = [f"{r['shape']} {r['pose']}" for r in figures["scan_references"] if not r["converged"]]
    body = []
    for ref in figures["scan_references"]:
        rs = {
            r["basis"]: r
            for r in figures["scan_rows"]
            if (r["shape"], r["pose"]) == (ref["shape"], ref["pose"])
        }
        cells = [
            f"{rs[k]['dimension']}: {100 * rs[k]['rms_error']:.2f}%, {rs[k]['objective_gap']:.3f}"
            if ref["converged"]
            else "reference did not converge"
            for k in scans["bases"]
        ]
        body.append(
            [ref["shape"], ref["pose"], f"{ref['iterations']} it, {ref['seconds']:.0f} s"] + cells
        )
    out += [
        table(
            ["scan", "pose", "reference (Newton)"]
            + [f"{k}: dims, RMS, gap" for k in scans["bases"]],
            body,
        )
    ]
    if missed:
        out += ["", "References that did not converge, left out: " + ", ".join(missed) + "."]
    return out


def accuracy_reading(parameters, used, figures):
    """What the accuracy figures say, written from the record: the basis with the lowest mean
    objective gap shape by shape, the paper pairs against linear modes at the paper's sizes, and the
    real scan's bases against Refine's minimum. `used`: the rows whose reference converged."""
    sizes, bases = [tuple(size) for size in parameters["sizes"]], parameters["bases"]

    def mean_gap(name, size, kind):
        gaps = [
            r["objective_gap"]
            for r in used
            if r["shape"] == name and (r["modes"], r["derivatives"]) == size and r["basis"] == kind
        ]
        return np.mean(gaps) if gaps else None

    lowest = []
    for name in parameters["shapes"]:
        runs = []  # [basis, first size, last size] over consecutive sizes with the same lowest basis
        for size in sizes:
            gaps = {kind: mean_gap(name, size, kind) for kind in bases}
            best = min(
                (kind for kind in bases if gaps[kind] is not None), key=gaps.get, default=None
            )
            if runs and runs[-1][0] == best:
                runs[-1][2] = size
            else:
                runs.append([best, size, size])
        lowest.append(
            f"{name}: "
            + ", ".join(
                f"{kind} at {first}" if first == last else f"{kind} from {first} to {last}"
                for kind, first, last in runs
            )
        )
    out = [
        "What the figures say:",
        "",
        "- Lowest mean objective gap, size by size: " + "; ".join(lowest) + ".",
    ]
    against, linear_lower = [], False
    for size in sizes[2:4]:
        pairs = [
            (name, mean_gap(name, size, "paper pairs"), mean_gap(name, size, "linear modes"))
            for name in parameters["shapes"]
        ]
        pairs = [
            (name, ours, linear)
            for name, ours, linear in pairs
            if ours is not None and linear is not None
        ]
        linear_lower = linear_lower or any(linear < ours for _, ours, linear in pairs)
        against.append(
            f"at {size} "
            + ", ".join(f"{name} {ours:.3g} against {linear:.3g}" for name, ours, linear in pairs)
        )
    out.append(
        "- Mean gap of the paper pairs against linear modes alone of the same dimension: "
        + "; ".join(against)
        + "."
        + (
            " Where linear modes are lower, the pose has no large rotations for the derivatives' "
            "second-order terms to correct and spatial resolution is what counts "
            "(tests/cpp/test_posing_accuracy.cpp, BumpyPlaneLiftedInTheMiddle)."
            if linear_lower
            else ""
        )
    )
    scans = parameters["scans"]
    references = {(r["shape"], r["pose"]) for r in figures["scan_references"] if r["converged"]}
    for name in scans["poses"]:
        rows = [
            r
            for r in figures["scan_rows"]
            if r["shape"] == name and (name, r["pose"]) in references
        ]
        if not rows:
            continue
        poses = [pose for pose, _ in scans["poses"][name] if (name, pose) in references]
        per_basis = [
            f"{kind} "
            + " and ".join(
                f"{100 * r['rms_error']:.2f}% (gap {r['objective_gap']:.3g})"
                for r in rows
                if r["basis"] == kind
            )
            for kind in scans["bases"]
        ]
        out.append(
            f"- {name} against Refine's minimum at {' and '.join(poses)}, RMS: "
            + "; ".join(per_basis)
            + "."
            + (
                " The gaps are large for every basis: a scan's slivers and flaps carry most of a reduced pose's "
                "objective and relax only on the full mesh, which is what Refine is for."
                if min(r["objective_gap"] for r in rows) > 1
                else ""
            )
        )
    out.append(
        "- RMS is a poor judge where a pose can spread differently at almost the same objective (a buckled "
        "twist); the gap is the paper's measure. Issue 16's own, thicker bar is checked against the issue's "
        "figures by tests/cpp/test_posing_accuracy.cpp (BarOfTheIssueTwistedAndBent)."
    )
    return "\n".join(out)


def section_renders(result):
    if not result or not result["figures"]["images"]:
        return "## Renders\n\nNot produced in this run."
    out = [
        "## Renders",
        "",
        "Cycles (CPU), the poses of the accuracy experiment with the (15, 52) basis: from left to right the "
        "full solve, the reduced solve with modal derivatives, the reduced solve with linear modes only, and "
        "Blender's Laplacian Deform with the same handles (when the Blender experiment ran). Made by "
        "`blender_scripts/render_figures.py` (see its docstring).",
        "",
    ]
    out += [
        f"![{pathlib.Path(p).stem}]({pathlib.Path(p).relative_to('docs')})"
        for p in result["figures"]["images"]
    ]
    out += ["", provenance(result)]
    return "\n".join(out)


def section_convergence(result):
    cases = result["figures"]["cases"]
    out = [
        "## Convergence of the reduced solve (paper Fig. 7)",
        "",
        "One large pose taken in a single step from rest, on a 67-dimensional basis with a 1k ghost: the "
        "objective minus the lowest value any method reached, per iteration, for Newton's method with the exact "
        "reduced Hessian, the solver's BFGS with the warm start (rest Hessian), BFGS from the identity, and "
        "steepest descent (bench/convergence.py).",
        "",
    ]
    fig, axes = plt.subplots(1, len(cases), figsize=(4.5 * len(cases), 4))
    rows = []
    for ax, case in zip(np.atleast_1d(axes), cases):
        for name, trace in case["traces"].items():
            gap = np.maximum(np.array(trace) - case["minimum"], 1e-12)
            ax.semilogy(range(len(gap)), gap, label=name)
            reach = next(
                (
                    i
                    for i, v in enumerate(trace)
                    if v - case["minimum"] <= 1e-6 * abs(case["minimum"])
                ),
                None,
            )
            rows.append(
                [
                    f"{case['shape']} {case['pose']}",
                    name,
                    len(trace) - 1,
                    f"{trace[-1]:.6g}",
                    f"{case['final_gradient_norms'][name]:.2e}",
                    "—" if reach is None else reach,
                ]
            )
        ax.set(
            title=f"{case['shape']} ({case['vertices']} vertices), {case['pose']}",
            xlabel="iteration",
            ylabel="f(q_k) − f*",
        )
        ax.legend(fontsize=8)
    save_figure(fig, "convergence")
    out.append(
        table(
            [
                "case",
                "method",
                "iterations run",
                "final objective",
                "final gradient norm",
                "iterations to within 1e-6 (relative) of the lowest",
            ],
            rows,
        )
    )
    out += ["", "![convergence](figures/convergence.png)", "", provenance(result)]
    return "\n".join(out)


def section_taylor(result):
    f, p = result["figures"], result["parameters"]
    t = np.array(f["t"])
    out = [
        "## The energy along a line in the reduced space (paper Fig. 9)",
        "",
        f"{p['shape']} ({p['vertices']} vertices), pose `{p['pose']}`, {p['dimension']}-dimensional basis: along "
        "q(t) = t q* (q* the reduced pose converged on the fine mesh), the shells energy and the objective "
        "(energy + handle term) on the fine mesh, their 2nd- and 3rd-order Taylor expansions at rest (Hessian "
        "and third derivative from the energy API; the handle term is quadratic and exact), and on ghosts "
        "(bench/taylor.py). Minima of the objective on the line:",
        "",
    ]
    out.append(
        table(
            ["curve", "t at the minimum", "objective there"],
            [[name, f"{m['t']:.4f}", f"{m['value']:.5g}"] for name, m in f["minima"].items()],
        )
    )
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    near = np.abs(t - 1) <= 0.2  # the handle term dominates the objective: show it near the minimum
    for i, name in enumerate(f["objective"]):
        style = "-" if name == "fine mesh" else ("--" if name.startswith("Taylor") else ":")
        axes[0].plot(t, f["energy"][name], style, color=f"C{i}", label=name)
        axes[1].plot(
            t[near], np.array(f["objective"][name])[near], style, color=f"C{i}", label=name
        )
        m = f["minima"][name]
        axes[1].plot([m["t"]], [m["value"]], "o", color=f"C{i}")
    axes[0].set(xlabel="t", ylabel="shells energy", title="deformation energy along t q*")
    axes[1].set(
        xlabel="t", ylabel="energy + handle term", title="objective near t = 1 (minima marked)"
    )
    axes[0].legend(fontsize=8)
    save_figure(fig, "taylor")
    out += ["", "![taylor](figures/taylor.png)", "", provenance(result)]
    return "\n".join(out)


def section_blender(result):
    f = result["figures"]
    out = [
        "## In Blender: the add-on's pose update, and Laplacian Deform",
        "",
        "`bench/blender_pose.py` in headless Blender. " + UPDATE_STEPS,
        "",
    ]
    out.append(display_table(f["bases"].items(), ["dims"], lambda dims: [dims]))
    checks = []
    for dims, b in f["bases"].items():
        target, tick = TARGETS[f"tick_{dims}"], b["positions"]["tick"]
        checks.append(
            f"tick at {dims} dims ≤ {target:.0f} ms — **{'met' if tick <= target else 'NOT met'}** "
            f"({tick:.1f} ms)"
        )
    out += [
        "",
        "Targets (the add-on issue: 60 fps, the mesh without shape keys): "
        + "; ".join(checks)
        + ".",
    ]
    if "dense" in f:
        dims, b = next(iter(f["dense"]["bases"].items()))
        out += [
            "",
            f"Dense: {f['dense']['mesh']} ({f['dense']['vertices']} vertices) baked on a proxy of "
            f"{b['proxy_vertices']} vertices in {b['bake_s']:.1f} s ({dims} dims):",
            "",
        ]
        out.append(display_table(f["dense"]["bases"].items(), ["dims"], lambda dims: [dims]))
    lap = f["laplacian_deform"]
    outcome = (
        "it solved"
        if lap["solved"]
        else "it found no solution on this mesh (the modifier then passes the "
        "hooked mesh through), so this is not the time of a solve"
    )
    out += [
        "",
        f"Blender's Laplacian Deform on a subdivided Suzanne ({lap['vertices']} vertices): bind "
        f"{lap['bind_s']:.1f} s, {lap['update_ms']:.0f} ms per update; {outcome}.",
    ]
    if "shapes" in f:
        out += [
            "",
            "Same shapes and handles, Laplacian Deform against Modal Deform (67 dimensions, 1k ghost, "
            "10 iterations per update): time per update, and the result's shells energy and RMS error against "
            "the full solve (the lower the energy the more physical the pose; the full solve's energy is the "
            "minimum with these handles).",
            "",
        ]
        out.append(
            table(
                [
                    "shape",
                    "pose",
                    "vertices",
                    "Laplacian: bind s",
                    "Laplacian: ms / update",
                    "Modal Deform: ms / update",
                    "energy: full",
                    "energy: Modal Deform",
                    "energy: Laplacian",
                    "RMS error: Modal Deform",
                    "RMS error: Laplacian",
                ],
                [
                    [
                        s["shape"],
                        s["pose"],
                        s["vertices"],
                        f"{s['laplacian_bind_s']:.2f}",
                        f"{s['laplacian_update_ms']:.1f}",
                        f"{s['ours_update_ms']:.2f}",
                        f"{s['energy_full']:.4g}",
                        f"{s['energy_ours']:.4g}",
                        f"{s['energy_laplacian']:.4g}",
                        f"{s['rms_ours']:.2e}",
                        f"{s['rms_laplacian']:.2e}",
                    ]
                    for s in f["shapes"]
                ],
            )
        )
    out += ["", provenance(result)]
    return "\n".join(out)


DISPLAYS = {"positions": "vertex positions", "stand_in": "stand-in", "shape_key": "shape key"}
UPDATE_STEPS = (
    "One update is the Pose operator's own calls per timer tick, the controller moving every update: "
    '"controllers" (matrices, set_transforms), "solve" (BFGS within "budget": what the rest of the last '
    '5 updates left of a 60 fps frame, less 1 ms, at most the object\'s 5 ms; "fixed": 5 ms, runs '
    "before the budget adapted), "
    '"write" (the solver writes the fine positions straight into Blender\'s array, then mesh.update()); '
    '"tick" is ours in all, "evaluate" Blender\'s own evaluation of the mesh for display. Where the '
    'pose is shown: a mesh without shape keys is posed in its vertex positions ("vertex positions"); one '
    'whose only key that moves it is "Modal Deform" (a mesh posed and kept before; measured with the '
    "keys Basis and Modal Deform) in the vertex positions of a copy without shape keys standing in for it "
    '("stand-in"); any other in the "Modal Deform" key ("shape key", the same keys), which Blender '
    "blends on every evaluation (the path the mesh posed before took until the stand-in). They are "
    "measured in turn (A B C A B C) in one process. Medians, ms; a display missing from a row's run was "
    "not measured then."
)


def display_table(bases, header, leading):
    """A row per basis and display: the columns leading(key) (named `header`) for each (key, basis)
    of `bases`, then the steps of one update."""
    rows = []
    for key, b in bases:
        for display, label in DISPLAYS.items():
            if display not in b:
                continue
            d = b[display]
            budget = f"{d['budget']:.2f}" if "budget" in d else "fixed"
            rows.append(
                [
                    *leading(key),
                    label,
                    f"{d['controllers']:.2f}",
                    budget,
                    f"{d['solve']:.2f}",
                    f"{d['write']:.2f}",
                    f"{d['tick']:.2f}",
                    f"{d['evaluate']:.2f}",
                    f"{d['update']:.1f}",
                    f"{d['iterations']:.0f}",
                ]
            )
    return table(
        [
            *header,
            "display",
            "controllers",
            "budget",
            "solve",
            "write",
            "tick (ours)",
            "evaluate (Blender)",
            "update",
            "iterations",
        ],
        rows,
    )


def section_bpy_pose(result):
    runs = result["figures"]["runs"]
    out = [
        "## The pose update in the Blenders artists run (issues 21, 23)",
        "",
        "`bench/blender_pose.py --pose-only` in bpy from the package index, the add-on installed from its "
        "extension zip by Blender's own installer (`tests/blender/bpy_session.py`): the dragon (100k vertices), "
        "subdivided once (400k) and twice (1.6M), and twice with as many edges split as it has vertices (3.2M), "
        "all but the first baked on a proxy. " + UPDATE_STEPS,
        "",
    ]
    out.append(
        display_table(
            (((run, dims), b) for run in runs for dims, b in run["bases"].items()),
            ["Blender", "vertices", "dims", "bake s"],
            lambda key: [
                key[0]["blender"],
                key[0]["vertices"],
                key[1],
                f"{key[0]['bases'][key[1]]['bake_s']:.1f}",
            ],
        )
    )
    checks = []
    for run in runs:
        target = common.FRAME_TARGETS_MS.get(run["vertices"])
        if target is not None:
            update = next(iter(run["bases"].values()))["positions"]["update"]
            checks.append(
                f"{run['blender']}, {run['vertices']} vertices: ≤ {target:.0f} ms — "
                f"**{'met' if update <= target else 'NOT met'}** ({update:.1f} ms)"
            )
    out += [
        "",
        "Targets (issue 23, ours and Blender's evaluation, a mesh without shape keys): "
        + "; ".join(checks)
        + ".",
    ]
    second = [
        f"{run['blender']}, {run['vertices']:,} vertices: {b['stand_in']['update']:.1f} ms against "
        f"{b['shape_key']['update']:.1f}"
        for run in runs
        for b in [next(iter(run["bases"].values()))]
        if "stand_in" in b
    ]
    if second:
        out += [
            "",
            "A mesh posed before (keys Basis and Modal Deform), one update in a stand-in against the shape "
            "key: " + "; ".join(second) + ".",
        ]
    peaks = [
        f"{run['blender']}, {run['vertices']:,} vertices: {run['peak_gb']:.1f} GB"
        for run in runs
        if "peak_gb" in run
    ]
    if peaks:
        out += [
            "",
            "Peak resident memory of the Blender process (the bake's): " + "; ".join(peaks) + ".",
        ]
    out += measured_apart(runs)
    plot_update_time(runs)
    out += [
        "",
        "![update time against vertex count](figures/update_time.png)",
        "",
        provenance(result),
    ]
    return "\n".join(out)


def plot_update_time(runs):
    """Update time against vertex count per Blender and display: ours (the tick) and Blender's
    evaluation stacked, so the top line is one update."""
    blenders = sorted({run["blender"] for run in runs})
    fig, axes = plt.subplots(
        1, len(blenders), figsize=(5.5 * len(blenders), 4), sharey=True, squeeze=False
    )
    for ax, blender in zip(axes[0], blenders):
        mine = sorted(
            (run for run in runs if run["blender"] == blender), key=lambda run: run["vertices"]
        )
        n = [run["vertices"] for run in mine]
        for (display, label), colour in zip(DISPLAYS.items(), ("C0", "C2", "C1")):
            if any(display not in next(iter(run["bases"].values())) for run in mine):
                continue
            steps = [next(iter(run["bases"].values()))[display] for run in mine]
            ours = np.array([d["tick"] for d in steps])
            update = np.array([d["update"] for d in steps])
            ax.plot(n, ours, "o--", color=colour, label=f"{label}: ours")
            ax.plot(n, update, "s-", color=colour, label=f"{label}: ours + Blender's evaluation")
            ax.fill_between(n, ours, update, color=colour, alpha=0.15)
        for (
            run
        ) in mine:  # a run merged from a separate measurement says under what load it was taken
            if "measured" in run:
                ax.annotate(
                    f"measured apart,\nload {run['measured']['load_average'][0]:.1f}",
                    (run["vertices"], next(iter(run["bases"].values()))["positions"]["update"]),
                    xytext=(-70, 10),
                    textcoords="offset points",
                    fontsize=7,
                )
        targets = common.FRAME_TARGETS_MS
        ax.plot(list(targets), list(targets.values()), "r*", markersize=12, label="target")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("vertices")
        ax.set_title(f"bpy {blender}")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].set_ylabel("ms per update (medians)")
    axes[0][-1].legend(fontsize=7)
    save_figure(fig, "update_time")


def section_viewport_frames(result):
    out = [
        "## The viewport's frame while posing (issue 23)",
        "",
        "`bench/viewport_frames.py` in Debian's Blender 3.4.1 app with a window under Xvfb: software OpenGL "
        "(llvmpipe), so the drawing is far slower than on a GPU and these are figures to know, not targets. A "
        "frame is the pose update as above (ours, Blender's evaluation) and then the viewport drawn and swapped "
        '(`wm.redraw_timer`, "draw": normals, GPU buffers, drawing). Medians, ms.',
        "",
    ]
    rows = []
    for run in result["figures"]["runs"]:
        for display, label in DISPLAYS.items():
            if display not in run["displays"]:
                continue
            f = run["displays"][display]
            rows.append(
                [
                    run["vertices"],
                    run["dimension"],
                    label,
                    f"{f['tick']:.1f}",
                    f"{f['evaluate']:.1f}",
                    f"{f['draw']:.0f}",
                    f"{f['frame']:.0f}",
                ]
            )
    out.append(
        table(
            [
                "vertices",
                "dims",
                "display",
                "ours",
                "evaluate (Blender)",
                "draw (Blender)",
                "frame",
            ],
            rows,
        )
    )
    out += ["", provenance(result)]
    return "\n".join(out)


def section_native(result):
    out = [
        "## Native benchmarks (Google Benchmark)",
        "",
        f"`{result['parameters']['binary']}` (bench/bench_*.cpp); real time per iteration and the counters "
        "each benchmark reports.",
        "",
    ]
    rows = []
    for b in result["figures"]["benchmarks"]:
        if b.get("run_type") == "aggregate":
            continue
        skip = {
            "name",
            "family_index",
            "per_family_instance_index",
            "run_name",
            "run_type",
            "repetitions",
            "repetition_index",
            "threads",
            "iterations",
            "real_time",
            "cpu_time",
            "time_unit",
        }
        counters = ", ".join(
            f"{k} {v:.4g}" for k, v in b.items() if k not in skip and isinstance(v, (int, float))
        )
        rows.append([b["name"], f"{b['real_time']:.4g} {b['time_unit']}", counters])
    out.append(table(["benchmark", "real time", "counters"], rows))
    out += ["", provenance(result)]
    return "\n".join(out)


def section_raw_scan(result):
    p = result["parameters"]
    out = [
        "## Raw scans (issue 15)",
        "",
        f"{p['mesh']} midpoint-subdivided {p['subdivisions']} time(s) and damaged by tests/support/raw_scans.py (every "
        f"kind of scan damage), baked with {p['modes']} modes + {p['derivatives']} derivatives and a "
        f"{p['ghost']}-vertex ghost, each seed in a fresh process. Targets: at most {p['targets']['seconds']:.0f} s "
        f"within {p['targets']['peak_gb']:.0f} GB.",
        "",
    ]
    rows = []
    for b in result["figures"]["bakes"]:
        if b["ok"]:
            rows.append(
                [
                    b["seed"],
                    b["vertices"],
                    b["components"],
                    f"{b['seconds']:.1f}",
                    f"{b['peak_gb']:.2f}",
                    b["floppy"],
                    "baked",
                ]
            )
        else:
            rows.append(
                [b["seed"], b.get("vertices", ""), b.get("components", ""), "", "", "", b["error"]]
            )
    out.append(
        table(
            ["seed", "vertices", "components", "bake s", "peak GB", "zero modes", "outcome"], rows
        )
    )
    out += ["", provenance(result)]
    return "\n".join(out)


def section_multires(result):
    p, t = result["parameters"], result["parameters"]["targets"]
    out = [
        "## Multiresolution bake of a dense mesh (issue 15)",
        "",
        f"{p['mesh']} midpoint-subdivided {p['subdivisions']} times (tests/support/subdivision.py), baked "
        f"on a proxy with {p['modes']} modes + {p['derivatives']} derivatives and a {p['ghost']}-vertex ghost, "
        "each proxy size in a fresh process. Update: new transforms, 10 BFGS iterations and the fine positions, "
        "median over the end-pull animation. RMS: the converged end-pull pose against the dragon's own bake on "
        "the vertices the meshes share, relative to the bounding-box diagonal. Targets (printed, not asserted): "
        f"bake {t['seconds']:.0f} s, peak {t['peak_gb']:.0f} GB, stored {t['stored_mb']:.0f} MB, update "
        f"{t['update_ms']:.0f} ms, RMS {100 * t['rms']:.0f}%.",
        "",
    ]
    rows = []
    for b in result["figures"]["bakes"]:
        if b["ok"]:
            rows.append(
                [
                    b["vertices"],
                    b["proxy_vertices"],
                    f"{b['seconds']:.1f}",
                    f"{b['timings']['proxy']:.1f}",
                    f"{b['peak_gb']:.2f}",
                    f"{b['stored_mb']:.0f} ({b['dense_mb']:.0f})",
                    f"{b['update_ms']:.1f}",
                    f"{100 * b['rms']:.2f}%",
                ]
            )
        else:
            rows.append(["", b["proxy"], "", "", "", "", "", b["error"]])
    out.append(
        table(
            [
                "vertices",
                "proxy",
                "bake s",
                "of which proxy s",
                "peak GB",
                "stored MB (dense)",
                "update ms",
                "RMS",
            ],
            rows,
        )
    )
    out += ["", provenance(result)]
    return "\n".join(out)


def section_strong_poses(result):
    p, f = result["parameters"], result["figures"]
    out = [
        "## Strong poses (issue 22)",
        "",
        f"The 100k dragon's own bake ({p['modes']} modes + {p['derivatives']} derivatives, {p['ghost']}-vertex ghost, "
        f"stiffness {p['stiffness']:g}, handles on the last 15% at each end): each pose reached in steps of at most 30 "
        "degrees, each solved to convergence (tolerance 1e-6); difference error: the worst centred-difference error "
        "of the objective along a random direction over the path, relative to 1 + |f| (a jump shows as about "
        "jump / step).",
        "",
    ]
    rows = [
        [
            pose,
            "yes" if r["converged"] else "NO",
            "YES" if r["stalled"] else "no",
            r["iterations"],
            f"{r['energy']:.3f}",
            f"{r['difference_error']:.1e}",
        ]
        for pose, r in f["own_poses"].items()
    ]
    out.append(
        table(["pose", "converged", "stalled", "iterations", "objective", "difference error"], rows)
    )
    out += [
        "",
        f"The {p['mesh']} midpoint-subdivided {p['subdivisions']} times ({f['fine_vertices']:,} vertices) baked "
        f"with bake's defaults (proxy of {f['proxy_vertices']:,} vertices) in {f['fine_bake_s']:.0f} s; its end "
        "turned about the long axis and moved by (0, 3, 1.5) units, interactively (60 calls of 10 iterations while "
        "the pose ramps up, 140 more, tolerance 1e-8), then to convergence; the same for the 100k dragon's own "
        "bake. RMS: the two poses on the vertices they share, relative to the bounding-box diagonal (targets "
        + ", ".join(f"{100 * v:.0f}% at {k}" for k, v in p["targets"].items())
        + "). Objectives: the reduced "
        "solver's (ghost energy plus handle term). Gap: the full objective of the 100k dragon at the pose (the 1.6M "
        "pose on the vertices the meshes share) above its minimum, relative to the minimum; the minimum is "
        "solve_full's, converged from the lower of the two poses (Refine), with its iterations and seconds. The gaps "
        "are large because neither reduced pose sees the 100k mesh's own slivers: the ghost's energy leaves them "
        "out, and its tiniest triangles take most of the full objective at a "
        "reduced pose; the RMS, not the gap, says how close the poses are.",
        "",
    ]
    rows = []
    for degrees, r in f["turns"].items():
        full = r.get("full")

        def gap(pose):
            if not full or "gap" not in full:
                return ""
            if not full["converged"]:
                return "not converged: no reference"
            return f"{full['gap'][pose]:.3f} ({100 * full['gap'][pose] / full['energy']:.1f}%)"

        minimum = ""
        if full and "gap" in full:
            minimum = (
                f"{full['energy']:.3f}"
                if full["converged"]
                else f"NOT converged (from {full['gap'][full.get('start', 'own')] + full['energy']:.4g} to "
                f"{full['energy']:.4g})"
            )
            minimum += f", {full['iterations']} it, {full['seconds']:.0f} s"
        rows.append(
            [
                degrees,
                "yes" if r["fine"]["converged"] else "NO",
                r["fine"]["stalled_calls"],
                r["fine"]["calls_without_progress"],
                f"{r['fine']['energy']:.3f}",
                f"{r['own']['energy']:.3f}",
                minimum,
                gap("fine"),
                gap("own"),
                f"{100 * r['rms']:.2f}%",
                f"{r['fine']['difference_error']:.1e}",
            ]
        )
    out.append(
        table(
            [
                "turn deg",
                "1.6M converged",
                "stalled calls",
                "calls without progress",
                "1.6M objective",
                "100k objective",
                "full minimum",
                "1.6M gap",
                "100k gap",
                "RMS 1.6M vs 100k",
                "difference error",
            ],
            rows,
        )
    )
    if p.get("note"):
        out += ["", p["note"]]
    out += ["", provenance(result)]
    return "\n".join(out)


def zero_modes_note(run):
    """What the bake-limit record says of the dragon's zero modes (on top of the dimensions)."""
    zero_modes = max(int(r["dimension_with_zero_modes"]) - int(dims) for dims, r in run.items())
    return (
        f" The dragon's {zero_modes} floppy zero modes came on top of the dimensions."
        if zero_modes > 0
        else ""
    )


def section_bake_limit(result):
    p = result["parameters"]
    summary = result["figures"]["summary"]
    out = [
        "## The bake at the limit (issues 14 and 25)",
        "",
        f"{p['mesh']} (100k vertices) baked by `{p['binary']} --benchmark_filter={p['filter']}` "
        f"(bench/bench_bake.cpp) with a {p['ghost']}-vertex ghost at the paper's sizes and pairs, "
        f"{p['runs']} fresh process(es); medians; peak: the largest resident-set high-water mark of a bake, in GB of "
        "2^30 bytes. CHOLMOD: analysing and factoring "
        "the same stiffness matrix alone, in the same process right after the bake; the ratio is taken run by "
        "run." + zero_modes_note(result["figures"]["runs"][0]),
        "",
    ]
    rows = [
        [
            f"{d} ({'+'.join(str(x) for x in p['sizes'][d])})",
            f"{s['seconds']:.1f}",
            f"{s['cholmod_s']:.1f}",
            f"{s['ratio']:.2f}",
            f"{s['peak_gb']:.2f}",
        ]
        + [f"{s['stages'][k]:.2f}" for k in bake_limit.STAGE_KEYS]
        for d, s in summary.items()
    ]
    out.append(
        table(
            ["dims", "bake s", "CHOLMOD s", "ratio", "peak GB"] + list(bake_limit.STAGE_KEYS), rows
        )
    )
    solves = next(iter(summary.values())).get("solve_ms_per_rhs")
    if solves:
        out += [
            "",
            "CHOLMOD's solves with that factor, per right-hand side: "
            + ", ".join(
                f"{solves[w]:.1f} ms {'alone' if w == '1' else f'in blocks of {w}'}"
                for w in bake_limit.SOLVE_WIDTHS
            )
            + ".",
        ]
    out += ["", "Targets:", ""]
    out += [
        f"- {what}: **{measured:.2f} {unit}** — {'met' if measured <= target else 'NOT met'}"
        for what, measured, target, unit in bake_limit.checks(summary)
    ]
    out += ["", provenance(result)]
    return "\n".join(out)


def section_bake_busy(result):
    p, f = result["parameters"], result["figures"]
    summary = f["summary"]
    meshes = ", ".join(f"{size} ({mesh})" for size, mesh in p["meshes"].items())
    out = [
        "## The bake beside a busy core (issue 25)",
        "",
        f"The dragon at {meshes} baked at {p['modes']} + {p['derivatives']} with a {p['ghost']}-vertex ghost "
        "(bench/bake_once.py), each bake in a fresh process, quiet and with "
        f"{p['busy']}: in plain Python as shipped (OpenMP's passive wait, OpenBLAS under CHOLMOD on the usable "
        "cores less one) and with GCC OpenMP's default spinning wait, and inside bpy on the installed extension "
        "(Blender's own NumPy and OpenBLAS beside the core's). Each bake also ran quiet on one core (its "
        "affinity set to one): beside `yes` the bake's session gets about one core's worth of time, so busy / one "
        "core is what the sharing costs beyond the lost core, and busy / quiet is about one core / quiet at "
        "least, the speed-up the second core gives. The machine is shared: each bake ran quiet, on one core and "
        "busy back to back, the ratios are taken bake by bake, medians over "
        f"{p['rounds']} round(s); the load average (1 min) before each bake's runs is given. Issue 25's target: "
        "busy / quiet at most 1.3.",
        "",
    ]
    rows = [
        [
            bake.replace("_", " "),
            f"{s['quiet']:.1f}",
            f"{s['one_core']:.1f}",
            f"{s['busy']:.1f}",
            f"{s['busy_over_quiet']:.2f}",
            f"{s['busy_over_one_core']:.2f}",
            "{:.1f}–{:.1f}".format(*s["load_before"]),
        ]
        for bake, s in summary.items()
        if bake != "shipped_over_spinning"
    ]
    out.append(
        table(
            [
                "bake",
                "quiet s",
                "one core s",
                "busy s",
                "busy / quiet",
                "busy / one core",
                "load before",
            ],
            rows,
        )
    )
    out += ["", "Busy / quiet by stage (the bake's own timings, medians):", ""]
    stages = [
        k
        for k in bake_limit.STAGE_KEYS
        if k in next(iter(summary.values()))["stages_busy_over_quiet"]
    ]
    out.append(
        table(
            ["bake"] + stages,
            [
                [bake.replace("_", " ")]
                + [f"{s['stages_busy_over_quiet'].get(k, 0):.2f}" for k in stages]
                for bake, s in summary.items()
                if bake != "shipped_over_spinning"
            ],
        )
    )
    out += [
        "",
        "Shipped / spinning (plain Python): "
        + ", ".join(
            f"{c.replace('_', ' ')} {x:.2f}" for c, x in summary["shipped_over_spinning"].items()
        )
        + ".",
        "",
        f"The threads, in each Python, during a bake of {p['check_mesh']}: what the core's OpenMP runtime "
        "reports (OMP_DISPLAY_ENV), and the thread counts each OpenBLAS in the process showed (sampled every "
        "2 ms).",
        "",
    ]
    rows = [
        [
            python,
            ", ".join(c["omp_wait_policy"]),
            ", ".join(c["gomp_spincount"]),
            "; ".join(
                f"`{library}` {seen}" for library, seen in c["openblas_threads_seen"].items()
            ),
        ]
        for python, c in f["checks"].items()
    ]
    out += [
        table(["Python", "OpenMP wait", "spin count", "OpenBLAS: threads seen"], rows),
        "",
        provenance(result),
    ]
    return "\n".join(out)


def section_region(result):
    p, f = result["parameters"], result["figures"]
    out = [
        "## A region bake against the whole mesh (issue 24)",
        "",
        f"{p['mesh']} baked with {p['modes']} modes, {p['derivatives']} derivatives and a {p['ghost']}-vertex "
        f"ghost as a whole, and with only its head as the region (the {100 * p['head_fraction']:.0f}% of its "
        "length at the low-x end), the two bakes in turn in one process, medians: as it is (dense), and "
        f"midpoint-subdivided twice, where both bakes are on a proxy of about {p['proxy']} vertices (the whole "
        "mesh's, or the one of the region's own faces). The region's basis has no rigid motions (its boundary is "
        "fixed) and its ghost and proxy cover only the region and the faces around it.",
        "",
    ]
    for size in ("dense", "on_proxy"):
        g = f[size]
        whole, region = g["summary"]["whole"], g["summary"]["region"]
        stages = [k for k in whole["stages"] if k in region["stages"]]
        rows = [
            [
                kind,
                f"{s['seconds']:.1f}",
                f"{s['dimension']} ({s['num_rigid']} rigid, {s['num_floppy']} zero)",
                str(s["proxy_vertices"] or "-"),
                str(s["ghost_vertices"]),
            ]
            + [f"{s['stages'].get(k, 0.0):.2f}" for k in stages]
            for kind, s in (
                (f"whole mesh ({g['vertices']})", whole),
                (f"head region ({g['region_vertices']})", region),
            )
        ]
        out += [
            table(
                ["bake (vertices)", "s", "dimensions", "proxy vertices", "ghost vertices"] + stages,
                rows,
            ),
            "",
        ]
        ratios = [
            w["seconds"] / r["seconds"] for w, r in zip(g["runs"]["whole"], g["runs"]["region"])
        ]
        out += [
            f"Run by run ({len(ratios)} pair(s), each baked back to back), the head region bakes "
            f"{statistics.median(ratios):.1f} times faster (from {min(ratios):.1f} to {max(ratios):.1f}). Posed "
            f"with the top of the head lifted, the largest displacement of a vertex outside the region is "
            f"{g['outside_max_displacement']:g} (mesh units).",
            "",
        ]
    out.append(provenance(result))
    return "\n".join(out)


def section_refine(result):
    p = result["parameters"]
    out = [
        "## Refine and the full solve on scans (issue 26)",
        "",
        "Newton on the full mesh (`mdc.solve_full`, tolerance "
        f"{p['tolerance']:g} on the gradient norm) for the dragons and a raw-scan-like dragon (tests/support/raw_scans.py, "
        f"seed 0), handles on the 15% at each end, stiffness {p['stiffness']:g}: the far end turned about the long "
        "axis and moved by 9% of the length sideways and 4.5% up (turn), or bent about the up axis (bend). "
        f"Refine: the reduced pose ({p['basis']}, BFGS to convergence), then `ReducedSolver.refine` from it; gap "
        "and RMS (of the bounding-box diagonal) are the reduced pose's against the refined minimum. Time: the "
        "native solve's wall time, with the load average when it ended (2 cores shared). Exact / guarded / "
        "failed: iterations on the exact Hessian (the rest on the projected one), steps cut only because "
        "longer ones turned a triangle over, line searches that found no decrease. Relaxed: vertices of edges the "
        "reduced pose stretched beyond 3 times, relaxed on their own before Newton (fins and needles of the "
        f"scan). Crushed: faces with less than {refine.CRUSHED_BELOW:.0%} of their rest area at the start and at "
        "the end (Newton keeps every face from turning over, so each face the minimum crushes cuts steps on the "
        "way). Non-converged "
        "solves are marked and are no reference.",
        "",
    ]
    rows = []
    for mesh, entry in result["figures"].items():
        for kind in ("from_rest", "refine"):
            for pose, r in entry[kind].items():
                rows.append(
                    [
                        mesh,
                        entry["vertices"],
                        pose,
                        "from rest" if kind == "from_rest" else "Refine",
                        r["steps"],
                        r["iterations"],
                        r["factorizations"],
                        f"{r['seconds']:.1f}",
                        f"{r['load_average']:.1f}" if "load_average" in r else "",
                        "/".join(
                            str(r.get(k, ""))
                            for k in ("exact_iterations", "guarded_steps", "line_search_failures")
                        ),
                        f"{r['energy']:.5g}",
                        "yes" if r["converged"] else "**no**",
                        f"{r['gap']:.3g}" if "gap" in r else "",
                        f"{100 * r['rms']:.3f}%" if "rms" in r else "",
                        r.get("relaxed_vertices", ""),
                        f"{r['crushed_at_start']} → {r['crushed_at_end']}"
                        if "crushed_at_end" in r
                        else "",
                    ]
                )
    out.append(
        table(
            [
                "mesh",
                "vertices",
                "pose",
                "solve",
                "load steps",
                "iterations",
                "factorisations",
                "s",
                "load",
                "exact/guarded/failed",
                "objective",
                "converged",
                "reduced gap",
                "reduced RMS",
                "relaxed",
                "crushed",
            ],
            rows,
        )
    )
    older = [
        f"The {mesh} rows are from an earlier run: commit `{entry['commit'][:12]}`, {entry['date']}."
        for mesh, entry in result["figures"].items()
        if entry.get("commit", result["commit"]) != result["commit"]
    ]
    out += ["", *(older + [""] if older else []), "Targets:", ""]
    for mesh, degrees in p["targets"]["from_rest_converges"].items():
        entry = result["figures"].get(mesh)
        for d in degrees:
            r = entry and entry["from_rest"].get(f"turn {d}")
            out.append(
                f"- {mesh} from rest, turn {d}: "
                + (
                    "not run"
                    if not r
                    else f"**{'converged' if r['converged'] else 'NOT converged'}** ({r['iterations']} iterations)"
                )
            )
    for mesh, limit in p["targets"]["refine_seconds"].items():
        entry = result["figures"].get(mesh)
        if not entry:
            out.append(f"- {mesh} Refine within {limit:.0f} s: not run")
            continue
        worst = max(r["seconds"] for r in entry["refine"].values())
        ok = all(r["converged"] and r["seconds"] <= limit for r in entry["refine"].values())
        out.append(
            f"- {mesh} Refine converges within {limit:.0f} s: slowest {worst:.1f} s — "
            f"{'met' if ok else 'NOT met'}"
        )
    out += ["", provenance(result)]
    return "\n".join(out)


def section_playback(result):
    runs = result["figures"]["runs"]
    out = [
        "## Animation cache and secondary motion (issue 40)",
        "",
        "`bench/playback.py` in bpy from the package index, the add-on installed from its extension zip: the "
        "dragon (100k vertices; subdivided twice, 1.6M, on a proxy) with a controller turning and sliding, "
        f"keyed every 6 frames. Per frame, the median over the frames of each frame's least over "
        f"{runs[0]['dynamic_step'].get('rounds', 1)} rounds of the same frames (a live step's frames simulated "
        "again each round: a neighbour's load on the machine left out): \"handler\" is the frame handler's work "
        "for the object "
        "(playback.timeline.show: the checks, the cache read or the simulation step, x̄ + U q into the display, "
        'playback/frame_display.py), of it in brackets "map", x̄ + U q alone (the part that grows with the mesh), '
        '"evaluate" Blender\'s evaluation after it, to the return of frame_set. The frames are played: the '
        "add-on's playback handlers called around them, the display reads a stand-in mesh whose positions are "
        'the frame; "timeline still" steps the same frames with the timeline still (scrubbing), where the '
        "display's Geometry Nodes modifier sets the positions from a point attribute.",
        "",
    ]

    def split(figures):
        mapped = f" ({figures['map_ms']:.2f})" if "map_ms" in figures else ""
        return f"{figures['handler_ms']:.2f}{mapped} + {figures['evaluate_ms']:.2f}"

    rows = [
        [
            run["blender"],
            f"{run['vertices']:,}",
            run["dimension"],
            split(run["static_read"]),
            split(run["dynamic_read"]),
            split(run["dynamic_step"]),
            split(run["dynamic_step_still"]) if "dynamic_step_still" in run else "",
            "{:.1f} / {:.1f}".format(*loads) if (loads := load_range(run)) else "",
        ]
        for run in runs
    ]
    out.append(
        table(
            [
                "Blender",
                "vertices",
                "dims",
                "static cache read: handler (map) + evaluate ms",
                "simulation cache read ms",
                "live simulation step ms",
                "live step, timeline still ms",
                "load before / after",
            ],
            rows,
        )
    )
    stepped = [
        f"{run['blender']}, {run['vertices']:,} vertices: {run['dynamic_step']['step_ms']:.1f} ms, "
        f"{run['dynamic_step']['iterations']:.0f} BFGS iterations"
        for run in runs
        if "step_ms" in run["dynamic_step"]
    ]
    if stepped:
        out += [
            "",
            "Of the live step, the simulation's own step (Simulation.stats, both substeps): "
            + "; ".join(stepped)
            + ".",
        ]
    jumps = [
        f"{run['blender']}, {run['vertices']:,} vertices: {run['dynamic_jump']['ms_per_frame']:.1f} ms a frame "
        f"over {run['dynamic_jump']['frames']} frames"
        for run in runs
        if "dynamic_jump" in run
    ]
    if jumps:
        out += [
            "",
            "A jump forward (every frame in between simulated at its own frame, the last one mapped): "
            + "; ".join(jumps)
            + ".",
        ]
    bare = [
        f"{run['blender']}, {run['vertices']:,} vertices: {run['without_display']['evaluate_ms']:.2f} ms "
        f"against {run['dynamic_read']['evaluate_ms']:.2f} with the display"
        for run in runs
        if "without_display" in run
    ]
    if bare:
        out += [
            "",
            "Blender's evaluation of the same mesh without the display, its vertex positions written (a copy "
            'on another object): the floor of "evaluate", against the played cache read\'s: '
            + "; ".join(bare)
            + ".",
        ]
    targets = common.FRAME_TARGETS_MS
    checks = [
        f"{run['blender']}, {run['vertices']:,} vertices: ≤ {targets[run['vertices']]:.0f} ms — "
        f"**{'met' if total <= targets[run['vertices']] else 'NOT met'}** ({total:.1f} ms)"
        for run in runs
        if run["vertices"] in targets
        for total in [run["dynamic_step"]["handler_ms"] + run["dynamic_step"]["evaluate_ms"]]
    ]
    if checks:
        out += [
            "",
            "Target (issue 40, a live step with Blender's evaluation): " + "; ".join(checks) + ".",
        ]
    out += rig_playback(runs)
    out += measured_apart(runs)
    sized = [run for run in runs if "blend_with_shape_keys_bytes" in run]
    if sized:
        out += [
            "",
            table(
                [
                    "Blender",
                    "frames",
                    "cache KB",
                    ".blend with the cache MB",
                    ".blend with a shape key per frame MB",
                    "PC2 file MB",
                    "shape-key export s",
                ],
                [
                    [
                        run["blender"],
                        run["frames"],
                        f"{run['static_cache_bytes'] / 1024:.1f}",
                        f"{run['blend_with_cache_bytes'] / 2**20:.1f}",
                        f"{run['blend_with_shape_keys_bytes'] / 2**20:.1f}",
                        f"{run['pc2_bytes'] / 2**20:.1f}",
                        f"{run['shape_keys_export_seconds']:.1f}",
                    ]
                    for run in sized
                ],
            ),
        ]
    out += ["", provenance(result)]
    return "\n".join(out)


#: The add-on's share of a played frame on a rig (Follow Rig, issue 50) in at most this many ms, by
#: the vertex count of the dragon (100k, and subdivided twice, 1.6M, on a proxy).
RIG_TARGETS_MS = {100250: 4.0, 1606964: 8.0}


def rig_playback(runs):
    """The rig case of the playback runs (issue 50's Speed): per Blender, mesh and bone count, the
    add-on's share split, Blender's evaluation beside it and the Armature modifier alone."""
    rigged = [(run, case) for run in runs for case in run.get("rig", [])]
    if not rigged:
        return []
    played = rigged[0][1]["played"]
    rows = []
    for run, case in rigged:
        p = case["played"]
        target = RIG_TARGETS_MS.get(run["vertices"])
        met = "" if target is None else ("met" if p["handler_ms"] <= target else "**NOT met**")
        rows.append(
            [
                run["blender"],
                f"{run['vertices']:,}",
                case["bones"],
                f"{case['attached']:,}",
                f"**{p['handler_ms']:.2f}**",
                f"{p['bones_ms']:.2f} / {p['step_ms']:.2f} / {p['map_ms']:.2f} / {p['other_ms']:.2f}",
                f"{p['before_ms']:.2f} + {p['evaluate_ms']:.2f}",
                f"{case['armature_alone']['evaluate_ms']:.2f}",
                "" if target is None else f"≤ {target:.0f}: {met}",
                "{:.1f} / {:.1f}".format(*loads) if (loads := load_range(rig_run(run))) else "",
            ]
        )
    apart = sorted(
        {
            (m["date"], m["commit"][:12])
            for run, _ in rigged
            if (m := run.get("rig_measured")) is not None
        }
    )
    return [
        "",
        "### Secondary motion on a rig (issue 50)",
        "",
        "The same dragon skinned by an Armature modifier to a chain of 3, 30 or 100 bones along its long "
        "axis (weights by formula, linear between the bones' centres, two bones a vertex at most; the "
        "Attach group filled by Fill Attach from Armature within a tenth of the dragon's length of the "
        "chain); the armature object keyed to jump and turn (frames 1 to 9), every bone to bend and back "
        "(9 to 17), still after; Follow Rig on, the frames played (the add-on's playback handlers called "
        f"around them) and each simulated live, the median over {played['frames']} frames of a frame's "
        f'least over {played["rounds"]} rounds. "add-on" is the frame handler\'s work '
        "(playback.timeline.show), split into the rig's bones read (rig.Rig.frame), the simulation's step, "
        "the map of its q into the display's offset attribute (U q, natively), and the rest (the checks, "
        "the keyframes' digest and values, the cache, the attribute's update). Blender evaluates the frame "
        "twice: before the handler (the animation, the rig, the mesh with the offset it had) and after it "
        "(the mesh again with its new offset: the display's Geometry Nodes Set Position, then the Armature "
        "modifier); \"Armature alone\" is frame_set's time with the add-on's display and dynamics off the "
        "same mesh: its Armature modifier alone, the floor.",
        "",
        table(
            [
                "Blender",
                "vertices",
                "bones",
                "attached",
                "add-on ms",
                "bones / step / map / other ms",
                "Blender before + after ms",
                "Armature alone ms",
                "target (add-on)",
                "load before / after",
            ],
            rows,
        ),
    ] + (
        [
            "",
            "The rig case measured apart from the runs above and merged into their record: "
            + "; ".join(f"{date}, commit `{commit}`" for date, commit in apart)
            + " (the load beside each row).",
        ]
        if apart
        else []
    )


def rig_run(run):
    """The run's rig case's own provenance (rig_measured: its date, commit and load average) when it
    was measured apart from the run's other figures, else the run."""
    return run.get("rig_measured", run)


def load_range(run):
    """(1-minute load average before, after) of a playback run, None for runs that did not record it."""
    loads = run.get("load_average")
    return (loads["before"][0], loads["after"][0]) if loads else None


def section_dynamics(result):
    p, f = result["parameters"], result["figures"]
    d = p["defaults"]
    bar = f["bar"]
    out = [
        "## Secondary motion (issue 40)",
        "",
        f"`mdc.Simulation` with its defaults (period {d['period']:g} frames, damping ratio {d['damping']:g}, "
        f"{d['fps']:g} fps, {d['substeps']} substeps, the handles' pull {p.get('pull', d.get('stiffness')):g}, "
        f"BFGS tolerance "
        f"{d['tolerance']:g}, at most {d['max_iterations']} iterations a substep) unless said otherwise.",
        "",
        f"A free bar ({bar['vertices']} vertices, {bar['dimension']} dimensions) released from rest at "
        f"{p['amplitude']:g} along its lowest flexible mode; period and logarithmic decrement fitted to the mode's "
        "coordinate frame by frame (a damped sinusoid's recurrence, least squares). Undamped:",
        "",
    ]
    out.append(
        table(
            [
                "period set (frames)",
                "fps",
                "substeps",
                "period measured",
                "amplitude after 10 periods",
            ],
            [
                [
                    f"{r['period']:g}",
                    f"{r['fps']:g}",
                    r["substeps"],
                    f"{r['measured_period']:.4f}",
                    f"{100 * r['amplitude_after_10_periods']:.4f}%",
                ]
                for r in bar["undamped"]
            ],
        )
    )
    if "energy" in bar:
        e = bar["energy"]
        out += [
            "",
            f"Large undamped swings ({e['dimension']} dimensions, period {e['period']:g} frames): the total "
            "energy over 10 periods, as a fraction of its start, with the energy correction's removals and "
            "additions, at 2 substeps and at 32 (tolerance 1e-12):",
            "",
        ]
        out.append(
            table(
                [
                    "swing (of the length)",
                    "substeps",
                    "energy at the end",
                    "lowest, highest",
                    "removed",
                    "added",
                    "period measured",
                    "amplitude after 10 periods",
                ],
                [
                    [
                        f"{100 * r['fraction_of_length']:g}%",
                        name.split("_")[1],
                        f"{run['energy_end']:.6f}",
                        f"{run['energy_min']:.6f}, {run['energy_max']:.6f}",
                        f"{run['energy_removed']:.2e}",
                        f"{run['energy_added']:.2e}",
                        f"{run['measured_period']:.3f}",
                        f"{100 * run['amplitude_after_10_periods']:.2f}%",
                    ]
                    for r in e["rows"]
                    for name, run in r.items()
                    if name.startswith("substeps_")
                ],
            )
        )
    out += ["", "Damped (the damped period is the set one over √(1−ζ²)):", ""]
    out.append(
        table(
            ["ζ", "decrement 2πζ/√(1−ζ²)", "measured", "error", "period measured"],
            [
                [
                    f"{r['damping']:g}",
                    f"{r['expected_decrement']:.5f}",
                    f"{r['decrement']:.5f}",
                    f"{100 * (r['decrement'] / r['expected_decrement'] - 1):+.4f}%",
                    f"{r['measured_period']:.3f}",
                ]
                for r in bar["damped"]
            ],
        )
    )
    rows = []
    for name, c in list(f["cost"].items()) + [("subdivided twice, on a proxy", f["proxy"])]:
        rows.append(
            [
                name,
                c["vertices"],
                c.get("proxy_vertices", "-"),
                c["dimension"],
                f"{c['bake_s']:.1f}",
                f"{c['step_ms']['median']:.2f} / {c['step_ms']['p95']:.2f}",
                f"{c['iterations']['median']:g} / {c['iterations']['max']:g}",
                f"{c['evaluations']['median']:g}",
                f"{c['ms_per_evaluation']['median']:.3f}",
                f"{c['map_ms']['median']:.2f} / {c['map_ms']['p95']:.2f}",
                f"{c['map_back_to_back_ms']:.2f}",
            ]
        )
    out += [
        "",
        "Cost per frame: the tail held, the head's controller turning 60° in 12 frames and still after "
        "(the demo's motion), 60 frames (30 on the proxy). Step: the core's integrator (`stats['ms']`), its "
        "BFGS iterations and evaluations of the ghost energy a frame and its time per evaluation (what a "
        "frame costs is evaluations times that); map: `Simulation.positions` into a float32 buffer (what "
        "Blender's `foreach_set` takes) after each step, and back to back (a busy machine wakes the map's "
        "threads late after each serial step); median / 95th percentile. Blender's own evaluation "
        "(foreach_set and the mesh update) is not included.",
        "",
    ]
    out.append(
        table(
            [
                "mesh",
                "vertices",
                "proxy",
                "dimensions",
                "bake s",
                "step ms",
                "BFGS iterations (median / max)",
                "evaluations",
                "ms per evaluation",
                "map ms",
                "map back to back ms",
            ],
            rows,
        )
    )
    stresses = [(f"the {f['stress']['mesh']}", f["stress"])]
    if "stress" in f["proxy"]:
        stresses.append(
            (
                f"the dragon subdivided twice on its proxy of {f['proxy']['proxy_vertices']} vertices",
                f["proxy"]["stress"],
            )
        )
    for mesh, s in stresses:
        out += [
            "",
            f"Stress: {mesh} ({s['vertices']} vertices), {s['frames']} frames of random controller "
            f"moves (turns up to 150°, jumps of a third of its length), damping {s['damping']:g}: "
            f"{s['non_finite_frames']} non-finite frames, farthest vertex {s['farthest_vertex_diagonals']:.2f} "
            f"diagonals from the centre, step {s['step_ms_median']:.1f} ms median ({s['step_ms_max']:.0f} max), "
            f"{s['implicit_euler_substeps']} substeps retaken by implicit Euler. Then the controller still for "
            f"{s['still_frames']} frames: the energy went from {s['energy_at_stop']:.4g} to "
            f"{s['energy_at_end']:.4g}, its largest increase from one frame to the next "
            f"{s['largest_energy_increase_still']:.3g}; the mesh ended {s['settled_distance_diagonals']:.2g} "
            f"diagonals from ReducedSolver's pose ({'converged' if s['pose_converged'] else 'NOT converged'}).",
        ]
    out.append("")
    t = f["tolerance"]
    out += [
        f"BFGS's stopping tolerance on the {t['mesh']} ({t['vertices']} vertices, the demo's motion, {t['frames']} "
        f"frames) against a solve to {t['reference_tolerance']:g}: the largest distance of a frame, in diagonals "
        "(the map's own precision is 3e-5), and the iterations a frame.",
        "",
    ]
    out.append(
        table(
            [
                "tolerance",
                "largest distance",
                "iterations (median)",
                "while turning",
                "last 24 frames",
            ],
            [
                [
                    f"{r['tolerance']:g}",
                    f"{r['largest_distance_diagonals']:.2g}",
                    f"{r['iterations_median']:g}",
                    f"{r['iterations_moving']:.1f}",
                    f"{r['iterations_still']:.1f}",
                ]
                for r in t["rows"]
            ],
        )
    )
    out += ["", provenance(result)]
    return "\n".join(out)


def section_rig(result):
    p, f = result["parameters"], result["figures"]
    plain = f["without_rig"]
    rows = [
        [
            bones,
            f"{r['construct_s']:.2f}",
            f"{r['step_ms']:.2f} ({r['step_ms_p95']:.2f})",
            f"{r['still_step_ms']:.3f}",
            f"{r['map_ms']:.2f}",
        ]
        for bones, r in f["bones"].items()
    ]
    out = [
        "## Secondary motion on a rig",
        "",
        f"`mdc.Simulation(..., rig=W)`, the {f['mesh']} ({f['vertices']} vertices, {f['dimension']} "
        f"dimensions) on chains of bones, {p['frames']} frames. Per frame, medians: the step with the rig "
        "moving (95th percentile), the step with it still at rest, and the map to the fine mesh. Without a "
        f"rig: made in {plain['construct_s']:.2f} s, a still step {plain['step_ms']:.3f} ms.",
        "",
        table(["bones", "made in (s)", "step, moving (ms)", "step, still (ms)", "map (ms)"], rows),
        "",
        provenance(result),
    ]
    return "\n".join(out)


def section_shape_space(result):
    p, f = result["parameters"], result["figures"]
    rows = [
        [
            r["mesh"],
            f"{r['vertices']:,}"
            + (f" ({r['basis_vertices']:,})" if r["basis_vertices"] != r["vertices"] else ""),
            r["dimension"],
            f"{r['basis_bake_s']:.2f}",
            ", ".join(f"{k}: {s:.2f}" for k, s in r["space_bake_s"].items()),
            f"{r['blend_ms_median']:.1f} ({r['blend_ms_min']:.1f})",
            f"{r['solve_ms_median']:.1f}",
            f"{r['map_ms_median']:.1f}",
            f"{r['other_ms_median']:.2f}",
            f"{r['iterations_median']:g} / {r['iterations_max']}",
            f"{r['evaluation_ms_median']:.3f}",
            f"{r['converged']}/{p['blends']}",
        ]
        for r in f.values()
    ]
    targets = [
        f"- blend at {f[name]['vertices']:,} vertices ≤ {target:g} ms: **{f[name]['blend_ms_median']:.1f} ms** — "
        f"{'met' if f[name]['blend_ms_median'] <= target else 'NOT met'}"
        for name, target in shape_space.TARGETS.items()
        if name in f
    ]
    if "res2" in f:
        r = f["res2"]
        bake = r["space_bake_s"]["8"]
        targets.append(
            f"- space bake for 8 keys at {r['vertices']:,} vertices ≤ the basis bake's {r['basis_bake_s']:.1f} s: "
            f"**{bake:.1f} s** — {'met' if bake <= r['basis_bake_s'] else 'NOT met'}"
        )
    out = [
        "## Shape blending (issue 52)",
        "",
        f"`mdc.ShapeSpace` of smooth keys of the dragon (and of it subdivided twice, on a proxy: its vertices "
        f"in parentheses), {p['blends']} blends of random weights of {p['keys']} keys: the basis's bake, the "
        "space's bake per key count (s), a blend with the map (ms; per weights the least of "
        f"{p.get('repeats', 1)} runs, then the median and least over the weights) and where it goes: the "
        "minimisation (BFGS), the map to the fine mesh (with the keys' residuals on a proxy), the rest (the "
        "rests' blend, the initial Hessian); BFGS's iterations (median / most) and one energy evaluation on "
        "the ghost with its reduced gradient (ms). The issue's targets: a blend at 100k with 8 keys in at "
        "most 4 ms, at 1.6M on a proxy in at most 16 ms; the space's bake for 8 keys at 100k within the "
        "basis bake's time.",
        "",
        table(
            [
                "mesh",
                "vertices",
                "dimension",
                "basis bake (s)",
                "space bake by keys (s)",
                "blend (ms)",
                "solve (ms)",
                "map (ms)",
                "rest (ms)",
                "iterations",
                "evaluation (ms)",
                "converged",
            ],
            rows,
        ),
        "",
        *targets,
        "",
        provenance(result),
    ]
    return "\n".join(out)


def section_shape_keys_blender(result):
    runs = result["figures"]["runs"]
    out = [
        "## Blend as Shapes in Blender (issue 52)",
        "",
        "`bench/shape_keys_blender.py` in bpy from the package index, the add-on installed from its extension "
        f"zip: the dragon (100k vertices; subdivided twice, 1.6M, on a proxy) with {runs[0]['keys']} shape keys "
        'made by formula (support.poses.smooth_keys), Blend as Shapes turned on with its operator ("bake": '
        "the space's bake, a basis baked first), then one key's value changed per update and the view layer "
        'updated, as moving a slider in the Shape Keys panel does. "linear" is that update with Blend as '
        "Shapes off (Blender's own mix); with it on, the update's whole time, and its parts: \"handlers\" the "
        "add-on's depsgraph handlers before and after Blender's evaluation (of it, in brackets, \"blend\": the "
        "core's blend with its map, ShapeSpace.stats), \"evaluate\" the rest, Blender's evaluation, of which "
        '"after" follows the add-on\'s last handler (a second evaluation, of a display written after the '
        "first). Each figure is the median over the updates of each update's least over "
        f"{runs[0]['blend']['rounds']} rounds of the same changes (each round from every key at 0). The "
        "issue's targets for the blend with its map: "
        + ", ".join(
            f"{ms:g} ms at {vertices:,} vertices"
            for vertices, ms in common.FRAME_TARGETS_MS.items()
        )
        + ".",
        "",
    ]
    rows = []
    for run in runs:
        blend = run["blend"]
        target = common.FRAME_TARGETS_MS.get(run["vertices"])
        met = "" if target is None else (", met" if blend["blend_ms"] <= target else ", NOT met")
        rows.append(
            [
                run["blender"],
                f"{run['vertices']:,}",
                f"{run['dimension']}"
                + (f", proxy {run['proxy_vertices']:,}" if run["proxy_vertices"] else ""),
                f"{run['bake_seconds']:.1f}",
                f"{run['linear']['update_ms']:.1f}",
                f"{blend['update_ms']:.1f}",
                f"{blend['handlers_ms']:.1f} ({blend['blend_ms']:.1f}{met}) + {blend['evaluate_ms']:.1f} "
                f"({blend['after_ms']:.2f})",
                "{:.1f} / {:.1f}".format(*loads) if (loads := load_range(run)) else "",
            ]
        )
    out += [
        table(
            [
                "Blender",
                "vertices",
                "dims",
                "bake s",
                "linear update ms",
                "blend update ms",
                "handlers (blend) + evaluate (after) ms",
                "load before / after",
            ],
            rows,
        ),
        "",
        provenance(result),
    ]
    return "\n".join(out)


def section_inbetween(result):
    p, f = result["parameters"], result["figures"]

    def row(label, r):
        return [
            label,
            r["dimension"],
            r["frames"],
            r["nodes"],
            f"{r['solve_s']:.2f}",
            r["iterations"],
            r["evaluations"],
            "yes" if r["converged"] else "no",
            f"{r['control']:.3g} / {r['initial_control']:.3g}",
            f"{r['positions_ms']['median']:.2f}",
        ]

    header = [
        "run",
        "dims",
        "frames",
        "substeps solved",
        "solve (s)",
        "iterations",
        "ghost gradients",
        "converged",
        "control / start's",
        "a frame's positions (ms)",
    ]
    mesh = f"{f['mesh']} ({f['vertices']} vertices)"
    rows = [row(f"{mesh}, 5 keys", f["cost"])]
    rows += [row(f"{mesh}, frames", r) for r in f["frames"]]
    small = f["dimensions"]
    rows += [
        row(f"{small['mesh']} ({small['vertices']} vertices), dimensions", r) for r in small["runs"]
    ]
    rep = f["reproduction"]
    worst = max(k["inbetween"] - k["posing"] for k in rep["key_errors"])
    out = [
        "## Physics in-betweens (issue 51)",
        "",
        f"`mdc.Inbetween` through {p['keys']} keys of the dragon's head (the tail keyed at rest), the "
        "paper's 67 dimensions: the solve and a frame's positions (median inside the keys) against the "
        "issue's 1 s and 2 ms, the solve against frames and dimensions.",
        "",
        table(header, rows),
        "",
        f"Reproduction: the dragon released from posing's minimum with the head turned 10°, "
        f"{rep['frames']} frames of Simulation's free motion (largest excursion "
        f"{100 * rep['excursion']:.2f}% of the diagonal), keys every {rep['key_every']} frames at "
        f"each handle's rigid fit: the in-betweens' vertices within {100 * rep['error']:.4f}% of the "
        f"diagonal of Simulation's over every frame ({100 * rep['error_first_frame']:.4f}% at the "
        f"first, where the start differs: posing's minimum at the fits), converged "
        f"{'yes' if rep['converged'] else 'no'} in {rep['iterations']} iterations; each key's fit "
        f"error minus posing's at the same transforms at most {100 * worst:.5f}% of the diagonal.",
        "",
        provenance(result),
    ]
    return "\n".join(out)


SECTIONS = (
    ("table1", section_table1),
    ("accuracy", section_accuracy),
    ("renders", section_renders),
    ("convergence", section_convergence),
    ("taylor", section_taylor),
    ("blender", section_blender),
    ("bpy_pose", section_bpy_pose),
    ("viewport_frames", section_viewport_frames),
    ("native", section_native),
    ("bake_limit", section_bake_limit),
    ("bake_busy", section_bake_busy),
    ("raw_scan", section_raw_scan),
    ("multires", section_multires),
    ("strong_poses", section_strong_poses),
    ("refine", section_refine),
    ("region", section_region),
    ("dynamics", section_dynamics),
    ("rig", section_rig),
    ("shape_space", section_shape_space),
    ("inbetween", section_inbetween),
    ("playback", section_playback),
    ("shape_keys_blender", section_shape_keys_blender),
)


def write():
    results = {name: load(name) for name, _ in SECTIONS}
    total = sum(r["seconds"] for r in results.values() if r)
    parts = [
        "# Benchmarks: how fast and how good, against the paper and the full solve",
        "",
        "Generated by `make bench` (bench/run.py, then bench/report.py) from the JSON in bench/results/ (one "
        "file per experiment: machine, commit, command, every parameter, the figures). Regenerate this page "
        "alone with `PYTHONPATH=python_addon /usr/bin/python3 bench/report.py`; run one experiment with "
        '`bench/run.py --only NAME`. The paper: Hildebrandt et al., "Interactive Surface Modeling using Modal '
        'Analysis", ACM TOG 30(5), 2011. Each section ends with the machine it ran on '
        "and the load average at its end; where that is above the machine's cores, other work shared them, the "
        "timings are pessimistic and the section says so.",
        "",
        f"Sum of the experiments' wall times in this run: {total / 60:.1f} min.",
        "",
    ]
    missing = []
    for name, section in SECTIONS:
        if results[name]:
            parts += [section(results[name]), ""]
        elif name != "renders":
            missing.append(name)
    parts += (
        [
            "## What is not here",
            "",
            "- Only one row of the paper's Table 1 is compared (its dragon, the figures DESIGN.md quotes); the other "
            "rows have no paper counterpart here.",
            "- Table 1's ghosts other than 1k are rebuilt on the baked basis (`mdc.ghost_mesh` + "
            "`mdc.restrict_to_ghost`, from the stored float32 vectors) rather than baked anew, so their bake time is "
            "the 1k bake's.",
        ]
        + table1_zero_modes_note(results["table1"])
        + [""]
    )
    if missing:
        parts += ["Not in this run (no results file): " + ", ".join(missing) + ".", ""]
    path = DOCS / "benchmarks.md"
    path.write_text("\n".join(parts))
    return path


if __name__ == "__main__":
    print(write())
