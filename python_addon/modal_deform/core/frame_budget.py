"""The solver's share of a frame while posing, adapted to what the rest of each update takes.

An update of the interactive pose is: controllers → solve → positions written → Blender evaluates
and draws. At 60 frames a second all of it has 1000/60 ms; the solve is the only part that can
give way (BFGS keeps q and its inverse Hessian from update to update and goes on converging once
the controllers stop, so fewer iterations per update delay the converged pose, never change it).
FrameBudget gives the solve what the rest of the recent updates left of the frame, between a
floor (one iteration always runs) and the artist's Milliseconds per Update.
"""

import numpy as np

#: 60 frames a second.
FRAME_MS = 1000.0 / 60.0
#: Kept free of the frame for what the measurement misses (the timer's own jitter, Python's calls).
MARGIN_MS = 1.0
#: The rest of the update is the median of this many last ones: a single slow redraw (an undo
#: push, a panel drawn) does not starve the next solve.
RECENT_UPDATES = 5


class FrameBudget:
    """budget = clamp(FRAME_MS − MARGIN_MS − median of the rest of the last RECENT_UPDATES updates,
    least_ms, most_ms); most_ms until an update has been measured."""

    def __init__(self, most_ms, least_ms=0.5, frame_ms=FRAME_MS):
        if not 0 < least_ms <= most_ms:
            raise ValueError(
                f"least_ms and most_ms: expected 0 < least_ms <= most_ms, got {least_ms} and {most_ms}"
            )
        self.most_ms, self.least_ms, self.frame_ms = (
            float(most_ms),
            float(least_ms),
            float(frame_ms),
        )
        self._rest = []

    @property
    def ms(self):
        """Milliseconds the next solve may take."""
        if not self._rest:
            return self.most_ms
        left = self.frame_ms - MARGIN_MS - float(np.median(self._rest))
        return min(self.most_ms, max(self.least_ms, left))

    def measured(self, rest_ms):
        """What an update took besides its solve: ours (controllers, writing the positions) and
        Blender's (evaluation, drawing), in ms."""
        self._rest = (self._rest + [float(rest_ms)])[-RECENT_UPDATES:]
