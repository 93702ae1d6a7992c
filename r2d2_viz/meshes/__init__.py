"""Shapes and mesh files → what the viewer draws: primitives in numpy, COLLADA → GLB, a GLB writer, a disk cache.
Imports from ``robot`` (the model's shapes) and below; no rerun.
"""
