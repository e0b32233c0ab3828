"""Point-cache files that Blender's Mesh Cache modifier reads (and other packages: 3ds Max's Point
Cache, LightWave's MDD), written a frame at a time so a long animation of a dense mesh never sits
in memory whole. No bpy: frames in, file out.

PC2 (little-endian): the 12-byte signature "POINTCACHE2\\0", int32 version 1, int32 points,
float32 start frame, float32 sampling (frames per sample), int32 samples; then per sample the
points' float32 x y z.
MDD (big-endian): int32 frames, int32 points, float32 time of each frame (seconds); then per frame
the points' float32 x y z.
"""

import struct

import numpy as np

FORMATS = ("PC2", "MDD")


def write(path, fmt, num_points, frames, fps, positions):
    """Write `positions(frame)` ((num_points, 3) float32, called once per frame in order) for each
    of `frames` (consecutive ints) to `path` in format `fmt` ("PC2" or "MDD")."""
    frames = list(frames)
    if fmt not in FORMATS:
        raise ValueError(f"format: expected one of {FORMATS}, got {fmt!r}")
    if not frames:
        raise ValueError("frames: no frame to write")
    if frames != list(range(frames[0], frames[0] + len(frames))):
        raise ValueError("frames: expected consecutive frames")
    order = "<" if fmt == "PC2" else ">"
    with open(path, "wb") as out:
        if fmt == "PC2":
            out.write(
                struct.pack(
                    "<12siiffi", b"POINTCACHE2\0", 1, num_points, float(frames[0]), 1.0, len(frames)
                )
            )
        else:
            out.write(struct.pack(">ii", len(frames), num_points))
            out.write(np.array([f / fps for f in frames], order + "f4").tobytes())
        for frame in frames:
            co = np.asarray(positions(frame), np.float32)
            if co.shape != (num_points, 3):
                raise ValueError(
                    f"frame {frame}: expected positions of shape ({num_points}, 3), got {co.shape}"
                )
            out.write(co.astype(order + "f4", copy=False).tobytes())
