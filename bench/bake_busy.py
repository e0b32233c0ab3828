"""The bake beside a busy core (issue 25, "Busy-proof"): the dragon at 23k (dragon_vrip_res3) and
100k vertices (dragon_vrip_res2) baked at 15 modes + 52 derivatives with a 1k ghost by
bench/bake_once.py, each bake in a fresh process, quiet and with one `yes` process beside it: in plain
Python as the add-on ships (OpenMP's passive wait, OpenBLAS under CHOLMOD on the usable cores less
one) and, at 23k, with GCC OpenMP's default spinning wait (GOMP_SPINCOUNT=300000, which the core's
import then leaves alone); and inside bpy 4.5 and 5.3 on the installed extension, beside Blender's
own NumPy and its OpenBLAS. `yes` runs in a session of its own, as another application does: Linux
shares the cores between sessions first (autogroups), so a `yes` in the bake's session would take half
of what the session gets, which on a machine loaded by other sessions is far less than the core it
leaves free on an idle one (the 23k bake then took 1.9 to 2.7 times as long at load 10 to 11, against
1.09 on an idle machine). The machine is shared, so "quiet" means nothing of ours beside the bake:
each bake runs quiet, on one core and busy back to back (the order reverses by round), the ratios are
taken bake by bake and the load average before each is kept; medians over the rounds.

Each bake also runs quiet on one core (its affinity set to the first core it may use, so the core's
OpenMP and OpenBLAS see one core): while `yes` runs, the sharing between sessions leaves the bake about
one core's worth of time, so the busy bake is at best about as fast as this one. Busy / one core is what
the sharing costs beyond losing the core (threads that spin or wait for a descheduled partner); busy /
quiet is then about one core / quiet at least, the speed-up the second core gives the quiet bake.

Inside each Python, one bake of the 5k dragon first checks the threads: the OpenMP settings the
core's runtime reports (OMP_DISPLAY_ENV) and the thread counts of every OpenBLAS in the process
during the bake (bake_once.py --threads).
"""

import json
import os
import re
import statistics
import subprocess
import sys
import tempfile

import common
from common import ROOT

MESHES = {"23k": "dragon_vrip_res3.ply.gz", "100k": "dragon_vrip_res2.ply.gz"}
#: The 5k dragon: the thread checks, and the smoke test's only bake.
CHECK_MESH = "dragon_vrip_res4.ply.gz"
ROUNDS = 3
#: The Pythons the bake runs in: this one (the source tree's core) and each bpy.
PYTHONS = ("python",) + tuple(f"bpy {version}" for version in common.BPY_VERSIONS)
#: The bake's environment on top of this process's, by variant.
VARIANTS = {"shipped": {}, "spinning_openmp": {"GOMP_SPINCOUNT": "300000"}}
CONDITIONS = ("quiet", "one_core", "busy")
SCRIPT = ROOT / "bench" / "bake_once.py"


def bakes_of(meshes):
    """(python, mesh size, variant) of each bake: every Python as shipped at every size, and plain Python
    with OpenMP spinning at the first size."""
    first = next(iter(meshes))
    return tuple(
        (python, size, variant)
        for python in PYTHONS
        for size in meshes
        for variant in VARIANTS
        if variant == "shipped" or (python == "python" and size == first)
    )


def name(bake):
    return " ".join(bake)


def on_one_core():
    """Pins the calling process (a child about to start) to the first core it may use."""
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})


def in_fresh_process(python, arguments, environment, folder, one_core=False):
    """bake_once.py's JSON and its standard error, in plain Python or in bpy `python`; with `one_core`,
    on the first core only."""
    pin = {"preexec_fn": on_one_core} if one_core else {}
    if python == "python":
        inherited = {
            k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")
        }
        run = subprocess.run(
            [sys.executable, "-W", "ignore", str(SCRIPT), *arguments],
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=True,
            env=inherited | environment,
            **pin,
        )
    else:
        run = common.in_bpy(
            python.split()[1],
            SCRIPT,
            arguments,
            folder,
            env=environment,
            capture_output=True,
            text=True,
            **pin,
        )
    return json.loads(run.stdout.strip().splitlines()[-1]), run.stderr


def thread_check(python, folder):
    """What the core's OpenMP runtime reports of its wait, and the OpenBLAS thread counts seen."""
    result, stderr = in_fresh_process(
        python, [CHECK_MESH, "--threads"], {"OMP_DISPLAY_ENV": "verbose"}, folder
    )
    return {
        "omp_wait_policy": re.findall(r"OMP_WAIT_POLICY = '(\w+)'", stderr),
        "gomp_spincount": re.findall(r"GOMP_SPINCOUNT = '(\d+)'", stderr),
        "openblas_threads_seen": result["openblas_threads_seen"],
    }


def bake_triple(bake, mesh, reverse, folder):
    """{condition: seconds, "stages": {condition: {stage: seconds}}} of the bake quiet, quiet on one core
    and beside one `yes`, back to back (in reverse order when `reverse`)."""
    python, _, variant = bake
    timings = {"stages": {}}
    for condition in CONDITIONS[::-1] if reverse else CONDITIONS:
        busy = (
            subprocess.Popen(["yes"], stdout=subprocess.DEVNULL, start_new_session=True)
            if condition == "busy"
            else None
        )
        try:
            result = in_fresh_process(
                python, [mesh], VARIANTS[variant], folder, one_core=condition == "one_core"
            )[0]
        finally:
            if busy is not None:
                busy.kill()
                busy.wait()
        timings[condition] = result["seconds"]
        timings["stages"][condition] = result["stages"]
    return timings


def summary(bakes, rounds):
    """Medians over the rounds per bake: seconds, busy / quiet and busy / one core bake by bake, busy / quiet
    also per stage; shipped / spinning."""

    def median(values):
        return statistics.median(list(values))

    out = {}
    for bake in bakes:
        triples = [r[name(bake)] for r in rounds]
        out[name(bake)] = {
            **{c: median(p[c] for p in triples) for c in CONDITIONS},
            **{
                f"busy_over_{c}": median(p["busy"] / p[c] for p in triples)
                for c in ("quiet", "one_core")
            },
            "stages_busy_over_quiet": {
                stage: median(
                    p["stages"]["busy"][stage] / p["stages"]["quiet"][stage] for p in triples
                )
                for stage in triples[0]["stages"]["quiet"]
                if triples[0]["stages"]["quiet"][stage] > 0
            },
            "load_before": [
                min(p["load_before"] for p in triples),
                max(p["load_before"] for p in triples),
            ],
        }
    shipped, spinning = (name(b) for b in bakes if b[0] == "python" and b[1] == bakes[0][1])
    out["shipped_over_spinning"] = {
        c: median(r[shipped][c] / r[spinning][c] for r in rounds) for c in CONDITIONS
    }
    return out


def run(quick=False):
    meshes = {"5k": CHECK_MESH} if quick else MESHES
    bakes = bakes_of(meshes)
    rounds = []
    with tempfile.TemporaryDirectory() as folder:
        checks = {python: thread_check(python, folder) for python in PYTHONS}
        for python, check in checks.items():
            print(
                f"   {python}: OpenMP wait {check['omp_wait_policy']}, spin count {check['gomp_spincount']}; "
                f"OpenBLAS threads seen {check['openblas_threads_seen']}",
                flush=True,
            )
        for index in range(1 if quick else ROUNDS):
            round_ = {}
            for bake in bakes:
                load = os.getloadavg()[0]
                round_[name(bake)] = bake_triple(bake, meshes[bake[1]], index % 2 == 1, folder) | {
                    "load_before": load
                }
                p = round_[name(bake)]
                print(
                    f"   round {index + 1}, {name(bake)}: quiet {p['quiet']:.1f} s, one core {p['one_core']:.1f} s, "
                    f"busy {p['busy']:.1f} s, busy / quiet {p['busy'] / p['quiet']:.2f}, busy / one core "
                    f"{p['busy'] / p['one_core']:.2f} (load {load:.1f})",
                    flush=True,
                )
            rounds.append(round_)
    result = summary(bakes, rounds)
    parameters = {
        "meshes": meshes,
        "check_mesh": CHECK_MESH,
        "modes": 15,
        "derivatives": 52,
        "ghost": 1000,
        "rounds": len(rounds),
        "bakes": [list(b) for b in bakes],
        "variants": VARIANTS,
        "busy": "one `yes` process beside the bake",
        "one_core": "quiet, the affinity set to one core",
        "load_before": os.getloadavg(),
    }
    return parameters, {"checks": checks, "rounds": rounds, "summary": result}
