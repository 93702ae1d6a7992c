"""``--compare``'s Rerun side: each run's chunks rewritten under ``/runs/<name>`` (times, frames, tints), the frame
the runs hang from, the summary's text view and the comparison's layout."""
