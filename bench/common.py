"""What every benchmark experiment shares: the machine and commit it ran on, timing, and its
results file bench/results/<experiment>.json (parameters and figures, read by bench/report.py)."""

import json
import os
import pathlib
import platform
import shutil
import subprocess
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python_addon"))
sys.path.insert(0, str(ROOT / "tests"))  # the test-support package (subdivision, raw scans, poses)
import package  # noqa: E402 (which extension zip serves which Python)

RESULTS = ROOT / "bench" / "results"
#: Posed meshes passed from one experiment to the next (accuracy -> blender -> renders); not committed.
MESHES = ROOT / "bench" / "results" / "tmp" / "meshes"
#: The Blenders the bpy experiments run in, as Python modules (.venv/bpy-<version>, made by `make bench`).
BPY_VERSIONS = ("4.5", "5.3")
#: A frame's work with Blender's evaluation in at most this many ms, by the vertex count of the dragon
#: it is measured on (100k, and subdivided twice, 1.6M): the pose update's target (issue 23) and a
#: live playback step's (issue 40).
FRAME_TARGETS_MS = {100250: 4.0, 1606964: 16.0}


def machine():
    """CPU model, cores, memory and uname of this machine."""
    cpu = next(
        (
            line.split(":", 1)[1].strip()
            for line in open("/proc/cpuinfo")
            if line.startswith("model name")
        ),
        platform.processor(),
    )
    memory_kb = next(
        int(line.split()[1]) for line in open("/proc/meminfo") if line.startswith("MemTotal")
    )
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "memory_gb": round(memory_kb / 2**20, 1),
        "uname": " ".join(platform.uname()),
        "load_average": os.getloadavg(),
    }


def commit():
    """The checked-out commit, with "+dirty" when the work tree differs from it (outside the
    benchmark's own outputs, which a run rewrites as it goes)."""

    def git(*args):
        return subprocess.run(
            ["git", *args], cwd=ROOT, capture_output=True, text=True
        ).stdout.strip()

    dirty = git(
        "status",
        "--porcelain",
        "--untracked-files=no",
        "--",
        ".",
        ":!bench/results",
        ":!docs/benchmarks.md",
        ":!docs/figures",
    )
    return git("rev-parse", "HEAD") + ("+dirty" if dirty else "")


def write(experiment, command, parameters, figures, seconds):
    """bench/results/<experiment>.json: machine, commit, the command that made it, parameters,
    figures and the experiment's wall time."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    record = {
        "experiment": experiment,
        "command": command,
        "machine": machine(),
        "commit": commit(),
        "date": time.strftime("%Y-%m-%d %H:%M:%S %Z"),
        "seconds": round(seconds, 1),
        "parameters": parameters,
        "figures": figures,
    }
    path = RESULTS / f"{experiment}.json"
    path.write_text(json.dumps(record, indent=1, default=_plain) + "\n")
    return path


def _plain(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def median_ms(function, repeats):
    """Median wall time of `repeats` calls of function(), milliseconds."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(1e3 * (time.perf_counter() - start))
    return float(np.median(times))


def rms_error(X, reference):
    """Vertex RMS distance between X and reference (n, 3), relative to the reference's bounding-box
    diagonal."""
    X, reference = np.asarray(X, np.float64), np.asarray(reference, np.float64)
    diagonal = np.linalg.norm(np.ptp(reference, axis=0))
    return float(np.sqrt(np.mean(np.sum((X - reference) ** 2, axis=1))) / diagonal)


def json_from_fresh_process(code):
    """Run the Python `code` in a fresh process of this interpreter (from the project's root) and
    return the JSON object its last line prints, with "ok": True unless it says otherwise; when it
    fails, {"ok": False, "error": [its last line of standard error]}."""
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    if result.returncode != 0:
        return {"ok": False, "error": result.stderr.strip().splitlines()[-1:]}
    return {"ok": True} | json.loads(result.stdout.strip().splitlines()[-1])


def in_bpy(version, script, arguments, folder, **run):
    """Run `script` in bpy `version` (.venv/bpy-<version>) as tests/blender/bpy_session.py runs the
    tests: the extension zip of its Python installed by Blender's installer into a fresh user
    folder under `folder`, neither the source tree's add-on nor the machine's libraries in sight.
    `run`: subprocess.run's further arguments (environment variables in `env`, added to this
    process's); returns what it returns."""
    python = ROOT / ".venv" / f"bpy-{version}" / "bin" / "python"
    tag = subprocess.run(
        [str(python), "-c", "import sys; print('%d.%d' % sys.version_info[:2])"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    extension = next(e for e in package.EXTENSIONS if e.python == tag)
    user = pathlib.Path(folder) / f"user-{version}"
    environment = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    environment.update(run.pop("env", {}), LD_LIBRARY_PATH="", BLENDER_USER_RESOURCES=str(user))
    try:
        return subprocess.run(
            [
                str(python),
                str(ROOT / "tests" / "blender" / "bpy_session.py"),
                "--extension",
                str(ROOT / "dist" / package.extension_zip_name(extension)),
                str(script),
                "--",
                *arguments,
            ],
            check=True,
            cwd=ROOT,
            env=environment,
            **run,
        )
    finally:
        shutil.rmtree(user, ignore_errors=True)
