"""Fleets: many bags converted in parallel (processes or Ray tasks), served as one Rerun dataset, summed up.

At the top of the house with runner and cli: it calls :func:`r2d2_viz.runner.run` once per bag.
"""
