"""The interactive pose: its operators (Pose, Solve, Refine, Reset), where it shows the pose while it
runs (displays), and the repair of meshes written mid-pose (recovery). The posing session they share
with playback and the jobs is ../posing.py."""
