"""`make demo`'s script (blender_scripts/demo.py), small: it runs to its end in the Blender app that
`make demo` runs, writes its .blend and pictures, Suzanne's ears overshoot and settle, her
ears blended as shapes at 0.5 keep more of their length than Blender's mix, and her ear tip with
In-betweens is flung past the last key's pose, where Blender's interpolation stops, and settles
there."""

import re

import pytest
from conftest import BLENDER_PYTHON, ROOT


@pytest.mark.skipif(BLENDER_PYTHON is not None, reason="make demo runs the Blender app")
def test_demo_runs_the_ears_overshoot_and_settle_and_blend_as_shapes_and_in_between(
    run_blender, tmp_path
):
    output = tmp_path / "out"
    result = run_blender(
        ROOT / "blender_scripts" / "demo.py",
        "--output",
        output,
        "--subdivisions",
        1,
        "--samples",
        1,
        "--width",
        120,
        "--dynamics-subdivisions",
        1,
        "--shapes-subdivisions",
        1,
        "--inbetweens-subdivisions",
        1,
    )
    for name in (
        "demo.blend",
        "demo.png",
        "demo_dynamics.png",
        "demo_rig.png",
        "demo_shapes.png",
        "demo_inbetweens.png",
    ):
        assert (output / name).stat().st_size > 0, name
    found = re.search(
        r"the ears' way from rest \(0\) to where they settle \(1\), frames 1 to \d+: ([\d. ]+)",
        result.stdout,
    )
    assert found, result.stdout[-2000:]
    way = [float(value) for value in found.group(1).split()]
    assert max(way) > 1.03, f"the ears do not overshoot: {way}"
    assert abs(way[-1] - 1) < 0.01, f"the ears do not settle: {way}"
    found = re.search(
        r"the left ear from its hinge to its tip: rest ([\d.]+), key ([\d.]+), Blender's mix at "
        r"0.5 ([\d.]+), Blend as Shapes at 0.5 ([\d.]+)",
        result.stdout,
    )
    assert found, result.stdout[-2000:]
    rest, key, mix, blend = (float(value) for value in found.groups())
    assert abs(key - rest) < 1e-3 * rest, (rest, key)
    assert mix < 0.5 * rest and blend > 0.7 * rest, (rest, mix, blend)
    found = re.search(
        r"the ear tip rises ([\d.]+) \([\d.]+% of her width\) above where Blender's interpolation "
        r"holds it and settles within ([\d.]+) of it",
        result.stdout,
    )
    assert found, result.stdout[-2000:]
    rises, settled = (float(value) for value in found.groups())
    assert rises > 0.05 and settled < 0.02, (rises, settled)
