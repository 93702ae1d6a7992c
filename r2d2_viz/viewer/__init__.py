"""Everything that talks to Rerun: the static scene, per-sample transforms, plots, warnings, a bag's other
topics, sinks and the layout. The only stage that imports rerun; it may import every stage before it.
"""
