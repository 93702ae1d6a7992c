"""The system behind a recording drawn in Rerun: the TF tree as a graph view whose nodes carry each frame's rate and
age at the time cursor (``/tf_tree``). Analysis lives in :mod:`r2d2_viz.sources.system`; only this draws."""
