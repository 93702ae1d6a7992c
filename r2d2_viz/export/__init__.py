"""Recordings out of the viewer as files other tools read (a LeRobot v3.0 dataset: parquet, JSON, video).

Imports ``sources``, ``msgs``, ``robot`` and below; no rerun."""
