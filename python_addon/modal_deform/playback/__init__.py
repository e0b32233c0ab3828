"""Playback on the timeline: the per-frame cache (frame_cache), playing it (timeline), showing a frame
(frame_display), its operators (operators, bake_animation) and the point-cache files it exports
(point_cache)."""
