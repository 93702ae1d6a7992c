"""Display messages logged per block: a run of one topic's images or points goes to Rerun in one ``send_columns``
per entity, with the components :mod:`r2d2_viz.viewer.displays` logs per message; a block's odometry is thinned
first, as RViz's Odometry display thins it."""
