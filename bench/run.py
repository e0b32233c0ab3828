"""`make bench`: every benchmark experiment, then the report docs/benchmarks.md.

    PYTHONPATH=python_addon /usr/bin/python3 bench/run.py [--quick] [--only NAME ...] [--report-only]

Experiments (each writes bench/results/<name>.json: machine, commit, command, parameters, figures):
  native       the Google Benchmark binary (build/bench/modal_deform_bench): energies, ghost,
               CHOLMOD, modes, full solves (its bake, BFGS and positions benchmarks are left
               out: table1 measures them on the same dragon)
  table1       Table 1 analogue (bench/table1.py)
  accuracy     Fig. 5/12 analogue (bench/accuracy.py)
  convergence  Fig. 7 analogue (bench/convergence.py)
  taylor       Fig. 9 analogue (bench/taylor.py)
  bake_limit   the 100k-vertex dragon's bake at 67 and 130 dimensions, three fresh processes, against
               CHOLMOD's analysis and factorisation of the same matrix and issue 25's targets (issue 14's
               at 130) (bench/bake_limit.py)
  bake_busy    the 23k and 100k dragons' bakes quiet and beside one busy core (`yes`), in plain Python
               (as shipped, and with OpenMP's default spinning wait) and in bpy 4.5 and 5.3 on the
               extension zip (`make addon`), fresh processes, quiet and busy back to back
               (bench/bake_busy.py)
  raw_scan     a damaged, subdivided dragon of about 405k vertices baked in a fresh process: time
               and peak memory against issue 15's targets (bench/raw_scan.py)
  multires     the dragon subdivided twice (1.6M vertices) baked on a proxy: time, memory, stored
               size, update time and agreement with the dragon's own bake (bench/multires.py)
  strong_poses the 100k dragon under turns of 90/170 and bends of 90/180 degrees, and the 1.6M
               dragon on its proxy under end turns of 30/90/170 degrees against the 100k dragon's
               own bake and solve_full (bench/strong_poses.py)
  refine       the full solve from rest and Refine from the reduced pose on the 23k and 100k dragons and
               a raw-scan-like 23k dragon, turned by 30, 90, 170 degrees and bent (bench/refine.py)
  region       the head of the 100k dragon, and of it subdivided to 1.6M (on proxies), baked as a region
               against the whole mesh: time, stages, dimensions, and that nothing outside the region moves
               (bench/region.py)
  dynamics     secondary motion (issue 40): a free bar's period and decrement against the ones set, the
               step's cost per frame on the 23k and 100k dragons and the 1.6M one on a proxy, 1000 frames of
               fast random controllers, BFGS's tolerance (bench/dynamics.py)
  rig          secondary motion on a rig: the 100k dragon on chains of 3, 30 and 100 bones, the step's
               and the rig forces' cost per frame (bench/rig.py)
  shape_space  shape blending: the blend's and the space's bake time per key count on the 23k and 100k
               dragons, 8 smooth keys (bench/shape_space.py)
  inbetween    physics in-betweens (issue 51): the solve through 5 keys over 120 frames and a frame's
               positions on the 100k dragon at 67 dimensions, the solve against frames and
               dimensions, a free motion reproduced from its keys (bench/inbetween.py)
  blender      the add-on's pose update in headless Blender and Blender's Laplacian Deform
               (bench/blender_pose.py), in Debian's 3.4.1 app from the source tree
  bpy_pose     the pose update alone at 100k, 400k, 1.6M and 3.2M vertices in bpy 4.5 and 5.3 (.venv/bpy-<version>,
               made by `make bench`) with the add-on installed from its extension zip (`make addon`)
  viewport_frames  the frame while posing in a real viewport: Debian's 3.4.1 app under Xvfb (software
               OpenGL), the dragon at 100k and 1.6M vertices (bench/viewport_frames.py)
  playback     the per-frame cache and secondary motion (issue 40) in bpy 4.5 and 5.3 on the extension zips:
               per frame, a cached frame read back and a live simulation step with Blender's evaluation,
               at 100k vertices (and 1.6M on a proxy unless --quick); the cache's and the .blend's sizes
               for 250 frames of the 100k dragon against a shape key per frame and a PC2 file; the same
               dragons skinned by chains of 3, 30 and 100 bones with Follow Rig on (issue 50), the add-on's
               share of a played frame beside Blender's evaluation and the Armature modifier alone
               (bench/playback.py)
  shape_keys_blender  Blend as Shapes in bpy 4.5 and 5.3 on the extension zips: the 100k dragon with 8 keys
               made by formula, driven by changing key values; per update the add-on's handler, the core's
               blend with its map and Blender's evaluation, against Blender's linear mix of the same keys
               (and the dragon subdivided twice, 1.6M vertices on a proxy, unless --quick)
               (bench/shape_keys_blender.py)
  renders      Cycles renders of the accuracy experiment's bar and cylinder poses
               (blender_scripts/render_figures.py; needs accuracy's meshes from the same run)
--quick runs tiny sizes (the smoke test): results go to bench/results/tmp/, the report is not
written. The report alone is regenerated from the JSON with --report-only (or bench/report.py).
"""

import argparse
import importlib
import json
import pathlib
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import common  # noqa: E402
import report  # noqa: E402

PYTHON_EXPERIMENTS = (
    "table1",
    "accuracy",
    "convergence",
    "taylor",
    "bake_limit",
    "bake_busy",
    "raw_scan",
    "multires",
    "strong_poses",
    "refine",
    "region",
    "dynamics",
    "rig",
    "shape_space",
    "inbetween",
)
EXPERIMENTS = (
    ("native",)
    + PYTHON_EXPERIMENTS
    + ("blender", "bpy_pose", "viewport_frames", "playback", "shape_keys_blender", "renders")
)
NATIVE_IN_TABLE1 = "BM_Bake|BM_BfgsIteration|BM_Positions"
BLENDER = ["blender", "-b", "--factory-startup", "--python-exit-code", "1", "--python"]


def command(name):
    return (
        f"make bench  (alone: PYTHONPATH=python_addon /usr/bin/python3 bench/run.py --only {name})"
    )


def native(quick):
    binary = common.ROOT / "build" / "bench" / "modal_deform_bench"
    with tempfile.TemporaryDirectory() as folder:
        out = pathlib.Path(folder) / "native.json"
        # The dragon's bake, BFGS iterations and positions are measured by table1 at the same sizes.
        arguments = [
            str(binary),
            f"--benchmark_out={out}",
            "--benchmark_out_format=json",
            "--benchmark_filter=BM_Shells|BM_LumpedMass"
            if quick
            else f"--benchmark_filter=-{NATIVE_IN_TABLE1}",
        ]
        subprocess.run(arguments, check=True)
        raw = json.loads(out.read_text())
    return {
        "binary": str(binary.relative_to(common.ROOT)),
        "filter": arguments[3:],
        "context": raw["context"],
    }, {"benchmarks": raw["benchmarks"]}


def blender(quick):
    pose = common.ROOT / "bench" / "blender_pose.py"
    with tempfile.TemporaryDirectory() as folder:
        out = pathlib.Path(folder) / "blender_pose.json"
        extra = ["--updates", "3", "--quick"] if quick else []
        # The comparison on the accuracy experiment's meshes when they are there (make bench runs it first).
        shapes = ["--shapes", str(common.MESHES)] if common.MESHES.is_dir() else []
        subprocess.run(
            BLENDER + [str(pose), "--", "--output", str(out), *shapes, *extra],
            check=True,
            cwd=common.ROOT,
        )
        raw = json.loads(out.read_text())
        if (
            not quick
        ):  # the dragon subdivided twice (1.6M vertices), baked on a proxy: pose updates only
            dense = pathlib.Path(folder) / "blender_dense.json"
            subprocess.run(
                BLENDER
                + [str(pose), "--", "--output", str(dense), "--subdivide", "2", "--updates", "15"],
                check=True,
                cwd=common.ROOT,
            )
            raw["dense"] = json.loads(dense.read_text())
    return raw.pop("parameters"), raw


#: The bpy_pose experiment's meshes: blender_pose.py's arguments for the dragon (100k vertices),
#: subdivided once (400k), twice (1.6M), and twice with as many edges split as it has vertices
#: (3.2M; the process peaks at about 6 GB, the bake's).
DENSE_DRAGONS = (
    ["--subdivide", "0"],
    ["--subdivide", "1"],
    ["--subdivide", "2"],
    ["--subdivide", "2", "--double"],
)


def bpy_pose(quick):
    """The installed extension alone, in the Blenders artists run: the dragon at each of
    DENSE_DRAGONS, all but the first baked on a proxy."""
    runs = []
    sizes = DENSE_DRAGONS[:1] if quick else DENSE_DRAGONS
    with tempfile.TemporaryDirectory() as folder:
        for version in common.BPY_VERSIONS:
            for i, size in enumerate(sizes):
                out = pathlib.Path(folder) / f"bpy-{version}-{i}.json"
                common.in_bpy(
                    version,
                    common.ROOT / "bench" / "blender_pose.py",
                    [
                        "--output",
                        str(out),
                        "--pose-only",
                        *size,
                        "--updates",
                        "3" if quick else "15",
                        *(["--quick"] if quick else []),
                    ],
                    folder,
                )
                runs.append(json.loads(out.read_text()))
    return {"blenders": common.BPY_VERSIONS, "sizes": sizes}, {"runs": runs}


def viewport_frames(quick):
    """The viewport's frame while posing, at 100k and 1.6M vertices (quick: 100k on a small basis)."""
    runs = []
    sizes = (
        [["--modes", "8", "--derivatives", "8", "--proxy-above", "50000", "--proxy", "10000"]]
        if quick
        else [["--subdivide", "0"], ["--subdivide", "2"]]
    )
    with tempfile.TemporaryDirectory() as folder:
        for i, size in enumerate(sizes):
            out = pathlib.Path(folder) / f"frames-{i}.json"
            subprocess.run(
                [
                    "xvfb-run",
                    "-a",
                    "-s",
                    "-screen 0 1280x800x24",
                    "blender",
                    "--factory-startup",
                    "--python",
                    str(common.ROOT / "bench" / "viewport_frames.py"),
                    "--",
                    str(out),
                    "--updates",
                    "2" if quick else "3",
                    *size,
                ],
                check=True,
                cwd=common.ROOT,
            )
            run = json.loads(out.read_text())
            if not run["ok"]:
                raise RuntimeError("\n".join(run["log"]))
            runs.append(run)
    return {"sizes": sizes, "updates": 2 if quick else 3}, {"runs": runs}


def playback(quick):
    """bench/playback.py in each of common.BPY_VERSIONS: the 100k dragon with the sizes, then (not
    quick) the dragon subdivided twice (1.6M vertices, on a proxy) for the per-frame figures."""
    runs = []
    sizes = [[]] if quick else [[], ["--subdivide", "2", "--no-sizes"]]
    with tempfile.TemporaryDirectory() as folder:
        for version in common.BPY_VERSIONS:
            for i, size in enumerate(sizes):
                out = pathlib.Path(folder) / f"playback-{version}-{i}.json"
                common.in_bpy(
                    version,
                    common.ROOT / "bench" / "playback.py",
                    ["--output", str(out), *size, *(["--quick"] if quick else [])],
                    folder,
                )
                runs.append(json.loads(out.read_text()))
    return {"blenders": common.BPY_VERSIONS, "sizes": sizes}, {"runs": runs}


def shape_keys_blender(quick):
    """bench/shape_keys_blender.py in each of common.BPY_VERSIONS: the 100k dragon, then (not quick)
    the dragon subdivided twice (1.6M vertices, on a proxy)."""
    runs = []
    sizes = [[]] if quick else [[], ["--subdivide", "2", "--updates", "10"]]
    with tempfile.TemporaryDirectory() as folder:
        for version in common.BPY_VERSIONS:
            for i, size in enumerate(sizes):
                out = pathlib.Path(folder) / f"shape-keys-{version}-{i}.json"
                common.in_bpy(
                    version,
                    common.ROOT / "bench" / "shape_keys_blender.py",
                    ["--output", str(out), *size, *(["--quick"] if quick else [])],
                    folder,
                )
                runs.append(json.loads(out.read_text()))
    return {"blenders": common.BPY_VERSIONS, "sizes": sizes}, {"runs": runs}


def renders(quick):
    folder = common.RESULTS / "renders" if quick else common.ROOT / "docs" / "figures"
    arguments = ["--meshes", str(common.MESHES), "--output", str(folder)] + (
        ["--samples", "4", "--width", "160"] if quick else []
    )
    subprocess.run(
        BLENDER + [str(common.ROOT / "blender_scripts" / "render_figures.py"), "--", *arguments],
        check=True,
        cwd=common.ROOT,
    )
    images = sorted(str(p.relative_to(common.ROOT)) for p in folder.glob("render_*.png"))
    return {"meshes": "accuracy experiment, bench/results/tmp/meshes", "arguments": arguments}, {
        "images": images
    }


def main():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--quick", action="store_true", help="tiny sizes, results in bench/results/tmp/, no report"
    )
    parser.add_argument("--only", nargs="+", choices=EXPERIMENTS, help="run only these experiments")
    parser.add_argument(
        "--report-only", action="store_true", help="write docs/benchmarks.md from the JSON and stop"
    )
    args = parser.parse_args()
    if args.quick:
        common.RESULTS = common.RESULTS / "tmp"
    if not args.report_only:
        start_all = time.perf_counter()
        for name in args.only or EXPERIMENTS:
            print(f"== {name}", flush=True)
            start = time.perf_counter()
            if name in PYTHON_EXPERIMENTS:
                parameters, figures = importlib.import_module(name).run(quick=args.quick)
            else:
                parameters, figures = globals()[name](args.quick)
            path = common.write(
                name, command(name), parameters, figures, time.perf_counter() - start
            )
            print(
                f"   {time.perf_counter() - start:.0f} s -> {path.relative_to(common.ROOT)}",
                flush=True,
            )
        print(f"all experiments: {time.perf_counter() - start_all:.0f} s", flush=True)
    if not args.quick:
        print(f"wrote {report.write().relative_to(common.ROOT)}")


if __name__ == "__main__":
    main()
