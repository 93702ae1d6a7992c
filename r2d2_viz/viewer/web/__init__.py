"""r2d2-viz's own web page: Rerun's web viewer (from rerun-notebook) with RViz's tools on a toolbar, served on
loopback behind a per-run token; the picks come back to Python as typed tool events."""
