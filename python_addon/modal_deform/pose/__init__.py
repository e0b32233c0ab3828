"""Posing: the posing session of an object (posing), shared with playback; the operators (Pose,
Solve, Refine, Reset), Refine's job on a thread (refine), where the interactive pose shows the pose
while it runs (displays), and the repair of meshes written mid-pose (recovery)."""
