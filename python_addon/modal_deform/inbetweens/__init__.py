"""Dynamics > In-betweens: the motion through the controllers' keyed poses that needs the least
force under the dynamics (core.Inbetween), solved in the background and played through the
per-frame cache (keys.py reads the keys, motion.py solves and shows, operators.py drives it)."""
