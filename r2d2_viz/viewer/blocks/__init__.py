"""Display messages logged as columns: a run of a topic's images or points, and every other display's rows
(gathered per entity; shapes, numbers and log lines as plain numbers) go to Rerun in one ``send_columns`` per entity
and run, with the components :mod:`r2d2_viz.viewer.displays` logs per message; a block's odometry is thinned first,
as RViz's Odometry display thins it."""
