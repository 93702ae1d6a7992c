"""The system behind a recording, as ROS tools see it: the TF tree with each edge's rate, largest gap and the
problems tf2 users know (two parents, loops, several roots, frames no transform reaches, stale frames, transforms
older than the messages that use them), from a bag or a live graph. Pure numpy; no rerun import."""
